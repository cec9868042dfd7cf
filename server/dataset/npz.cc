#include "server/dataset/npz.h"

#include "api/atomic_file.h"
#include "navstack/rl/json_read.h"

#include <array>
#include <limits>
#include <stdexcept>
#include <string>

namespace enavi::dataset {
namespace {

std::size_t ItemSize(const std::string& descr) {
  // '<f8', '|b1', '<U24': the digits after the kind are the size (U: characters of 4 bytes).
  if (descr.size() < 3) throw std::logic_error("npy: bad dtype '" + descr + "'");
  const std::size_t n = std::stoul(descr.substr(2));
  return descr[1] == 'U' ? 4 * n : n;
}

template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof v);
}

}  // namespace

std::uint32_t Crc32(const std::string& bytes) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const char ch : bytes) crc = table[(crc ^ static_cast<unsigned char>(ch)) & 0xFF] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFu;
}

std::string NpyBytes(const NpyArray& a) {
  std::size_t count = 1;
  for (const std::size_t d : a.shape) count *= d;
  if (count * ItemSize(a.descr) != a.data.size()) {
    throw std::logic_error("npy " + a.name + ": " + std::to_string(a.data.size()) +
                           " bytes do not match dtype " + a.descr + " and shape");
  }
  std::string shape = "(";
  for (std::size_t i = 0; i < a.shape.size(); ++i) shape += std::to_string(a.shape[i]) + (a.shape.size() == 1 ? "," : (i + 1 < a.shape.size() ? ", " : ""));
  shape += ")";
  std::string header = "{'descr': '" + a.descr + "', 'fortran_order': False, 'shape': " + shape + ", }";
  // Magic (6) + version (2) + header length (2) + header, padded with spaces and ended by '\n'
  // to a multiple of 64 bytes.
  const std::size_t unpadded = 10 + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header += '\n';
  std::string out("\x93NUMPY\x01\x00", 8);
  Put(&out, static_cast<std::uint16_t>(header.size()));
  out += header;
  out += a.data;
  return out;
}

void WriteNpz(const std::filesystem::path& path, const std::vector<NpyArray>& arrays) {
  // DOS date 1980-01-01 00:00 for every entry: the same dataset gives the same bytes.
  constexpr std::uint16_t kTime = 0, kDate = (0 << 9) | (1 << 5) | 1;
  std::string zip, central;
  for (const NpyArray& a : arrays) {
    const std::string name = a.name + ".npy";
    const std::string data = NpyBytes(a);
    const std::uint32_t crc = Crc32(data);
    if (zip.size() + data.size() > std::numeric_limits<std::uint32_t>::max()) {
      throw std::runtime_error(path.string() + ": shard above 4 GiB (use smaller shards)");
    }
    const auto offset = static_cast<std::uint32_t>(zip.size());
    const auto size = static_cast<std::uint32_t>(data.size());
    // Local file header.
    Put(&zip, std::uint32_t{0x04034b50});
    Put(&zip, std::uint16_t{20});  // version needed: 2.0
    Put(&zip, std::uint16_t{0});   // flags
    Put(&zip, std::uint16_t{0});   // method: stored
    Put(&zip, kTime);
    Put(&zip, kDate);
    Put(&zip, crc);
    Put(&zip, size);
    Put(&zip, size);
    Put(&zip, static_cast<std::uint16_t>(name.size()));
    Put(&zip, std::uint16_t{0});
    zip += name;
    zip += data;
    // Its central directory entry.
    Put(&central, std::uint32_t{0x02014b50});
    Put(&central, std::uint16_t{20});  // made by
    Put(&central, std::uint16_t{20});  // needed
    Put(&central, std::uint16_t{0});
    Put(&central, std::uint16_t{0});
    Put(&central, kTime);
    Put(&central, kDate);
    Put(&central, crc);
    Put(&central, size);
    Put(&central, size);
    Put(&central, static_cast<std::uint16_t>(name.size()));
    Put(&central, std::uint16_t{0});  // extra
    Put(&central, std::uint16_t{0});  // comment
    Put(&central, std::uint16_t{0});  // disk
    Put(&central, std::uint16_t{0});  // internal attributes
    Put(&central, std::uint32_t{0});  // external attributes
    Put(&central, offset);
    central += name;
  }
  const auto central_offset = static_cast<std::uint32_t>(zip.size());
  zip += central;
  Put(&zip, std::uint32_t{0x06054b50});
  Put(&zip, std::uint16_t{0});
  Put(&zip, std::uint16_t{0});
  Put(&zip, static_cast<std::uint16_t>(arrays.size()));
  Put(&zip, static_cast<std::uint16_t>(arrays.size()));
  Put(&zip, static_cast<std::uint32_t>(central.size()));
  Put(&zip, central_offset);
  Put(&zip, std::uint16_t{0});

  api::WriteFileAtomic(path, zip);
}

}  // namespace enavi::dataset
