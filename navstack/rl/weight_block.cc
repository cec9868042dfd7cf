#include "navstack/rl/weight_block.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "api/base64.h"
#include "api/content_hash.h"

namespace enavi::navstack::rl::detail {
namespace {

const char* DtypeName(WeightPrecision p) { return p == WeightPrecision::kFloat32 ? "float32" : "float64"; }
std::size_t DtypeBytes(WeightPrecision p) { return p == WeightPrecision::kFloat32 ? 4 : 8; }

}  // namespace

// Little-endian bytes of each weight at `precision`, whatever the host's byte order.
nlohmann::json EncodeWeights(const std::vector<double>& values, WeightPrecision precision, const std::string& layout,
                             const WeightName& name_of) {
  std::string bytes;
  bytes.reserve(values.size() * DtypeBytes(precision));
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double v = values[i];
    if (!std::isfinite(v)) throw std::domain_error("policy: " + name_of(i) + " is not finite");
    std::uint64_t bits = 0;
    if (precision == WeightPrecision::kFloat32) {
      const float f = static_cast<float>(v);
      if (!std::isfinite(f)) throw std::domain_error("policy: " + name_of(i) + " is beyond float32's range");
      bits = std::bit_cast<std::uint32_t>(f);
    } else {
      bits = std::bit_cast<std::uint64_t>(v);
    }
    for (std::size_t k = 0; k < DtypeBytes(precision); ++k) bytes.push_back(static_cast<char>((bits >> (8 * k)) & 0xff));
  }
  return {{"dtype", DtypeName(precision)},          {"byte_order", "little"},
          {"encoding", "base64"},                   {"layout", layout},
          {"count", values.size()},                 {"sha256", api::Sha256Hex(bytes)},
          {"data", api::Base64Encode(bytes)}};
}

std::vector<double> DecodeWeights(const nlohmann::json& j, const JsonReader& r, const std::string& f,
                                  std::size_t count, const std::string& layout, const WeightName& name_of) {
  r.Object(j, f);
  const std::string dtype = r.String(r.Field(j, f, "dtype"), f + ".dtype");
  if (dtype != "float32" && dtype != "float64") {
    r.Fail(f + ".dtype", "expected \"float32\" or \"float64\", got \"" + dtype + "\"");
  }
  const WeightPrecision precision = dtype == "float32" ? WeightPrecision::kFloat32 : WeightPrecision::kFloat64;
  const auto expect = [&](const char* key, const std::string& value) {
    const std::string got = r.String(r.Field(j, f, key), f + "." + key);
    if (got != value) r.Fail(f + "." + key, "expected \"" + value + "\", got \"" + got + "\"");
  };
  expect("byte_order", "little");
  expect("encoding", "base64");
  expect("layout", layout);
  if (r.Integer(r.Field(j, f, "count"), f + ".count") != static_cast<std::int64_t>(count)) {
    r.Fail(f + ".count", "expected " + std::to_string(count) + " (the architecture's weights and biases)");
  }
  const std::string sha256 = r.String(r.Field(j, f, "sha256"), f + ".sha256");
  std::string bytes;
  try {
    bytes = api::Base64Decode(r.String(r.Field(j, f, "data"), f + ".data"));
  } catch (const std::invalid_argument& e) {
    r.Fail(f + ".data", e.what());
  }
  const std::size_t width = DtypeBytes(precision);
  const std::size_t expected = count * width;
  if (bytes.size() != expected) {
    r.Fail(f + ".data", std::string(bytes.size() < expected ? "truncated: " : "too long: ") +
                            std::to_string(bytes.size()) + " bytes, expected " + std::to_string(expected) + " (" +
                            std::to_string(count) + " " + dtype + " values)");
  }
  const std::string digest = api::Sha256Hex(bytes);
  if (digest != sha256) {
    r.Fail(f + ".sha256", "does not match the weights (their sha256 is " + digest + "): the file is damaged or was edited");
  }
  std::vector<double> values(count);
  for (std::size_t i = 0, at = 0; i < count; ++i, at += width) {
    std::uint64_t bits = 0;
    for (std::size_t k = 0; k < width; ++k) bits |= std::uint64_t{static_cast<unsigned char>(bytes[at + k])} << (8 * k);
    values[i] = precision == WeightPrecision::kFloat32 ? static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(bits)))
                                                       : std::bit_cast<double>(bits);
    if (!std::isfinite(values[i])) r.Fail(f + ".data", name_of(i) + " is not finite");
  }
  return values;
}

}  // namespace enavi::navstack::rl::detail
