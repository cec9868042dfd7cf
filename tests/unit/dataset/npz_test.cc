// The .npy/.npz writer: NumPy's header layout and zip's CRC-32 and record structure.
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "server/dataset/npz.h"

namespace enavi::dataset {
namespace {

TEST(NpzTest, Crc32MatchesTheCheckValue) {
  // The standard check value of CRC-32/ISO-HDLC for "123456789".
  EXPECT_EQ(Crc32("123456789"), 0xCBF43926u);
  EXPECT_EQ(Crc32(""), 0u);
}

TEST(NpzTest, NpyHeaderIsNumpysVersion1Layout) {
  const double values[4] = {1, 2, 3, 4};
  const NpyArray a{"x", "<f8", {2, 2}, std::string(reinterpret_cast<const char*>(values), sizeof values)};
  const std::string bytes = NpyBytes(a);
  ASSERT_EQ(bytes.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
  std::uint16_t header_len = 0;
  std::memcpy(&header_len, bytes.data() + 8, 2);
  EXPECT_EQ((10 + header_len) % 64, 0);
  const std::string header = bytes.substr(10, header_len);
  EXPECT_EQ(header.rfind("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2), }", 0), 0u) << header;
  EXPECT_EQ(header.back(), '\n');
  EXPECT_EQ(bytes.size(), 10u + header_len + sizeof values);
  EXPECT_NE(NpyBytes({"v", "<i4", {3}, std::string(12, '\0')}).find("'shape': (3,)"), std::string::npos);
  EXPECT_THROW(NpyBytes({"bad", "<f8", {3}, std::string(8, '\0')}), std::logic_error);
}

TEST(NpzTest, ArchiveHasOneStoredEntryPerArrayAndACentralDirectory) {
  const auto path = std::filesystem::temp_directory_path() / ("npz_test_" + std::to_string(getpid()) + ".npz");
  WriteNpz(path, {{"a", "|b1", {3}, std::string("\1\0\1", 3)}, {"b", "<U2", {1}, std::string(8, '\0')}});
  std::ifstream in(path, std::ios::binary);
  const std::string zip((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::filesystem::remove(path);
  ASSERT_GT(zip.size(), 22u);
  EXPECT_EQ(zip.substr(0, 4), std::string("PK\3\4", 4));
  const std::string end = zip.substr(zip.size() - 22);
  EXPECT_EQ(end.substr(0, 4), std::string("PK\5\6", 4));
  std::uint16_t entries = 0;
  std::memcpy(&entries, end.data() + 10, 2);
  EXPECT_EQ(entries, 2);
  EXPECT_NE(zip.find("a.npy"), std::string::npos);
  EXPECT_NE(zip.find("b.npy"), std::string::npos);
}

}  // namespace
}  // namespace enavi::dataset
