#pragma once
// NumPy .npy arrays and .npz archives, written without NumPy: an .npy file is a magic string, a
// small header dict (dtype, order, shape) and the raw little-endian data (NumPy's format spec,
// "numpy.lib.format", version 1.0); an .npz is a zip archive of .npy files (here with the zip
// "stored" method, no compression: PKWARE APPNOTE 6.3, sections 4.3 and 4.4).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace enavi::dataset {

/// One array: its NumPy dtype string ('<f8', '<i4', '|b1', '<U24', ...), shape, and raw bytes
/// in C order.
struct NpyArray {
  std::string name;  ///< the key in the .npz (file "<name>.npy")
  std::string descr;
  std::vector<std::size_t> shape;
  std::string data;
};

/// The .npy bytes of an array (header padded to a multiple of 64 bytes, as NumPy writes it).
/// @throws std::logic_error when data.size() does not match descr and shape.
std::string NpyBytes(const NpyArray& array);

/// Writes the arrays as one .npz (atomically: temporary file, then rename).
/// @throws std::runtime_error on I/O failure or an archive above 4 GiB (no zip64).
void WriteNpz(const std::filesystem::path& path, const std::vector<NpyArray>& arrays);

/// CRC-32 (ISO-HDLC, polynomial 0xEDB88320) as zip uses it.
std::uint32_t Crc32(const std::string& bytes);

}  // namespace enavi::dataset
