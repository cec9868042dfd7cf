// OctoMap's octree as the occupancy map's cell store: pruned, so large free or occupied regions
// take one leaf, and any resolution in [0.02, 5] m (E-Navi's Resolution Adapter rebuilds it).

#include <algorithm>
#include <memory>

#include <octomap/OcTree.h>

#include "navstack/perception/cell_store.h"

namespace enavi::navstack::detail {
namespace {

octomap::OcTreeKey Unpack(std::uint64_t packed_key) {
  const Eigen::Vector3i k = UnpackKey(packed_key);
  return octomap::OcTreeKey(static_cast<octomap::key_type>(k.x()), static_cast<octomap::key_type>(k.y()),
                            static_cast<octomap::key_type>(k.z()));
}

class OctreeStore final : public CellStore {
 public:
  OctreeStore(const MapOptions& o, double resolution) : tree_(resolution) {
    tree_.setProbHit(o.prob_hit);
    tree_.setProbMiss(o.prob_miss);
    tree_.setClampingThresMin(o.clamp_min);
    tree_.setClampingThresMax(o.clamp_max);
    tree_.setOccupancyThres(o.occupancy_threshold);
  }

  void Update(std::uint64_t packed_key, bool occupied) override {
    tree_.updateNode(Unpack(packed_key), occupied);
  }
  void Set(std::uint64_t packed_key, float log_odds) override {
    tree_.setNodeValue(Unpack(packed_key), log_odds);
  }
  CellState State(std::uint64_t packed_key) const override {
    const octomap::OcTreeNode* node = tree_.search(Unpack(packed_key));
    if (node == nullptr) return CellState::kUnknown;
    return tree_.isNodeOccupied(node) ? CellState::kOccupied : CellState::kFree;
  }

  // Pruned leaves fill whole blocks.
  void ForEachKnownBlock(const KeyBox& kb, const BlockFn& fill) const override {
    const octomap::OcTreeKey kmin(kb.lo.x(), kb.lo.y(), kb.lo.z());
    const octomap::OcTreeKey kmax(kb.hi.x(), kb.hi.y(), kb.hi.z());
    const int depth = static_cast<int>(tree_.getTreeDepth());
    for (auto it = tree_.begin_leafs_bbx(kmin, kmax), end = tree_.end_leafs_bbx(); it != end; ++it) {
      const int size = 1 << (depth - static_cast<int>(it.getDepth()));
      const octomap::OcTreeKey base = it.getIndexKey();
      Eigen::Vector3i lo, hi;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::max<int>(base[a], kb.lo[a]);
        hi[a] = std::min<int>(base[a] + size - 1, kb.hi[a]);
      }
      if ((lo.array() > hi.array()).any()) continue;
      fill(lo, hi, tree_.isNodeOccupied(*it));
    }
  }

  void ForEachOccupiedLeaf(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                           const LeafFn& leaf) const override {
    const octomap::point3d l(lo.x(), lo.y(), lo.z());
    const octomap::point3d h(hi.x(), hi.y(), hi.z());
    for (auto it = tree_.begin_leafs_bbx(l, h), end = tree_.end_leafs_bbx(); it != end; ++it) {
      if (!tree_.isNodeOccupied(*it)) continue;
      const octomap::point3d c = it.getCoordinate();
      leaf(Eigen::Vector3d(c.x(), c.y(), c.z()), it.getSize());
    }
  }

  float HitLogOdds() const override { return tree_.getProbHitLog(); }
  std::size_t NumLeaves() const override { return tree_.getNumLeafNodes(); }
  void Clear() override { tree_.clear(); }

 private:
  octomap::OcTree tree_;
};

}  // namespace

std::unique_ptr<CellStore> MakeOctreeStore(const MapOptions& options, double resolution) {
  return std::make_unique<OctreeStore>(options, resolution);
}

}  // namespace enavi::navstack::detail
