#include "worlds/mesh_import.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <string_view>
#include <tuple>

#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "worlds/number_text.h"
#include "worlds/obj_import.h"
#include "worlds/ply_import.h"

namespace enavi::worlds {
namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
  return s;
}

// The text between `open` and the next '<' inside the first <asset> block, e.g. "Z_UP".
std::string_view AssetElementText(std::string_view text, std::string_view open) {
  const auto end = text.find("</asset>");
  const std::string_view asset = text.substr(0, end);
  const auto at = asset.find(open);
  if (at == std::string_view::npos) return {};
  std::string_view rest = asset.substr(at + open.size());
  rest = rest.substr(0, rest.find('<'));
  while (!rest.empty() && (rest.front() == ' ' || rest.front() == '\n' || rest.front() == '\t' || rest.front() == '\r'))
    rest.remove_prefix(1);
  while (!rest.empty() && (rest.back() == ' ' || rest.back() == '\n' || rest.back() == '\t' || rest.back() == '\r'))
    rest.remove_suffix(1);
  return rest;
}

// Assimp 5.2 loops forever on a COLLADA number list with a stray character: the lists are
// checked before it reads them (<p>, <vcount>, <int_array>: integers; <float_array>: numbers).
void CheckColladaLists(const std::string& name, const std::string& text) {
  struct List {
    const char* open;
    const char* allowed;
  };
  static constexpr List kLists[] = {{"<p>", "0123456789-"},
                                    {"<vcount>", "0123456789"},
                                    {"<int_array", "0123456789-"},
                                    {"<float_array", "0123456789.eE+-"}};
  for (const auto& list : kLists) {
    const std::string_view open = list.open;
    for (std::size_t at = text.find(open); at != std::string::npos; at = text.find(open, at + 1)) {
      std::size_t i = text.find('>', at);
      if (i == std::string::npos) throw WorldError(name, 0, "xml", "truncated element " + std::string(open) + ">");
      const std::size_t end = text.find('<', i);
      if (end == std::string::npos) throw WorldError(name, 0, "xml", "truncated " + std::string(open) + "> list");
      for (++i; i < end; ++i) {
        const char c = text[i];
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || std::strchr(list.allowed, c) != nullptr) continue;
        const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(i), '\n'));
        throw WorldError(name, line, std::string(open.substr(1)),
                         std::string("not a number list (unexpected '") + (c >= 32 && c < 127 ? std::string(1, c) : "?") + "')");
      }
    }
  }
}

// COLLADA declares its unit and up axis in <asset> (COLLADA 1.4.1 spec, "asset"): <unit meter="0.001"/>,
// <up_axis>Z_UP</up_axis>; the defaults are 1 m and Y_UP.
void ReadColladaAsset(const std::string& name, ImportedMesh* mesh) {
  const std::string text = ReadInputFile(name);
  CheckColladaLists(name, text);
  mesh->file_up = UpAxis::kY;
  const std::string_view up = AssetElementText(text, "<up_axis>");
  if (up == "Z_UP") mesh->file_up = UpAxis::kZ;
  else if (up == "X_UP") throw WorldError(name, 0, "up_axis", "X_UP is not supported (give --up y or z)");
  else if (!up.empty() && up != "Y_UP") throw WorldError(name, 0, "up_axis", "expected Y_UP or Z_UP (got '" + std::string(up.substr(0, 20)) + "')");
  const std::string_view unit = AssetElementText(text, "<unit");
  const auto meter = unit.find("meter=");
  if (meter != std::string_view::npos && meter + 7 < unit.size()) {
    const char quote = unit[meter + 6];
    std::string_view value = unit.substr(meter + 7);
    value = value.substr(0, value.find(quote));
    double m = 0.0;
    if (!ParseFiniteDouble(value, &m) || !(m > 0.0)) {
      throw WorldError(name, 0, "unit", "meter must be a positive number (got '" + std::string(value.substr(0, 20)) + "')");
    }
    mesh->file_unit_m = m;
  }
  // Assimp applies the unit itself (and, told to, leaves the axes alone).
  mesh->applied_unit_m = mesh->file_unit_m.value_or(1.0);
}

// FBX global settings as Assimp reports them: UnitScaleFactor (cm per unit), UpAxis (0, 1, 2)
// with UpAxisSign; Assimp applies neither by default.
void ReadFbxSettings(const std::string& name, const aiScene& scene, ImportedMesh* mesh) {
  if (scene.mMetaData == nullptr) return;
  double unit_cm = 0.0;
  if (scene.mMetaData->Get("UnitScaleFactor", unit_cm) && unit_cm > 0.0) mesh->file_unit_m = 0.01 * unit_cm;
  float unit_cm_f = 0.0f;
  if (!mesh->file_unit_m && scene.mMetaData->Get("UnitScaleFactor", unit_cm_f) && unit_cm_f > 0.0f)
    mesh->file_unit_m = 0.01 * unit_cm_f;
  int axis = -1, sign = 1;
  if (scene.mMetaData->Get("UpAxis", axis)) {
    scene.mMetaData->Get("UpAxisSign", sign);
    if (sign > 0 && axis == 1) mesh->file_up = UpAxis::kY;
    else if (sign > 0 && axis == 2) mesh->file_up = UpAxis::kZ;
    else throw WorldError(name, 0, "UpAxis", "only +y or +z up is supported (give --up y or z)");
  }
}

// Assimp reports geometry it dropped (faces with out-of-range indices, bad accessors) only as log
// messages; they are collected during one import and refuse the file, since silently losing an
// obstacle is worse than no world. One import at a time: Assimp's logger is process-wide.
class AssimpMessages : public Assimp::LogStream {
 public:
  void write(const char* message) override {
    const std::string m = message;
    const bool loss = m.find("rror") != std::string::npos || m.find("out-of-range") != std::string::npos ||
                      m.find("out of range") != std::string::npos || m.find("dropped") != std::string::npos ||
                      m.find("nvalid") != std::string::npos;
    // "Warn,  T0: text\n" -> "text".
    const auto colon = m.find(": ");
    std::string text = colon == std::string::npos ? m : m.substr(colon + 2);
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    if (loss && first_.empty()) first_ = text.substr(0, 200);
  }
  const std::string& first() const { return first_; }

 private:
  std::string first_;
};

class ScopedAssimpLog {
 public:
  explicit ScopedAssimpLog(AssimpMessages* sink) : lock_(Mutex()) {
    Assimp::DefaultLogger::create(nullptr, Assimp::Logger::NORMAL, 0);
    Assimp::DefaultLogger::get()->attachStream(sink, Assimp::Logger::Warn | Assimp::Logger::Err);
    sink_ = sink;
  }
  ~ScopedAssimpLog() {
    Assimp::DefaultLogger::get()->detachStream(sink_, Assimp::Logger::Warn | Assimp::Logger::Err);
    Assimp::DefaultLogger::kill();
  }
  ScopedAssimpLog(const ScopedAssimpLog&) = delete;
  ScopedAssimpLog& operator=(const ScopedAssimpLog&) = delete;

 private:
  static std::mutex& Mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  AssimpMessages* sink_ = nullptr;
};

struct Walker {
  const std::string& name;
  const aiScene& scene;
  ImportedMesh* out;
  std::map<std::tuple<double, double, double>, int> index;  // identical positions share a vertex

  void Node(const aiNode& node, const Eigen::Matrix4d& parent) {
    Eigen::Matrix4d local;
    const aiMatrix4x4& m = node.mTransformation;
    local << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
    const Eigen::Matrix4d X = parent * local;
    for (unsigned i = 0; i < node.mNumMeshes; ++i) {
      if (node.mMeshes[i] >= scene.mNumMeshes) throw WorldError(name, 0, "node", "mesh index out of range");
      Mesh(*scene.mMeshes[node.mMeshes[i]], X);
    }
    for (unsigned c = 0; c < node.mNumChildren; ++c) Node(*node.mChildren[c], X);
  }

  void Mesh(const aiMesh& mesh, const Eigen::Matrix4d& X) {
    const std::string what = "mesh '" + std::string(mesh.mName.C_Str()).substr(0, 40) + "'";
    std::vector<int> ids(mesh.mNumVertices);
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        throw WorldError(name, 0, "vertex", what + " vertex " + std::to_string(v) + " is not a finite number");
      }
      const Eigen::Vector4d q = X * Eigen::Vector4d(p.x, p.y, p.z, 1.0);
      if (!q.head<3>().allFinite() || q.head<3>().cwiseAbs().maxCoeff() > kMaxFileCoordinate) {
        throw WorldError(name, 0, "vertex", what + " vertex " + std::to_string(v) + " is out of range (|x| <= 1e12)");
      }
      const auto key = std::make_tuple(q.x(), q.y(), q.z());
      auto it = index.find(key);
      if (it == index.end()) {
        it = index.emplace(key, static_cast<int>(out->vertices.size())).first;
        out->vertices.emplace_back(q.x(), q.y(), q.z());
      }
      ids[v] = it->second;
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices < 3) continue;  // points and lines are not solid
      if (face.mNumIndices > 3) throw WorldError(name, 0, "face", what + " face " + std::to_string(f) + " is not a triangle");
      for (unsigned k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh.mNumVertices) {
          throw WorldError(name, 0, "face", what + " face " + std::to_string(f) + ": vertex index " +
                                                std::to_string(face.mIndices[k]) + " out of range (mesh has " +
                                                std::to_string(mesh.mNumVertices) + " vertices)");
        }
      }
      if (out->triangles.size() >= kMaxTriangles) {
        throw WorldError(name, 0, "face", "too many triangles (limit " + std::to_string(kMaxTriangles) + ")");
      }
      out->triangles.emplace_back(ids[face.mIndices[0]], ids[face.mIndices[1]], ids[face.mIndices[2]]);
    }
  }
};

ImportedMesh LoadWithAssimp(const std::filesystem::path& path, const std::string& extension) {
  const std::string name = path.string();
  CheckInputFile(path);  // regular file within kMaxFileBytes, before the library sees it
  ImportedMesh mesh;
  if (extension == ".dae") ReadColladaAsset(name, &mesh);
  if (extension == ".gltf" || extension == ".glb") mesh.file_up = UpAxis::kY;  // glTF 2.0 spec: metres, +y up

  AssimpMessages messages;
  const ScopedAssimpLog log(&messages);
  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene = importer.ReadFile(name, aiProcess_Triangulate | aiProcess_ValidateDataStructure);
  if (scene == nullptr) throw WorldError(name, 0, "file", std::string("cannot read: ") + importer.GetErrorString());
  if (!messages.first().empty()) throw WorldError(name, 0, "file", "refused: " + messages.first());
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 || scene->mRootNode == nullptr) {
    throw WorldError(name, 0, "file", "incomplete scene (no geometry could be read)");
  }
  if (extension == ".fbx") ReadFbxSettings(name, *scene, &mesh);
  Walker walker{name, *scene, &mesh, {}};
  walker.Node(*scene->mRootNode, Eigen::Matrix4d::Identity());
  if (mesh.triangles.empty()) throw WorldError(name, 0, "mesh", "no triangles found (a mesh world needs triangles)");
  return mesh;
}

}  // namespace

bool IsMeshFile(const std::filesystem::path& path) {
  const std::string ext = Lower(path.extension().string());
  for (const auto& f : kMeshFormats) {
    if (ext == f.extension) return true;
  }
  return false;
}

std::string MeshExtensions() {
  std::string out;
  for (const auto& f : kMeshFormats) out += (out.empty() ? "" : ", ") + std::string(f.extension);
  return out;
}

ImportedMesh LoadMeshFile(const std::filesystem::path& path) {
  const std::string ext = Lower(path.extension().string());
  if (ext == ".obj") return LoadObjFile(path);
  if (ext == ".ply") return LoadPlyFile(path);
  if (!IsMeshFile(path)) {
    throw WorldError(path.string(), 0, "file", "not a mesh format the farm reads (" + MeshExtensions() + ")");
  }
  return LoadWithAssimp(path, ext);
}

}  // namespace enavi::worlds
