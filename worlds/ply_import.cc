#include "worlds/ply_import.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "worlds/number_text.h"
#include "worlds/obj_import.h"

namespace enavi::worlds {
namespace {

enum class Type { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool ParseType(std::string_view name, Type* out) {
  static constexpr std::pair<std::string_view, Type> kNames[] = {
      {"char", Type::kInt8},     {"int8", Type::kInt8},       {"uchar", Type::kUint8},   {"uint8", Type::kUint8},
      {"short", Type::kInt16},   {"int16", Type::kInt16},     {"ushort", Type::kUint16}, {"uint16", Type::kUint16},
      {"int", Type::kInt32},     {"int32", Type::kInt32},     {"uint", Type::kUint32},   {"uint32", Type::kUint32},
      {"float", Type::kFloat32}, {"float32", Type::kFloat32}, {"double", Type::kFloat64}, {"float64", Type::kFloat64}};
  for (const auto& [n, t] : kNames) {
    if (name == n) {
      *out = t;
      return true;
    }
  }
  return false;
}

int Size(Type t) {
  switch (t) {
    case Type::kInt8: case Type::kUint8: return 1;
    case Type::kInt16: case Type::kUint16: return 2;
    case Type::kInt32: case Type::kUint32: case Type::kFloat32: return 4;
    case Type::kFloat64: return 8;
  }
  return 0;
}

struct Property {
  std::string name;
  Type type = Type::kFloat32;
  bool list = false;
  Type count_type = Type::kUint8;
};

struct Element {
  std::string name;
  std::int64_t count = 0;
  std::vector<Property> properties;
};

std::vector<std::string_view> Tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

// Values of the body, one at a time: ASCII tokens line by line, or binary numbers.
class Body {
 public:
  Body(std::string_view bytes, std::size_t pos, int line, bool ascii, bool big_endian, const std::string& file)
      : bytes_(bytes), pos_(pos), line_(line), ascii_(ascii), big_(big_endian), file_(file) {}

  // ASCII: the next instance is the next non-empty line.
  void NextInstance(const std::string& element) {
    if (!ascii_) return;
    do {
      if (pos_ >= bytes_.size()) throw WorldError(file_, line_, element, "truncated: the file ends before all " + element + "s");
      const std::size_t end = std::min(bytes_.find('\n', pos_), bytes_.size());
      tokens_ = Tokens(bytes_.substr(pos_, end - pos_));
      pos_ = end + 1;
      ++line_;
    } while (tokens_.empty());
    next_ = 0;
  }
  void EndInstance(const std::string& element) {
    if (ascii_ && next_ != tokens_.size()) throw WorldError(file_, line_, element, "more values than the header declares");
  }

  double Read(Type t, const std::string& field) {
    if (ascii_) {
      if (next_ >= tokens_.size()) throw WorldError(file_, line_, field, "fewer values than the header declares");
      double v = 0.0;
      if (!ParseFiniteDouble(tokens_[next_], &v)) {
        throw WorldError(file_, line_, field, "not a finite number: '" + std::string(tokens_[next_].substr(0, 20)) + "'");
      }
      ++next_;
      return v;
    }
    const int n = Size(t);
    if (pos_ + n > bytes_.size()) throw WorldError(file_, 0, field, "truncated: the binary body ends early");
    unsigned char b[8];
    std::memcpy(b, bytes_.data() + pos_, n);
    pos_ += n;
    if (big_ != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
    switch (t) {
      case Type::kInt8: return static_cast<std::int8_t>(b[0]);
      case Type::kUint8: return b[0];
      case Type::kInt16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
      case Type::kUint16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
      case Type::kInt32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
      case Type::kUint32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
      case Type::kFloat32: { float v; std::memcpy(&v, b, 4); return v; }
      case Type::kFloat64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0.0;
  }
  int line() const { return ascii_ ? line_ : 0; }

 private:
  std::string_view bytes_;
  std::size_t pos_;
  int line_;
  bool ascii_, big_;
  const std::string& file_;
  std::vector<std::string_view> tokens_;
  std::size_t next_ = 0;
};

}  // namespace

ImportedMesh ParsePly(std::string_view bytes, const std::string& file_name) {
  auto fail = [&](int line, const std::string& field, const std::string& reason) {
    throw WorldError(file_name, line, field, reason);
  };
  // Header: line by line up to end_header.
  std::vector<Element> elements;
  std::string format;
  std::size_t pos = 0;
  int line_no = 0;
  bool ended = false;
  while (!ended) {
    if (pos >= bytes.size()) fail(line_no, "header", "truncated: no end_header");
    const std::size_t end = std::min(bytes.find('\n', pos), bytes.size());
    const auto t = Tokens(bytes.substr(pos, end - pos));
    pos = end + 1;
    ++line_no;
    if (line_no == 1) {
      if (t.size() != 1 || t[0] != "ply") fail(1, "header", "not a PLY file (the first line must be 'ply')");
      continue;
    }
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "format") {
      if (t.size() != 3 || (t[1] != "ascii" && t[1] != "binary_little_endian" && t[1] != "binary_big_endian") || t[2] != "1.0")
        fail(line_no, "format", "expected ascii, binary_little_endian or binary_big_endian 1.0");
      format = std::string(t[1]);
    } else if (t[0] == "element") {
      std::int64_t n = 0;
      if (t.size() != 3 || !ParseInt64(t[2], &n) || n < 0 || n > static_cast<std::int64_t>(3 * kMaxTriangles)) {
        fail(line_no, "element", "expected 'element NAME COUNT' with COUNT in [0, " + std::to_string(3 * kMaxTriangles) + "]");
      }
      elements.push_back({std::string(t[1]), n, {}});
    } else if (t[0] == "property") {
      if (elements.empty()) fail(line_no, "property", "a property before any element");
      Property p;
      p.list = t.size() == 5 && t[1] == "list";
      const bool ok = p.list ? ParseType(t[2], &p.count_type) && ParseType(t[3], &p.type)
                             : t.size() == 3 && ParseType(t[1], &p.type);
      if (!ok) fail(line_no, "property", "expected 'property TYPE NAME' or 'property list TYPE TYPE NAME'");
      p.name = std::string(t.back());
      elements.back().properties.push_back(p);
    } else if (t[0] == "end_header") {
      ended = true;
    } else {
      fail(line_no, "header", "unknown header line '" + std::string(t[0].substr(0, 20)) + "'");
    }
  }
  if (format.empty()) fail(0, "format", "missing format line");

  ImportedMesh mesh;
  Body body(bytes, pos, line_no, format == "ascii", format == "binary_big_endian", file_name);
  std::vector<int> corners;
  for (const Element& e : elements) {
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    int axis[3] = {-1, -1, -1};
    for (int i = 0; i < static_cast<int>(e.properties.size()); ++i) {
      const std::string& n = e.properties[i].name;
      if (is_vertex && n.size() == 1 && n[0] >= 'x' && n[0] <= 'z' && !e.properties[i].list) axis[n[0] - 'x'] = i;
    }
    if (is_vertex && (axis[0] < 0 || axis[1] < 0 || axis[2] < 0)) fail(0, "vertex", "needs float properties x, y and z");
    for (std::int64_t k = 0; k < e.count; ++k) {
      body.NextInstance(e.name);
      double xyz[3] = {0, 0, 0};
      for (int i = 0; i < static_cast<int>(e.properties.size()); ++i) {
        const Property& p = e.properties[i];
        if (!p.list) {
          const double v = body.Read(p.type, e.name);
          for (int a = 0; a < 3; ++a) {
            if (i == axis[a]) xyz[a] = v;
          }
          continue;
        }
        const double count = body.Read(p.count_type, e.name);
        if (!(count >= 0 && count <= 1000 && count == std::floor(count))) fail(body.line(), e.name, "bad list length");
        const bool indices = is_face && (p.name == "vertex_indices" || p.name == "vertex_index");
        corners.clear();
        for (int c = 0; c < static_cast<int>(count); ++c) {
          const double v = body.Read(p.type, e.name);
          if (indices) {
            if (!(v >= 0 && v < static_cast<double>(mesh.vertices.size())) || v != std::floor(v)) {
              fail(body.line(), "face", "vertex index " + FormatFixed(v, 0) + " out of range (file has " +
                                            std::to_string(mesh.vertices.size()) + " vertices before its faces)");
            }
            corners.push_back(static_cast<int>(v));
          }
        }
        if (indices) {
          if (corners.size() < 3) fail(body.line(), "face", "a face needs at least 3 vertices (got " + std::to_string(corners.size()) + ")");
          if (mesh.triangles.size() + corners.size() - 2 > kMaxTriangles) {
            fail(body.line(), "face", "too many triangles (limit " + std::to_string(kMaxTriangles) + ")");
          }
          for (std::size_t c = 1; c + 1 < corners.size(); ++c) mesh.triangles.emplace_back(corners[0], corners[c], corners[c + 1]);
        }
      }
      body.EndInstance(e.name);
      if (is_vertex) {
        for (double v : xyz) {
          if (!std::isfinite(v)) fail(body.line(), "vertex", "not a finite number (vertex " + std::to_string(k) + ")");
          if (std::abs(v) > kMaxFileCoordinate) fail(body.line(), "vertex", "coordinate out of range (|x| <= 1e12)");
        }
        mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
      }
    }
  }
  if (mesh.triangles.empty()) fail(0, "face", "no faces found (a mesh world needs triangles)");
  return mesh;
}

ImportedMesh LoadPlyFile(const std::filesystem::path& path) { return ParsePly(ReadInputFile(path), path.string()); }

}  // namespace enavi::worlds
