#pragma once
// Small worlds in every format the farm reads, written by the tests themselves: the same solid
// boxes as OBJ (millimetres, z up, a georeferenced offset near 1,000 km), glTF and GLB (metres,
// y up), COLLADA (millimetres, z up), STL (ASCII and binary), PLY, and a Gazebo SDF world of
// primitives with an included mesh model.
//
//   top view, every mesh world (metres, once placed):   y
//        +----+  box [2, 4] x [3, 5] x [0, 2]           ^
//        |    |                                           |
//        +----+                                           +--> x
//   S . . . . . . . G    start (-2.5, 0, 1.5), goal (2.5, 0, 1.5)

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "worlds/mesh.h"
#include "worlds/primitives.h"
#include "worlds/world.h"

namespace enavi::worlds::testing {

inline const Eigen::Vector3d kFixtureStart(-2.5, 0.0, 1.5);
inline const Eigen::Vector3d kFixtureGoal(2.5, 0.0, 1.5);
/// The box every mesh fixture holds, in world metres.
inline const Eigen::Vector3d kBoxMin(2, 3, 0), kBoxMax(4, 5, 2);

/// The fixture box as 8 vertices and 12 outward triangles (world metres, z up).
inline TriangleMesh FixtureBox() {
  Box b;
  b.center = 0.5 * (kBoxMin + kBoxMax);
  b.size = kBoxMax - kBoxMin;
  return ObjectMesh(b);
}

inline std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.4f", v);
  return buf;
}

/// World metres -> y-up file coordinates (the inverse of the importer's (x, y, z) -> (x, -z, y)).
inline Eigen::Vector3d ToYUp(const Eigen::Vector3d& w) { return {w.x(), w.z(), -w.y()}; }

/// OBJ in millimetres, z up, every vertex moved by `offset_mm`.
inline std::string ObjMm(const TriangleMesh& m, const Eigen::Vector3d& offset_mm) {
  std::string s = "# fixture: millimetres, z up, georeferenced\n";
  for (const auto& v : m.vertices) {
    const Eigen::Vector3d p = 1000.0 * v.cast<double>() + offset_mm;
    s += "v " + Num(p.x()) + " " + Num(p.y()) + " " + Num(p.z()) + "\n";
  }
  for (const auto& t : m.triangles) s += "f " + std::to_string(t.x() + 1) + " " + std::to_string(t.y() + 1) + " " + std::to_string(t.z() + 1) + "\n";
  return s;
}

// Little-endian bytes of float positions (y up) and uint16 indices: the glTF buffer.
inline std::string GltfBuffer(const TriangleMesh& m, std::size_t* index_bytes) {
  std::string bin;
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) {
      const auto i = static_cast<std::uint16_t>(t[k]);
      bin.append(reinterpret_cast<const char*>(&i), 2);
    }
  }
  while (bin.size() % 4 != 0) bin.push_back('\0');
  *index_bytes = 6 * m.triangles.size();
  for (const auto& v : m.vertices) {
    const Eigen::Vector3f p = ToYUp(v.cast<double>()).cast<float>();
    bin.append(reinterpret_cast<const char*>(p.data()), 12);
  }
  return bin;
}

inline std::string Base64(const std::string& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < in.size(); i += 3) {
    const std::uint32_t n = (static_cast<unsigned char>(in[i]) << 16) |
                            (i + 1 < in.size() ? static_cast<unsigned char>(in[i + 1]) << 8 : 0) |
                            (i + 2 < in.size() ? static_cast<unsigned char>(in[i + 2]) : 0);
    out += k[(n >> 18) & 63];
    out += k[(n >> 12) & 63];
    out += i + 1 < in.size() ? k[(n >> 6) & 63] : '=';
    out += i + 2 < in.size() ? k[n & 63] : '=';
  }
  return out;
}

// The glTF JSON for `m`; `uri` empty for GLB (the buffer is the binary chunk).
inline std::string GltfJson(const TriangleMesh& m, const std::string& bin, std::size_t index_bytes,
                            const std::string& uri) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = Eigen::Vector3f::Constant(-1e30f);
  for (const auto& v : m.vertices) {
    const Eigen::Vector3f p = ToYUp(v.cast<double>()).cast<float>();
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const std::size_t index_padded = (index_bytes + 3) / 4 * 4;
  auto vec = [](const Eigen::Vector3f& v) { return "[" + Num(v.x()) + "," + Num(v.y()) + "," + Num(v.z()) + "]"; };
  return std::string(R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)") +
         R"("meshes":[{"primitives":[{"attributes":{"POSITION":1},"indices":0}]}],)" +
         R"("buffers":[{"byteLength":)" + std::to_string(bin.size()) + (uri.empty() ? "" : R"(,"uri":")" + uri + "\"") +
         "}]," + R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":)" + std::to_string(index_bytes) +
         R"(,"target":34963},{"buffer":0,"byteOffset":)" + std::to_string(index_padded) + R"(,"byteLength":)" +
         std::to_string(12 * m.vertices.size()) + R"(,"target":34962}],)" +
         R"("accessors":[{"bufferView":0,"componentType":5123,"count":)" + std::to_string(3 * m.triangles.size()) +
         R"(,"type":"SCALAR"},{"bufferView":1,"componentType":5126,"count":)" + std::to_string(m.vertices.size()) +
         R"(,"type":"VEC3","min":)" + vec(lo) + R"(,"max":)" + vec(hi) + "}]}";
}

/// glTF 2.0 with the buffer inline (data URI): metres, y up.
inline std::string Gltf(const TriangleMesh& m) {
  std::size_t index_bytes = 0;
  const std::string bin = GltfBuffer(m, &index_bytes);
  return GltfJson(m, bin, index_bytes, "data:application/octet-stream;base64," + Base64(bin));
}

/// GLB (binary glTF 2.0): header, JSON chunk, BIN chunk.
inline std::string Glb(const TriangleMesh& m) {
  std::size_t index_bytes = 0;
  const std::string bin = GltfBuffer(m, &index_bytes);
  std::string json = GltfJson(m, bin, index_bytes, "");
  while (json.size() % 4 != 0) json.push_back(' ');
  auto u32 = [](std::uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  const std::uint32_t total = 12 + 8 + json.size() + 8 + bin.size();
  return "glTF" + u32(2) + u32(total) + u32(json.size()) + u32(0x4E4F534A) + json + u32(bin.size()) +
         u32(0x004E4942) + bin;
}

/// COLLADA 1.4.1 in millimetres (<unit meter="0.001"/>) with <up_axis>Z_UP</up_axis>.
inline std::string DaeMmZUp(const TriangleMesh& m) {
  std::string pos, idx;
  for (const auto& v : m.vertices) pos += Num(1000 * v.x()) + " " + Num(1000 * v.y()) + " " + Num(1000 * v.z()) + " ";
  for (const auto& t : m.triangles) idx += std::to_string(t.x()) + " " + std::to_string(t.y()) + " " + std::to_string(t.z()) + " ";
  return R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="millimeter" meter="0.001"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count=")" + std::to_string(3 * m.vertices.size()) + "\">" + pos +
         R"(</float_array>
      <technique_common><accessor source="#pa" count=")" + std::to_string(m.vertices.size()) +
         R"(" stride="3"><param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count=")" + std::to_string(m.triangles.size()) + R"("><input semantic="VERTEX" source="#v" offset="0"/><p>)" + idx +
         R"(</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
)";
}

/// ASCII STL (metres, z up).
inline std::string StlAscii(const TriangleMesh& m) {
  std::string s = "solid fixture\n";
  for (const auto& t : m.triangles) {
    s += " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const auto& v = m.vertices[t[k]];
      s += "   vertex " + Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z()) + "\n";
    }
    s += "  endloop\n endfacet\n";
  }
  return s + "endsolid fixture\n";
}

/// Binary STL (metres, z up): 80-byte header, count, 50 bytes a triangle.
inline std::string StlBinary(const TriangleMesh& m) {
  std::string s(80, ' ');
  const auto n = static_cast<std::uint32_t>(m.triangles.size());
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : m.triangles) {
    const float normal[3] = {0, 0, 0};
    s.append(reinterpret_cast<const char*>(normal), 12);
    for (int k = 0; k < 3; ++k) s.append(reinterpret_cast<const char*>(m.vertices[t[k]].data()), 12);
    s.append(2, '\0');
  }
  return s;
}

/// ASCII PLY (metres, z up).
inline std::string PlyAscii(const TriangleMesh& m) {
  std::string s = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(m.vertices.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                  std::to_string(m.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : m.vertices) s += Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z()) + "\n";
  for (const auto& t : m.triangles) s += "3 " + std::to_string(t.x()) + " " + std::to_string(t.y()) + " " + std::to_string(t.z()) + "\n";
  return s;
}

/// Binary little-endian PLY (metres, z up), with an extra per-vertex property to skip.
inline std::string PlyBinary(const TriangleMesh& m) {
  std::string s = "ply\nformat binary_little_endian 1.0\ncomment fixture\nelement vertex " +
                  std::to_string(m.vertices.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face " +
                  std::to_string(m.triangles.size()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  for (const auto& v : m.vertices) {
    s.append(reinterpret_cast<const char*>(v.data()), 12);
    s.push_back('\x7f');
  }
  for (const auto& t : m.triangles) {
    s.push_back('\x03');
    for (int k = 0; k < 3; ++k) {
      const auto i = static_cast<std::uint32_t>(t[k]);
      s.append(reinterpret_cast<const char*>(&i), 4);
    }
  }
  return s;
}

/// A Gazebo model `pillar` (model.config, model.sdf): its collision is the mesh
/// model://pillar/meshes/pillar.stl scaled 1 x 1 x 2; its visual, a 9 m box, must be ignored.
inline std::string PillarModelConfig() {
  return "<?xml version=\"1.0\"?>\n<model><name>pillar</name><version>1.0</version><sdf version=\"1.6\">model.sdf</sdf></model>\n";
}
inline std::string PillarModelSdf() {
  return R"(<?xml version="1.0"?>
<sdf version="1.6"><model name="pillar"><static>true</static><link name="link">
  <collision name="c"><geometry><mesh><uri>model://pillar/meshes/pillar.stl</uri><scale>1 1 2</scale></mesh></geometry></collision>
  <visual name="v"><geometry><box><size>9 9 9</size></box></geometry></visual>
</link></model></sdf>
)";
}
/// The pillar's mesh: a unit cube [0, 1]^3 (12 triangles); scaled 1 x 1 x 2 by the model.
inline TriangleMesh UnitCube() {
  Box b;
  b.center = Eigen::Vector3d(0.5, 0.5, 0.5);
  b.size = Eigen::Vector3d::Ones();
  return ObjectMesh(b);
}

/// A Gazebo world: ground_plane and sun by model://, a box turned 0.3 rad about z, an upright
/// cylinder, a sphere, the pillar at (-3, 4, 0), a light, a plugin, a non-static model.
///   box:      centre (3, 4, 1), size 2 x 1 x 2, yaw 0.3      -> 12 triangles
///   cylinder: centre (0, -4, 1.5), radius 0.5, length 3      -> 96 triangles, bounds [-0.5, 0.5] x [-4.5, -3.5] x [0, 3]
///   sphere:   centre (3, -4, 1), radius 0.75                 -> 224 triangles
///   pillar:   mesh [0, 1] x [0, 1] x [0, 2] at (-3, 4, 0)    -> 12 triangles, [-3, -2] x [4, 5] x [0, 2]
inline std::string GazeboWorld() {
  return R"(<?xml version="1.0"?>
<sdf version="1.6">
  <world name="yard">
    <physics type="ode"><max_step_size>0.001</max_step_size></physics>
    <plugin name="p" filename="libgazebo_ros_state.so"/>
    <light type="point" name="lamp"><pose>0 0 5 0 0 0</pose></light>
    <include><uri>model://sun</uri></include>
    <include><uri>model://ground_plane</uri></include>
    <model name="crate"><static>true</static><pose>3 4 1 0 0 0.3</pose><link name="l">
      <collision name="c"><geometry><box><size>2 1 2</size></box></geometry></collision></link></model>
    <model name="post"><static>true</static><pose>0 -4 1.5 0 0 0</pose><link name="l">
      <collision name="c"><geometry><cylinder><radius>0.5</radius><length>3</length></cylinder></geometry></collision></link></model>
    <model name="ball"><static>true</static><link name="l"><pose>3 -4 1 0 0 0</pose>
      <visual name="v"><geometry><sphere><radius>0.75</radius></sphere></geometry></visual></link></model>
    <include><uri>model://pillar</uri><pose>-3 4 0 0 0 0</pose></include>
    <model name="rover"><pose>-10 -10 0 0 0 0</pose><link name="l">
      <collision name="c"><geometry><box><size>1 1 1</size></box></geometry></collision></link></model>
  </world>
</sdf>
)";
}

}  // namespace enavi::worlds::testing
