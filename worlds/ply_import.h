#pragma once
// PLY (Stanford polygon file) import, ASCII and binary: vertex x, y, z and face vertex lists,
// nothing else. Our own reader rather than Assimp's, which (5.2) loops forever or aborts on some
// malformed files.

#include <filesystem>
#include <string>
#include <string_view>

#include "worlds/placement.h"

namespace enavi::worlds {

/// Parses PLY bytes (format ascii, binary_little_endian or binary_big_endian 1.0). Reads the
/// `vertex` element's x, y, z and the `face` element's vertex_indices (or vertex_index) lists;
/// polygons are fan-triangulated; other elements and properties are skipped. Errors are
/// WorldError `FILE:LINE: FIELD: REASON` (the line in the header, or of an ASCII body).
ImportedMesh ParsePly(std::string_view bytes, const std::string& file_name);

/// Reads (size checked against kMaxFileBytes) and parses a PLY file.
ImportedMesh LoadPlyFile(const std::filesystem::path& path);

}  // namespace enavi::worlds
