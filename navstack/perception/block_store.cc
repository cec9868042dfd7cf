// Dense block grid: Ego-Planner's grid_map keeps the occupancy log-odds in dense arrays
// (plan_env/src/grid_map.cpp, occupancy_buffer_), so a voxel update is an index, not an octree
// descent. Its arrays span a configured map_size; ours allocate 8^3-cell blocks where rays reach,
// so no world size is needed. Log-odds, clamping and the occupancy test are OctoMap's, on the
// same float values, so cell states equal the octree's.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <unordered_map>
#include <vector>

#include <octomap/octomap_utils.h>

#include "navstack/perception/cell_store.h"

namespace enavi::navstack::detail {
namespace {

constexpr int kBlockBits = 3;
constexpr int kBlockEdge = 1 << kBlockBits;
constexpr int kBlockMask = kBlockEdge - 1;
constexpr int kBlockCells = kBlockEdge * kBlockEdge * kBlockEdge;

struct Block {
  Block() { log_odds.fill(std::numeric_limits<float>::quiet_NaN()); }  // NaN: unknown
  std::array<float, kBlockCells> log_odds;
};

std::uint64_t BlockId(int bx, int by, int bz) {
  return std::uint64_t(bx) | (std::uint64_t(by) << 16) | (std::uint64_t(bz) << 32);
}

int CellIndex(int x, int y, int z) {
  return (x & kBlockMask) | ((y & kBlockMask) << kBlockBits) | ((z & kBlockMask) << (2 * kBlockBits));
}

class BlockStore final : public CellStore {
 public:
  explicit BlockStore(const MapOptions& o)
      : resolution_(o.resolution),
        hit_(octomap::logodds(o.prob_hit)),
        miss_(octomap::logodds(o.prob_miss)),
        min_(octomap::logodds(o.clamp_min)),
        max_(octomap::logodds(o.clamp_max)),
        occupied_(octomap::logodds(o.occupancy_threshold)) {}

  void Update(std::uint64_t packed_key, bool occupied) override {
    float& v = Cell(packed_key);
    if (std::isnan(v)) {
      v = 0.0f;  // a new octree node starts at log-odds 0
      ++known_;
    }
    v += occupied ? hit_ : miss_;
    if (v < min_) {
      v = min_;
    } else if (v > max_) {
      v = max_;
    }
  }

  void Set(std::uint64_t packed_key, float log_odds) override {
    float& v = Cell(packed_key);
    if (std::isnan(v)) ++known_;
    v = std::min(std::max(log_odds, min_), max_);
  }

  CellState State(std::uint64_t packed_key) const override {
    const Eigen::Vector3i k = UnpackKey(packed_key);
    const Block* b = Find(k.x() >> kBlockBits, k.y() >> kBlockBits, k.z() >> kBlockBits);
    if (b == nullptr) return CellState::kUnknown;
    return StateOf(b->log_odds[CellIndex(k.x(), k.y(), k.z())]);
  }

  void ForEachKnownBlock(const KeyBox& box, const BlockFn& fill) const override {
    for (int bz = box.lo.z() >> kBlockBits; bz <= box.hi.z() >> kBlockBits; ++bz) {
      for (int by = box.lo.y() >> kBlockBits; by <= box.hi.y() >> kBlockBits; ++by) {
        for (int bx = box.lo.x() >> kBlockBits; bx <= box.hi.x() >> kBlockBits; ++bx) {
          const Block* b = Find(bx, by, bz);
          if (b == nullptr) continue;
          const Eigen::Vector3i base(bx << kBlockBits, by << kBlockBits, bz << kBlockBits);
          const Eigen::Vector3i lo = base.cwiseMax(box.lo);
          const Eigen::Vector3i hi = (base.array() + kBlockMask).matrix().cwiseMin(box.hi);
          for (int z = lo.z(); z <= hi.z(); ++z) {
            for (int y = lo.y(); y <= hi.y(); ++y) {
              // Runs of one state along x.
              int x0 = lo.x();
              CellState run = StateOf(b->log_odds[CellIndex(x0, y, z)]);
              for (int x = lo.x() + 1; x <= hi.x() + 1; ++x) {
                const CellState s =
                    x <= hi.x() ? StateOf(b->log_odds[CellIndex(x, y, z)]) : CellState::kUnknown;
                if (x <= hi.x() && s == run) continue;
                if (run != CellState::kUnknown) {
                  fill({x0, y, z}, {x - 1, y, z}, run == CellState::kOccupied);
                }
                x0 = x;
                run = s;
              }
            }
          }
        }
      }
    }
  }

  void ForEachOccupiedLeaf(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                           const LeafFn& leaf) const override {
    // The octree's bounding-box iterator takes the keys of both corners (coordToKey).
    const double inv = 1.0 / resolution_;
    KeyBox box;
    for (int a = 0; a < 3; ++a) {
      box.lo[a] = KeyOf(inv, lo[a]);
      box.hi[a] = KeyOf(inv, hi[a]);
    }
    ForEachKnownBlock(box, [&](const Eigen::Vector3i& l, const Eigen::Vector3i& h, bool occupied) {
      if (!occupied) return;
      for (int x = l.x(); x <= h.x(); ++x) {
        const Eigen::Vector3i k(x, l.y(), l.z());
        leaf(((k.array() - kKeyOffset).cast<double>() + 0.5) * resolution_, resolution_);
      }
    });
  }

  float HitLogOdds() const override { return hit_; }
  std::size_t NumLeaves() const override { return known_; }
  void Clear() override {
    blocks_.clear();
    index_.clear();
    known_ = 0;
    last_id_ = kNoBlock;
  }

 private:
  static constexpr std::uint64_t kNoBlock = ~std::uint64_t{0};

  CellState StateOf(float v) const {
    if (std::isnan(v)) return CellState::kUnknown;
    return v >= occupied_ ? CellState::kOccupied : CellState::kFree;
  }

  const Block* Find(int bx, int by, int bz) const {
    const auto it = index_.find(BlockId(bx, by, bz));
    return it == index_.end() ? nullptr : blocks_[it->second].get();
  }

  float& Cell(std::uint64_t packed_key) {
    const Eigen::Vector3i k = UnpackKey(packed_key);
    const std::uint64_t id = BlockId(k.x() >> kBlockBits, k.y() >> kBlockBits, k.z() >> kBlockBits);
    // Updates come in ray order, so most hit the block of the one before.
    if (id != last_id_) {
      auto [it, inserted] = index_.try_emplace(id, static_cast<std::uint32_t>(blocks_.size()));
      if (inserted) blocks_.push_back(std::make_unique<Block>());
      last_id_ = id;
      last_ = blocks_[it->second].get();
    }
    return last_->log_odds[CellIndex(k.x(), k.y(), k.z())];
  }

  double resolution_;
  float hit_, miss_, min_, max_, occupied_;
  std::vector<std::unique_ptr<Block>> blocks_;
  std::unordered_map<std::uint64_t, std::uint32_t> index_;
  std::size_t known_ = 0;
  std::uint64_t last_id_ = kNoBlock;
  Block* last_ = nullptr;
};

}  // namespace

std::unique_ptr<CellStore> MakeBlockStore(const MapOptions& options) {
  return std::make_unique<BlockStore>(options);
}

}  // namespace enavi::navstack::detail
