#include "navstack/perception/occupancy_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "navstack/common/argument_check.h"
#include "navstack/perception/cell_store.h"

namespace enavi::navstack {
namespace {

constexpr double kMinResolution = 0.02;
constexpr double kMaxResolution = 5.0;
constexpr std::int64_t kMaxGridCells = std::int64_t{1} << 28;

using detail::KeyBox;
using detail::kKeyOffset;

std::unique_ptr<detail::CellStore> MakeStore(const MapOptions& o) {
  return o.storage == MapStorage::kBlocks ? detail::MakeBlockStore(o)
                                          : detail::MakeOctreeStore(o, o.resolution);
}

constexpr ArgumentCheck kCheck("MapOptions");

void RequireResolution(double res, const char* where) {
  if (!(res >= kMinResolution && res <= kMaxResolution)) {
    throw std::invalid_argument(std::string(where) + ": " + std::to_string(res) +
                                " is out of range [0.02, 5]");
  }
}

// Open-addressing set of packed keys that remembers insertion order, so the keys it hands out
// come in a deterministic order without sorting. Much cheaper than OctoMap's unordered_set.
class KeySet {
 public:
  explicit KeySet(std::size_t expected) {
    std::size_t cap = 1024;
    while (cap < 2 * expected) cap <<= 1;
    Resize(cap);
    order_.reserve(expected);
  }
  bool Insert(std::uint64_t key) {
    if (2 * (order_.size() + 1) > slots_.size()) Resize(2 * slots_.size());
    std::size_t i = Slot(key);
    while (slots_[i] != kEmpty) {
      if (slots_[i] == key) return false;
      i = (i + 1) & mask_;
    }
    slots_[i] = key;
    order_.push_back(key);
    return true;
  }
  bool Contains(std::uint64_t key) const {
    std::size_t i = Slot(key);
    while (slots_[i] != kEmpty) {
      if (slots_[i] == key) return true;
      i = (i + 1) & mask_;
    }
    return false;
  }
  const std::vector<std::uint64_t>& keys() const { return order_; }
  std::vector<std::uint64_t> TakeKeys() { return std::move(order_); }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // packed keys use 48 bits
  std::size_t Slot(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_) & mask_;
  }
  void Resize(std::size_t cap) {
    slots_.assign(cap, kEmpty);
    mask_ = cap - 1;
    shift_ = 64 - static_cast<int>(std::log2(static_cast<double>(cap)));
    for (std::uint64_t key : order_) {
      std::size_t i = Slot(key);
      while (slots_[i] != kEmpty) i = (i + 1) & mask_;
      slots_[i] = key;
    }
  }
  std::vector<std::uint64_t> slots_;
  std::vector<std::uint64_t> order_;
  std::size_t mask_ = 0;
  int shift_ = 0;
};

// Marks of the voxels around the sensor for one frame, in a dense array over the local update
// box: deduplicating ray voxels by index instead of by hash, as Ego-Planner's raycast does with
// its per-voxel flags (grid_map.cpp, raycastProcess). A generation stamp resets the marks between
// frames without clearing the array; one array per thread, reused.
class FrameMarks {
 public:
  static constexpr std::int64_t kMaxCells = std::int64_t{1} << 23;

  // The box of keys within `half_cells` of `centre`; false (and unusable) if it has more than
  // kMaxCells cells.
  bool Reset(const Eigen::Vector3i& centre, const Eigen::Vector3i& half_cells) {
    const Eigen::Vector3i dims = 2 * half_cells + Eigen::Vector3i::Ones();
    if (std::int64_t{dims.x()} * dims.y() * dims.z() > kMaxCells) return false;
    lo_ = centre - half_cells;
    dims_ = dims;
    Scratch& s = scratch();
    const std::size_t cells = static_cast<std::size_t>(dims.prod());
    if (s.stamps.size() < cells) s.stamps.assign(cells, 0);
    if (++s.generation == (std::uint32_t{1} << 29)) {
      std::fill(s.stamps.begin(), s.stamps.end(), 0);
      s.generation = 1;
    }
    stamps_ = s.stamps.data();
    tag_ = s.generation << 3;
    return true;
  }
  // Sets `bit` on the key's voxel; true if it was not set yet this frame.
  bool Mark(std::uint64_t key, std::uint32_t bit) {
    std::uint32_t& v = stamps_[Index(key)];
    if ((v & ~7u) != tag_) v = tag_;
    if (v & bit) return false;
    v |= bit;
    return true;
  }
  bool Marked(std::uint64_t key, std::uint32_t bit) const {
    const std::uint32_t v = stamps_[Index(key)];
    return (v & ~7u) == tag_ && (v & bit) != 0;
  }

 private:
  struct Scratch {
    std::vector<std::uint32_t> stamps;
    std::uint32_t generation = 0;
  };
  static Scratch& scratch() {
    thread_local Scratch s;
    return s;
  }
  std::size_t Index(std::uint64_t key) const {
    const Eigen::Vector3i d = detail::UnpackKey(key) - lo_;
    const int x = d.x(), y = d.y(), z = d.z();
    if (static_cast<unsigned>(x) >= static_cast<unsigned>(dims_.x()) ||
        static_cast<unsigned>(y) >= static_cast<unsigned>(dims_.y()) ||
        static_cast<unsigned>(z) >= static_cast<unsigned>(dims_.z())) {
      throw std::logic_error("OccupancyMap: a ray left the local update box");
    }
    return static_cast<std::size_t>(x) +
           static_cast<std::size_t>(dims_.x()) * (y + static_cast<std::size_t>(dims_.y()) * z);
  }
  Eigen::Vector3i lo_ = Eigen::Vector3i::Zero();
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  std::uint32_t* stamps_ = nullptr;
  std::uint32_t tag_ = 0;
};

// The frame's three key sets (cleared, hit, free ray ends), the first two remembering insertion
// order so the keys come out in ray order. FrameMarks when the local box is small enough (every
// method's default box), hash sets otherwise; both give the same keys in the same order.
class FrameKeys {
 public:
  enum Set { kFree = 0, kOccupied = 1, kFreeEnd = 2 };

  FrameKeys(const Eigen::Vector3i& centre, const Eigen::Vector3i& half_cells, std::size_t rays,
            std::size_t hits)
      : dense_(marks_.Reset(centre, half_cells)) {
    if (dense_) {
      order_[kFree].reserve(rays * 2);
      order_[kOccupied].reserve(hits);
    } else {
      sets_.emplace_back(rays * 2);
      sets_.emplace_back(hits);
      sets_.emplace_back(rays);
    }
  }
  // Adds `key` to `set`; true if it was not in it yet.
  bool Add(Set set, std::uint64_t key) {
    if (!dense_) return sets_[set].Insert(key);
    if (!marks_.Mark(key, Bit(set))) return false;
    if (set != kFreeEnd) order_[set].push_back(key);
    return true;
  }
  bool Has(Set set, std::uint64_t key) const {
    return dense_ ? marks_.Marked(key, Bit(set)) : sets_[set].Contains(key);
  }
  const std::vector<std::uint64_t>& Order(Set set) const {
    return dense_ ? order_[set] : sets_[set].keys();
  }
  std::vector<std::uint64_t> Take(Set set) {
    return dense_ ? std::move(order_[set]) : sets_[set].TakeKeys();
  }

 private:
  static std::uint32_t Bit(Set set) { return std::uint32_t{1} << set; }
  FrameMarks marks_;
  bool dense_;
  std::vector<std::uint64_t> order_[2];
  std::vector<KeySet> sets_;
};

// Voxel traversal (Amanatides & Woo) in OctoMap's key space at one resolution.
class RayCaster {
 public:
  explicit RayCaster(double resolution) : res_(resolution), inv_(1.0 / resolution) {}

  // Key of the voxel containing p, the same formula as OcTree::coordToKey; false if outside the
  // tree's 16-bit key range.
  bool KeyOf(const Eigen::Vector3d& p, Eigen::Vector3i* key) const {
    for (int a = 0; a < 3; ++a) {
      const double k = std::floor(inv_ * p[a]) + kKeyOffset;
      if (!(k >= 0.0 && k <= 65535.0)) return false;
      (*key)[a] = static_cast<int>(k);
    }
    return true;
  }
  Eigen::Vector3d CenterOf(const Eigen::Vector3i& key) const {
    return ((key.array() - kKeyOffset).cast<double>() + 0.5) * res_;
  }
  static std::uint64_t Pack(const Eigen::Vector3i& k) {
    return OccupancyMap::PackKey(static_cast<std::uint16_t>(k.x()), static_cast<std::uint16_t>(k.y()),
                                 static_cast<std::uint16_t>(k.z()));
  }

  // Visits the voxels from the one containing `from` up to, but excluding, the one containing
  // `to` (`to_key`). Always ends exactly in to_key's voxel: an axis stops stepping once it has
  // reached its target index, so rounding cannot overshoot. Stops after a voxel for which
  // `visit` returns false. Returns the voxels visited.
  template <class Visit>
  std::int64_t Cast(const Eigen::Vector3d& from, const Eigen::Vector3i& from_key,
                    const Eigen::Vector3d& to, const Eigen::Vector3i& to_key, Visit&& visit) const {
    int step[3];
    int remaining[3];
    double t_max[3];
    double t_delta[3];
    std::int64_t n = 0;
    for (int a = 0; a < 3; ++a) {
      const double s0 = inv_ * from[a];
      const double d = inv_ * to[a] - s0;  // segment length along a, in voxels
      const int dk = to_key[a] - from_key[a];
      remaining[a] = std::abs(dk);
      n += remaining[a];
      const double inf = std::numeric_limits<double>::infinity();
      if (dk > 0) {
        step[a] = 1;
        t_max[a] = d > 0.0 ? (from_key[a] - kKeyOffset + 1 - s0) / d : 0.0;
        t_delta[a] = d > 0.0 ? 1.0 / d : 0.0;
      } else if (dk < 0) {
        step[a] = -1;
        t_max[a] = d < 0.0 ? (from_key[a] - kKeyOffset - s0) / d : 0.0;
        t_delta[a] = d < 0.0 ? -1.0 / d : 0.0;
      } else {
        step[a] = 0;
        t_max[a] = inf;
        t_delta[a] = inf;
      }
    }
    Eigen::Vector3i k = from_key;
    for (std::int64_t i = 0; i < n; ++i) {
      if (!visit(Pack(k))) return i + 1;
      int a = t_max[0] <= t_max[1] ? 0 : 1;
      if (t_max[2] < t_max[a]) a = 2;
      k[a] += step[a];
      if (--remaining[a] == 0) {
        t_max[a] = std::numeric_limits<double>::infinity();
      } else {
        t_max[a] += t_delta[a];
      }
    }
    return n;
  }

 private:
  double res_;
  double inv_;
};

}  // namespace

void MapOptions::Validate() const {
  kCheck.Range(resolution >= kMinResolution && resolution <= kMaxResolution, "resolution", resolution,
          "[0.02, 5]");
  kCheck.Range(occupancy_threshold > 0.0 && occupancy_threshold < 1.0, "occupancy_threshold",
          occupancy_threshold, "(0, 1)");
  kCheck.Range(prob_hit > 0.5 && prob_hit < 1.0, "prob_hit", prob_hit, "(0.5, 1)");
  kCheck.Range(prob_miss > 0.0 && prob_miss < 0.5, "prob_miss", prob_miss, "(0, 0.5)");
  kCheck.Range(clamp_min > 0.0 && clamp_min < occupancy_threshold, "clamp_min", clamp_min,
          "(0, occupancy_threshold)");
  kCheck.Range(clamp_max > occupancy_threshold && clamp_max < 1.0, "clamp_max", clamp_max,
          "(occupancy_threshold, 1)");
  for (int a = 0; a < 3; ++a) {
    kCheck.Range(local_half_extent[a] > 0.0 && local_half_extent[a] <= 1000.0, "local_half_extent",
            local_half_extent[a], "(0, 1000]");
  }
  kCheck.Range(rebuild_frames >= 0 && rebuild_frames <= 1000, "rebuild_frames", rebuild_frames,
          "[0, 1000]");
}

OccupancyMap::OccupancyMap(const MapOptions& options) : options_(options) {
  options_.Validate();
  store_ = MakeStore(options_);
}

OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

MapUpdate OccupancyMap::ComputeUpdate(const DepthFrame& frame, const CameraIntrinsics& intrinsics,
                                      const PerceptionOptions& perception, WorkCounts* work) const {
  return ComputeUpdate(std::make_shared<const ScanPoints>(
                           BackProject(frame, intrinsics, perception, work)),
                       work);
}

MapUpdate OccupancyMap::ComputeUpdate(std::shared_ptr<const ScanPoints> scan,
                                      WorkCounts* work) const {
  if (scan == nullptr) throw std::logic_error("OccupancyMap::ComputeUpdate: null scan");
  MapUpdate update;
  update.resolution = options_.resolution;
  const RayCaster caster(options_.resolution);
  const Eigen::Vector3d o = scan->origin_W;
  Eigen::Vector3i o_key;
  if (!caster.KeyOf(o, &o_key)) {
    update.scan = std::move(scan);
    return update;  // sensor outside the map's key range: nothing to insert
  }

  const std::size_t rays = scan->hits_W.size() + scan->far_W.size() +
                           (options_.clear_no_return ? scan->no_return_W.size() : 0);
  const double inv = 1.0 / options_.resolution;
  const Eigen::Vector3i half_cells =
      (options_.local_half_extent * inv).array().ceil().cast<int>() + 2;
  FrameKeys keys(o_key, half_cells, rays, scan->hits_W.size());
  const bool stop = options_.stop_at_traversed;
  auto mark_free = [&keys](std::uint64_t key) {
    keys.Add(FrameKeys::kFree, key);
    return true;
  };
  // stop_at_traversed: from the end voxel back to the sensor, until a voxel already cleared.
  if (stop) keys.Add(FrameKeys::kFree, RayCaster::Pack(o_key));
  auto cast_back = [&](const Eigen::Vector3d& end, const Eigen::Vector3i& end_key, bool end_is_free) {
    const std::uint64_t end_packed = RayCaster::Pack(end_key);
    update.ray_steps += caster.Cast(end, end_key, o, o_key, [&](std::uint64_t key) {
      return key == end_packed && !end_is_free ? true : keys.Add(FrameKeys::kFree, key);
    });
  };

  // Fraction of the segment o -> p inside the local update box centred on the sensor.
  const Eigen::Vector3d& h = options_.local_half_extent;
  auto inside_fraction = [&](const Eigen::Vector3d& d) {
    double t = 1.0;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(d[a]) > h[a]) t = std::min(t, h[a] / std::abs(d[a]));
    }
    return t;
  };

  // Rays that only clear space: cut returns, far returns, no-returns.
  auto cast_free = [&](const Eigen::Vector3d& end) {
    Eigen::Vector3i key;
    if (!caster.KeyOf(end, &key)) return;
    if (stop) {
      if (keys.Add(FrameKeys::kFreeEnd, RayCaster::Pack(key))) cast_back(end, key, true);
      return;
    }
    Eigen::Vector3d target = end;
    if (options_.discretize_endpoints) {
      if (!keys.Add(FrameKeys::kFreeEnd, RayCaster::Pack(key))) return;
      target = caster.CenterOf(key);
    }
    update.ray_steps += caster.Cast(o, o_key, target, key, mark_free);
  };

  for (const Eigen::Vector3f& p_f : scan->hits_W) {
    const Eigen::Vector3d p = p_f.cast<double>();
    const Eigen::Vector3d d = p - o;
    const double t = inside_fraction(d);
    if (t < 1.0) {
      cast_free(o + t * d);
      continue;
    }
    Eigen::Vector3i key;
    if (!caster.KeyOf(p, &key)) continue;
    const bool new_end = keys.Add(FrameKeys::kOccupied, RayCaster::Pack(key));
    if (stop) {
      if (new_end) cast_back(p, key, false);
    } else if (options_.discretize_endpoints) {
      if (!new_end) continue;
      update.ray_steps += caster.Cast(o, o_key, caster.CenterOf(key), key, mark_free);
    } else {
      update.ray_steps += caster.Cast(o, o_key, p, key, mark_free);
    }
  }
  auto cast_all_free = [&](const std::vector<Eigen::Vector3f>& points) {
    for (const Eigen::Vector3f& p_f : points) {
      const Eigen::Vector3d d = p_f.cast<double>() - o;
      cast_free(o + inside_fraction(d) * d);
    }
  };
  cast_all_free(scan->far_W);
  if (options_.clear_no_return) cast_all_free(scan->no_return_W);

  // Occupied wins over free (OctoMap's computeUpdate rule).
  update.free_keys.reserve(keys.Order(FrameKeys::kFree).size());
  for (std::uint64_t key : keys.Order(FrameKeys::kFree)) {
    if (!keys.Has(FrameKeys::kOccupied, key)) update.free_keys.push_back(key);
  }
  update.occupied_keys = keys.Take(FrameKeys::kOccupied);
  update.scan = std::move(scan);
  if (work != nullptr) {
    // A replayed scan (resolution switch) casts its rays again without back-projecting them.
    work->Add(WorkUnit::kRay, static_cast<std::int64_t>(rays));
    work->Add(WorkUnit::kRayStep, update.ray_steps);
  }
  return update;
}

ApplyResult OccupancyMap::Apply(const MapUpdate& update, WorkCounts* work) {
  ApplyResult result;
  const MapUpdate* use = &update;
  MapUpdate recomputed;
  if (update.resolution != options_.resolution) {
    if (update.scan == nullptr) {
      throw std::logic_error(
          "OccupancyMap::Apply: update at another resolution carries no points to recompute from");
    }
    recomputed = ComputeUpdate(update.scan, work);
    use = &recomputed;
    result.recomputed = true;
  }
  for (std::uint64_t key : use->free_keys) store_->Update(key, false);
  for (std::uint64_t key : use->occupied_keys) store_->Update(key, true);
  result.voxel_updates =
      static_cast<std::int64_t>(use->free_keys.size() + use->occupied_keys.size());
  if (work != nullptr) work->Add(WorkUnit::kVoxelUpdate, result.voxel_updates);

  if (use->scan != nullptr && options_.rebuild_frames > 0) {
    history_.push_back(use->scan);
    while (static_cast<int>(history_.size()) > options_.rebuild_frames) history_.pop_front();
  }
  return result;
}

void OccupancyMap::Insert(const DepthFrame& frame, const CameraIntrinsics& intrinsics,
                          const PerceptionOptions& perception, WorkCounts* work) {
  Apply(ComputeUpdate(frame, intrinsics, perception, work), work);
}

void OccupancyMap::SetResolution(double resolution, WorkCounts* work) {
  RequireResolution(resolution, "OccupancyMap::SetResolution resolution");
  if (resolution == options_.resolution) return;
  *this = std::move(*Rebuilt(resolution, work));
}

std::shared_ptr<OccupancyMap> OccupancyMap::Rebuilt(double resolution, WorkCounts* work, double carry_radius) const {
  RequireResolution(resolution, "OccupancyMap::Rebuilt resolution");
  MapOptions options = options_;
  options.resolution = resolution;
  auto map = std::make_shared<OccupancyMap>(options);
  // Obstacles seen before the kept frames (e.g. a door jamb now beside the camera) must survive
  // the switch, or the planner would route through them. Carry the occupied leaves within the
  // local update box of the newest frame over as occupied cells covering each leaf (conservative
  // when refining); the replayed frames below then clear what they see free.
  if (!history_.empty()) {
    const Eigen::Vector3d centre = history_.back()->origin_W;
    const Eigen::Vector3d half = options_.local_half_extent;
    const double inv = 1.0 / resolution;
    auto key = [inv](double x) { return detail::KeyOf(inv, x); };
    const float hit_log_odds = map->store_->HitLogOdds();
    std::int64_t carried = 0;
    store_->ForEachOccupiedLeaf(centre - half, centre + half, [&](const Eigen::Vector3d& c, double edge) {
      if ((c - centre).norm() > carry_radius) return;
      const double h = 0.5 * edge - 1e-6;
      // int counters: a key of 65535 must not wrap the loop.
      for (int x = key(c.x() - h); x <= key(c.x() + h); ++x) {
        for (int y = key(c.y() - h); y <= key(c.y() + h); ++y) {
          for (int z = key(c.z() - h); z <= key(c.z() + h); ++z) {
            // One hit's worth, however many old leaves share the cell, so frames clear it as fast
            // as a freshly seen one.
            map->store_->Set(RayCaster::Pack({x, y, z}), hit_log_odds);
            ++carried;
          }
        }
      }
    });
    if (work != nullptr) work->Add(WorkUnit::kRebuildVoxel, carried);
  }
  // Replay the kept frames, oldest first, exactly as they were inserted. Their updates go into a
  // fresh tree, where most allocate nodes: measured at about 4x an update of an existing leaf, so
  // they are counted as rebuild voxels, not voxel updates.
  WorkCounts replay;
  for (const auto& scan : history_) map->Apply(map->ComputeUpdate(scan, &replay), &replay);
  if (work != nullptr) {
    replay.Add(WorkUnit::kRebuildVoxel, replay.Get(WorkUnit::kVoxelUpdate));
    replay.Add(WorkUnit::kVoxelUpdate, -replay.Get(WorkUnit::kVoxelUpdate));
    *work += replay;
  }
  return map;
}

namespace {

// Key range [lo, hi] of the cells overlapping `box`.
KeyBox KeyBoxOf(const Eigen::AlignedBox3d& box, double resolution, const char* where) {
  if (box.isEmpty() || !box.min().allFinite() || !box.max().allFinite()) {
    throw std::invalid_argument(std::string(where) + ": box is empty or not finite");
  }
  const double inv = 1.0 / resolution;
  KeyBox kb;
  for (int a = 0; a < 3; ++a) {
    const double lo = std::floor(inv * box.min()[a]);
    // A max exactly on a cell face does not reach into the next cell.
    double hi = std::ceil(inv * box.max()[a] - 1e-9) - 1.0;
    hi = std::max(hi, lo);
    kb.lo[a] = static_cast<int>(std::clamp(lo + kKeyOffset, 0.0, 65535.0));
    kb.hi[a] = static_cast<int>(std::clamp(hi + kKeyOffset, 0.0, 65535.0));
  }
  if (kb.Cells() > kMaxGridCells) {
    throw std::invalid_argument(std::string(where) + ": box of " + std::to_string(kb.Cells()) +
                                " cells exceeds the limit of 2^28 cells");
  }
  return kb;
}

}  // namespace

VoxelGrid OccupancyMap::ExtractGrid(const Eigen::AlignedBox3d& box, WorkCounts* work) const {
  const double res = options_.resolution;
  const KeyBox kb = KeyBoxOf(box, res, "OccupancyMap::ExtractGrid");
  const Eigen::Vector3d origin = (kb.lo.array() - kKeyOffset).cast<double>() * res;
  VoxelGrid grid(origin, res, kb.hi - kb.lo + Eigen::Vector3i::Ones(), CellState::kUnknown);
  const std::size_t nx = grid.dims.x();
  const std::size_t nxy = nx * grid.dims.y();
  store_->ForEachKnownBlock(kb, [&](const Eigen::Vector3i& lo, const Eigen::Vector3i& hi, bool occ) {
    const CellState state = occ ? CellState::kOccupied : CellState::kFree;
    const Eigen::Vector3i c0 = lo - kb.lo;
    const Eigen::Vector3i c1 = hi - kb.lo;
    for (int z = c0.z(); z <= c1.z(); ++z) {
      for (int y = c0.y(); y <= c1.y(); ++y) {
        CellState* row = grid.cells.data() + z * nxy + y * nx;
        std::fill(row + c0.x(), row + c1.x() + 1, state);
      }
    }
  });
  if (work != nullptr) work->Add(WorkUnit::kGridCell, kb.Cells());
  return grid;
}

OccupancyStats OccupancyMap::Stats(const Eigen::AlignedBox3d& box, WorkCounts* work) const {
  const KeyBox kb = KeyBoxOf(box, options_.resolution, "OccupancyMap::Stats");
  OccupancyStats stats;
  stats.total = kb.Cells();
  store_->ForEachKnownBlock(kb, [&](const Eigen::Vector3i& lo, const Eigen::Vector3i& hi, bool occ) {
    const std::int64_t n =
        std::int64_t{hi.x() - lo.x() + 1} * (hi.y() - lo.y() + 1) * (hi.z() - lo.z() + 1);
    (occ ? stats.occupied : stats.free) += n;
  });
  stats.unknown = stats.total - stats.occupied - stats.free;
  if (work != nullptr) work->Add(WorkUnit::kGridCell, stats.total);
  return stats;
}

CellState OccupancyMap::Query(const Eigen::Vector3d& p_W) const {
  Eigen::Vector3i k;
  if (!RayCaster(options_.resolution).KeyOf(p_W, &k)) return CellState::kUnknown;
  return store_->State(RayCaster::Pack(k));
}

void OccupancyMap::Clear() {
  store_->Clear();
  history_.clear();
}

std::size_t OccupancyMap::num_leaves() const { return store_->NumLeaves(); }

}  // namespace enavi::navstack
