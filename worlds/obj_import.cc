#include "worlds/obj_import.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <system_error>
#include <utility>
#include <vector>

#include "worlds/number_text.h"

namespace enavi::worlds {
namespace {

std::vector<std::string_view> SplitWhitespace(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

std::string Quoted(std::string_view s) {
  constexpr std::size_t kMax = 40;
  std::string out = "'";
  for (char ch : s.substr(0, kMax)) out += (ch >= 32 && ch < 127) ? ch : '?';
  if (s.size() > kMax) out += "...";
  return out + "'";
}

[[noreturn]] void Fail(const std::string& file, int line, const std::string& field, const std::string& reason) {
  throw WorldError(file, line, field, reason);
}

// A positive index that refers to a vertex not yet defined; checked once the file is read.
struct ForwardRef {
  int line;
  std::int64_t index;
};

}  // namespace

ImportedMesh ParseObj(std::string_view text, const std::string& file_name) {
  ImportedMesh mesh;
  std::vector<ForwardRef> forward_refs;
  std::vector<int> corners;
  int line_no = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    const auto tokens = SplitWhitespace(line);
    if (tokens.empty()) continue;
    const std::string_view kw = tokens[0];
    auto fail = [&](const std::string& field, const std::string& reason) { Fail(file_name, line_no, field, reason); };

    if (kw == "v") {
      // x y z, optionally w or an r g b colour.
      if (tokens.size() != 4 && tokens.size() != 5 && tokens.size() != 7) {
        fail("v", "expected 3 coordinates (got " + std::to_string(tokens.size() - 1) + " values)");
      }
      double xyz[3] = {0.0, 0.0, 0.0};
      for (int k = 0; k < 3; ++k) {
        if (!ParseFiniteDouble(tokens[k + 1], &xyz[k])) fail("v", "not a finite number: " + Quoted(tokens[k + 1]));
        if (std::abs(xyz[k]) > kMaxFileCoordinate) {
          fail("v", "coordinate " + std::string(tokens[k + 1]) + " is out of range (|x| <= 1e12 in the file's units)");
        }
      }
      for (std::size_t k = 4; k < tokens.size(); ++k) {
        double ignored;
        if (!ParseFiniteDouble(tokens[k], &ignored)) fail("v", "not a finite number: " + Quoted(tokens[k]));
      }
      if (mesh.vertices.size() >= 3 * kMaxTriangles) {
        fail("v", "too many vertices (limit " + std::to_string(3 * kMaxTriangles) + ")");
      }
      mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
    } else if (kw == "f") {
      if (tokens.size() < 4) {
        fail("f", "a face needs at least 3 vertices (got " + std::to_string(tokens.size() - 1) + ")");
      }
      corners.clear();
      for (std::size_t k = 1; k < tokens.size(); ++k) {
        // v, v/vt, v//vn or v/vt/vn: the vertex index is the part before the first '/'.
        const std::string_view corner = tokens[k];
        std::vector<std::string_view> parts;
        std::size_t start = 0;
        while (true) {
          const auto slash = corner.find('/', start);
          parts.push_back(corner.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start));
          if (slash == std::string_view::npos) break;
          start = slash + 1;
        }
        std::int64_t idx = 0;
        bool ok = parts.size() <= 3 && ParseInt64(parts[0], &idx);
        for (std::size_t p = 1; ok && p < parts.size(); ++p) {
          std::int64_t other;
          ok = (parts[p].empty() && !(p == 1 && parts.size() == 2)) || ParseInt64(parts[p], &other);
        }
        if (!ok) fail("f", "malformed vertex reference " + Quoted(corner) + " (expected v, v/vt, v//vn or v/vt/vn)");
        const auto defined = static_cast<std::int64_t>(mesh.vertices.size());
        if (idx == 0) fail("f", "vertex index 0 is invalid (OBJ indices start at 1)");
        if (idx < 0) {
          // Relative: -1 is the last vertex defined so far.
          if (-idx > defined) {
            fail("f", "vertex index " + std::to_string(idx) + " out of range (" + std::to_string(defined) +
                          " vertices defined before this line)");
          }
          idx = defined + idx;
        } else {
          if (idx > static_cast<std::int64_t>(3 * kMaxTriangles)) {
            fail("f", "vertex index " + std::to_string(idx) + " out of range (file has at most " +
                          std::to_string(3 * kMaxTriangles) + " vertices)");
          }
          if (idx > defined) forward_refs.push_back({line_no, idx});
          idx = idx - 1;
        }
        corners.push_back(static_cast<int>(idx));
      }
      // Fan triangulation of the (assumed convex, planar) polygon.
      if (mesh.triangles.size() + corners.size() - 2 > kMaxTriangles) {
        fail("f", "too many triangles (limit " + std::to_string(kMaxTriangles) + ")");
      }
      for (std::size_t k = 1; k + 1 < corners.size(); ++k) {
        mesh.triangles.emplace_back(corners[0], corners[k], corners[k + 1]);
      }
    } else if (kw == "vt" || kw == "vn" || kw == "vp" || kw == "usemtl" || kw == "mtllib" || kw == "o" ||
               kw == "g" || kw == "s" || kw == "l" || kw == "p") {
      // Texture, normals, materials, grouping, smoothing, lines and points carry no solid geometry.
    } else {
      fail(std::string(kw.substr(0, 20)), "unknown OBJ statement " + Quoted(kw) + " (expected v, f, vt, vn, ...)");
    }
  }
  // Positive indices may point forward; now that every vertex is known, check them.
  const auto total = static_cast<std::int64_t>(mesh.vertices.size());
  for (const auto& ref : forward_refs) {
    if (ref.index > total) {
      throw WorldError(file_name, ref.line, "f",
                       "vertex index " + std::to_string(ref.index) + " out of range (file has " +
                           std::to_string(total) + " vertices)");
    }
  }
  if (mesh.triangles.empty()) throw WorldError(file_name, 0, "f", "no faces found (an OBJ world needs triangles)");
  return mesh;
}

std::uintmax_t CheckInputFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw WorldError(name, 0, "file", "not found or not a regular file");
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw WorldError(name, 0, "file", "cannot read: " + ec.message());
  if (size > kMaxFileBytes) {
    throw WorldError(name, 0, "file", "too large (" + std::to_string(size) + " bytes; limit 256 MiB)");
  }
  return size;
}

std::string ReadInputFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::uintmax_t size = CheckInputFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw WorldError(name, 0, "file", "cannot open for reading");
  std::string text(size, '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return text;
}

ImportedMesh LoadObjFile(const std::filesystem::path& path) {
  return ParseObj(ReadInputFile(path), path.string());
}

}  // namespace enavi::worlds
