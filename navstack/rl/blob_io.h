#pragma once
// The little-endian binary blobs of rollouts (rollout.h, nav_rollout.h): appending values, and a
// reader that names the field and the source on truncated or non-finite content.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>

namespace enavi::navstack::rl::detail {

// Host byte order: every platform the farm runs on (x86-64, aarch64) is little-endian.
template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof v);
}

class BlobReader {
 public:
  BlobReader(std::string_view bytes, const std::string& source) : bytes_(bytes), source_(source) {}
  template <typename T>
  T Get(const char* field) {
    T v;
    Need(sizeof v, field);
    std::memcpy(&v, bytes_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  double Finite(const char* field) {
    const double v = Get<double>(field);
    if (!std::isfinite(v)) Fail(field, "not a finite number");
    return v;
  }
  std::string_view Bytes(std::size_t n, const char* field) {
    Need(n, field);
    const std::string_view v = bytes_.substr(at_, n);
    at_ += n;
    return v;
  }
  std::size_t left() const { return bytes_.size() - at_; }
  [[noreturn]] void Fail(const std::string& field, const std::string& why) const {
    throw std::invalid_argument(source_ + ": rollout " + field + ": " + why);
  }

 private:
  void Need(std::size_t n, const char* field) const {
    if (n > bytes_.size() - at_) Fail(field, "truncated");
  }
  std::string_view bytes_;
  const std::string& source_;
  std::size_t at_ = 0;
};

// A rollout's id and info map, as both binary forms carry them: u32 + id bytes, u32 count, then
// (u32 + key bytes, f64) each.
inline void PutIdAndInfo(std::string* out, const std::string& id, const std::map<std::string, double>& info) {
  Put(out, static_cast<std::uint32_t>(id.size()));
  *out += id;
  Put(out, static_cast<std::uint32_t>(info.size()));
  for (const auto& [k, v] : info) {
    Put(out, static_cast<std::uint32_t>(k.size()));
    *out += k;
    Put(out, v);
  }
}

inline void ReadIdAndInfo(BlobReader* r, std::string* id, std::map<std::string, double>* info) {
  const auto id_len = r->Get<std::uint32_t>("id");
  *id = std::string(r->Bytes(id_len, "id"));
  const auto count = r->Get<std::uint32_t>("info");
  for (std::uint32_t i = 0; i < count; ++i) {
    const auto key_len = r->Get<std::uint32_t>("info");
    const std::string key(r->Bytes(key_len, "info"));
    (*info)[key] = r->Finite("info");
  }
}

}  // namespace enavi::navstack::rl::detail
