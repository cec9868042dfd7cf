#include "server/store/series_codec.h"

#include <cstring>
#include <stdexcept>

namespace enavi::server {
namespace {

// Series blob: "ENS1", then per column (t, position, velocity, eci, f_per, f_col, f_dif, res,
// utilisation, then wind_speed and odometry_error) a u32 element count and the doubles (vectors
// flattened xyz). The last two came later: a blob that ends before them has them empty, so the
// series stored before them still read. Host byte order: every platform the farm runs on
// (x86-64, aarch64) is little-endian.
constexpr char kSeriesMagic[4] = {'E', 'N', 'S', '1'};

void PutColumn(std::vector<std::uint8_t>* out, const double* data, std::uint32_t count) {
  const std::size_t at = out->size();
  out->resize(at + sizeof(count) + count * sizeof(double));
  std::memcpy(out->data() + at, &count, sizeof(count));
  if (count > 0) std::memcpy(out->data() + at + sizeof(count), data, count * sizeof(double));
}

}  // namespace

std::vector<std::uint8_t> PackSeries(const api::TimeSeries& s) {
  std::vector<std::uint8_t> out(kSeriesMagic, kSeriesMagic + 4);
  auto put = [&](const std::vector<double>& v) {
    PutColumn(&out, v.data(), static_cast<std::uint32_t>(v.size()));
  };
  auto put3 = [&](const std::vector<api::Vec3>& v) {
    PutColumn(&out, v.empty() ? nullptr : v.front().data(), static_cast<std::uint32_t>(3 * v.size()));
  };
  put(s.t);
  put3(s.position);
  put3(s.velocity);
  put(s.eci);
  put(s.f_per);
  put(s.f_col);
  put(s.f_dif);
  put(s.res);
  put(s.utilisation);
  put(s.wind_speed);
  put(s.odometry_error);
  return out;
}

api::TimeSeries UnpackSeries(const std::vector<std::uint8_t>& blob) {
  if (blob.size() < 4 || std::memcmp(blob.data(), kSeriesMagic, 4) != 0) {
    throw std::invalid_argument("series blob: bad magic");
  }
  std::size_t at = 4;
  auto get = [&](std::vector<double>* v) {
    std::uint32_t count = 0;
    if (at + sizeof(count) > blob.size()) throw std::invalid_argument("series blob: truncated");
    std::memcpy(&count, blob.data() + at, sizeof(count));
    at += sizeof(count);
    if (at + std::size_t{count} * sizeof(double) > blob.size()) {
      throw std::invalid_argument("series blob: truncated");
    }
    v->resize(count);
    if (count > 0) std::memcpy(v->data(), blob.data() + at, count * sizeof(double));
    at += count * sizeof(double);
  };
  auto get3 = [&](std::vector<api::Vec3>* v) {
    std::vector<double> flat;
    get(&flat);
    if (flat.size() % 3 != 0) throw std::invalid_argument("series blob: vector column length");
    v->resize(flat.size() / 3);
    for (std::size_t i = 0; i < v->size(); ++i) (*v)[i] = {flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]};
  };
  api::TimeSeries s;
  get(&s.t);
  get3(&s.position);
  get3(&s.velocity);
  get(&s.eci);
  get(&s.f_per);
  get(&s.f_col);
  get(&s.f_dif);
  get(&s.res);
  get(&s.utilisation);
  if (at < blob.size()) get(&s.wind_speed);
  if (at < blob.size()) get(&s.odometry_error);
  if (at != blob.size()) throw std::invalid_argument("series blob: trailing bytes");
  return s;
}

}  // namespace enavi::server
