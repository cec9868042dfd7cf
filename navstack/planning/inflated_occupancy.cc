#include "navstack/planning/inflated_occupancy.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace enavi::navstack {
namespace {

// row |= row shifted by -s .. +s bits (x dilation of one x-row of `words` words).
void DilateRow(const std::uint64_t* in, int words, int k, std::uint64_t* out) {
  for (int w = 0; w < words; ++w) out[w] = in[w];
  for (int s = 1; s <= k; ++s) {
    for (int w = 0; w < words; ++w) {
      // Towards higher x: bit b of the result holds bit b - s of the input.
      std::uint64_t up = in[w] << s;
      if (w > 0) up |= in[w - 1] >> (64 - s);
      std::uint64_t down = in[w] >> s;
      if (w + 1 < words) down |= in[w + 1] << (64 - s);
      out[w] |= up | down;
    }
  }
}

// Bit i set iff byte i of v (8 grid cells, little end first) is kOccupied: exact zero-byte test
// of v ^ kOccupied.., then the eight high bits gathered into one byte by a multiply.
static_assert(std::endian::native == std::endian::little, "OccupiedBits8 reads cells little end first");
std::uint64_t OccupiedBits8(std::uint64_t v) {
  constexpr std::uint64_t kOnes = 0x0101010101010101ULL, kLow7 = 0x7F7F7F7F7F7F7F7FULL;
  const std::uint64_t x = v ^ (kOnes * static_cast<std::uint8_t>(CellState::kOccupied));
  const std::uint64_t zero_high = ~(((x & kLow7) + kLow7) | x | kLow7);
  return ((zero_high >> 7) * 0x0102040810204080ULL) >> 56;
}

}  // namespace

OccupancyBits::OccupancyBits(const VoxelGrid& grid, WorkCounts* work)
    : grid_(grid), words_((std::max(grid.dims.x(), 0) + 63) / 64) {
  if (!(grid.resolution > 0.0) || (grid.dims.array() <= 0).any() ||
      grid.cells.size() != static_cast<std::size_t>(grid.dims.cast<long long>().prod())) {
    throw std::invalid_argument("OccupancyBits: the grid is malformed (dims, resolution or cells)");
  }
  bits_.assign(static_cast<std::size_t>(grid.dims.y()) * grid.dims.z() * words_, 0);
  // Eight cells at a time: the bytes equal to kOccupied, as one bit each.
  const CellState* cell = grid.cells.data();
  const int nx = grid.dims.x();
  for (int z = 0; z < grid.dims.z(); ++z) {
    for (int y = 0; y < grid.dims.y(); ++y, cell += nx) {
      std::uint64_t* row = &bits_[RowIndex(y, z)];
      int x = 0;
      for (; x + 8 <= nx; x += 8) {
        std::uint64_t v;
        std::memcpy(&v, cell + x, 8);
        row[x >> 6] |= OccupiedBits8(v) << (x & 63);
      }
      for (; x < nx; ++x) {
        if (cell[x] == CellState::kOccupied) row[x >> 6] |= std::uint64_t{1} << (x & 63);
      }
    }
  }
  if (work != nullptr) work->Add(WorkUnit::kInflateCell, static_cast<std::int64_t>(grid.cells.size()));
}

InflatedOccupancy::InflatedOccupancy(const OccupancyBits& base, double inflation, WorkCounts* work)
    : grid_(base.grid()), words_(base.words_per_row()), work_(work) {
  if (!(inflation >= 0.0) || !std::isfinite(inflation)) {
    std::ostringstream msg;
    msg << "InflatedOccupancy: inflation = " << inflation << " must be finite and >= 0";
    throw std::invalid_argument(msg.str());
  }
  // Ego-Planner, grid_map.cpp: inf_step = ceil(obstacles_inflation / resolution).
  cells_ = static_cast<int>(std::ceil(inflation / grid_.resolution - 1e-9));
  const int ny = grid_.dims.y(), nz = grid_.dims.z();
  const std::size_t row_words = static_cast<std::size_t>(words_);
  // Separable cube dilation: x within each row, then y across rows, then z across planes.
  std::vector<std::uint64_t> x_pass(static_cast<std::size_t>(ny) * nz * row_words);
  for (int z = 0; z < nz; ++z) {
    for (int y = 0; y < ny; ++y) {
      DilateRow(base.Row(y, z), words_, cells_, &x_pass[base.RowIndex(y, z)]);
    }
  }
  std::vector<std::uint64_t> y_pass(x_pass.size(), 0);
  for (int z = 0; z < nz; ++z) {
    for (int y = 0; y < ny; ++y) {
      std::uint64_t* out = &y_pass[base.RowIndex(y, z)];
      for (int yy = std::max(0, y - cells_); yy <= std::min(ny - 1, y + cells_); ++yy) {
        const std::uint64_t* in = &x_pass[base.RowIndex(yy, z)];
        for (std::size_t w = 0; w < row_words; ++w) out[w] |= in[w];
      }
    }
  }
  bits_.assign(x_pass.size(), 0);
  for (int z = 0; z < nz; ++z) {
    for (int zz = std::max(0, z - cells_); zz <= std::min(nz - 1, z + cells_); ++zz) {
      for (int y = 0; y < ny; ++y) {
        std::uint64_t* out = &bits_[base.RowIndex(y, z)];
        const std::uint64_t* in = &y_pass[base.RowIndex(y, zz)];
        for (std::size_t w = 0; w < row_words; ++w) out[w] |= in[w];
      }
    }
  }
  if (work != nullptr) work->Add(WorkUnit::kInflateCell, static_cast<std::int64_t>(grid_.cells.size()));
}

bool InflatedOccupancy::CellOccupied(const Eigen::Vector3i& c) const {
  if (work_ != nullptr) work_->Add(WorkUnit::kStateCheck, 1);
  if (!grid_.InBounds(c)) return false;
  const std::size_t row = (static_cast<std::size_t>(c.z()) * grid_.dims.y() + c.y()) * words_;
  return (bits_[row + (c.x() >> 6)] >> (c.x() & 63)) & 1u;
}

double InflatedOccupancy::Clearance(const Eigen::Vector3d& p_W, double needed) const {
  if (!(needed > 0.0)) return std::max(needed, 0.0);
  if (needed <= guaranteed_clearance() && !Occupied(p_W)) return needed;
  const double res = grid_.resolution;
  const Eigen::Vector3i lo = grid_.CellOf(p_W - Eigen::Vector3d::Constant(needed)).cwiseMax(0);
  const Eigen::Vector3i hi = grid_.CellOf(p_W + Eigen::Vector3d::Constant(needed))
                                 .cwiseMin(grid_.dims - Eigen::Vector3i::Ones());
  double best2 = needed * needed;
  std::int64_t reads = 0;
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      const std::size_t row = grid_.Index({0, y, z});
      for (int x = lo.x(); x <= hi.x(); ++x) {
        ++reads;
        if (grid_.cells[row + x] != CellState::kOccupied) continue;
        const Eigen::Vector3d cmin = grid_.origin + Eigen::Vector3d(x, y, z) * res;
        const Eigen::Vector3d nearest = p_W.cwiseMax(cmin).cwiseMin(cmin + Eigen::Vector3d::Constant(res));
        best2 = std::min(best2, (nearest - p_W).squaredNorm());
      }
    }
  }
  if (work_ != nullptr) work_->Add(WorkUnit::kCellProbe, reads);
  return std::sqrt(best2);
}

bool InflatedOccupancy::IsClear(const Eigen::Vector3d& p_W, double needed) const {
  if (!Occupied(p_W)) {
    if (needed <= guaranteed_clearance()) return true;
  } else if (needed > (cells_ - 1) * grid_.resolution) {
    return false;
  }
  return Clearance(p_W, needed) >= needed;
}

}  // namespace enavi::navstack
