#include "worlds/obj_import.h"

#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/unit/worlds/test_util.h"

namespace enavi::worlds {
namespace {

// The message of the WorldError `f()` throws ("" if it throws nothing).
template <typename F>
std::string ErrorOf(F&& f) {
  try {
    f();
  } catch (const WorldError& e) {
    return e.what();
  }
  return "";
}

// A unit cube as 8 vertices and 6 quads (12 triangles once fanned).
constexpr const char* kCube = R"(# unit cube
mtllib cube.mtl
o Cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vn 0 0 1
usemtl grey
s off
g faces
f 1 4 3 2
f 5/1 6/1 7/1 8/1
f 1//1 2//1 6//1 5//1
f 2/1/1 3/1/1 7/1/1 6/1/1
f 3 4 8 7
f 4 1 5 8
)";

TEST(ObjImportTest, ReadsAllFaceFormsAndFanTriangulatesQuads) {
  const ImportedMesh m = ParseObj(kCube, "cube.obj");
  EXPECT_EQ(m.vertices.size(), 8u);
  ASSERT_EQ(m.triangle_count(), 12u);
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 3, 2)) << "first fan triangle of f 1 4 3 2";
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 2, 1)) << "second fan triangle of f 1 4 3 2";
  EXPECT_EQ(m.Bounds().max(), Eigen::Vector3d(1, 1, 1));
}

TEST(ObjImportTest, PentagonBecomesThreeTriangles) {
  const ImportedMesh m = ParseObj("v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n", "p.obj");
  EXPECT_EQ(m.triangle_count(), 3u);
}

TEST(ObjImportTest, NegativeIndicesCountBackFromTheLastVertex) {
  const ImportedMesh m = ParseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -4/1 -3/1 -1/1\n", "n.obj");
  ASSERT_EQ(m.triangle_count(), 2u);
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 1, 3));
}

TEST(ObjImportTest, AcceptsCrlfCommentsVertexColoursAndPlusSigns) {
  const ImportedMesh m =
      ParseObj("v 0 0 0 1 0 0\r\nv +1 0 0 # x\r\nv 0 1.5e0 0 1.0\r\n\r\nf 1 2 3\r\nl 1 2\r\n", "c.obj");
  EXPECT_EQ(m.triangle_count(), 1u);
  EXPECT_FLOAT_EQ(m.vertices[1].x(), 1.0f);
  EXPECT_FLOAT_EQ(m.vertices[2].y(), 1.5f);
}

TEST(ObjImportTest, IndexBeyondTheVertexCountNamesFileLineAndCount) {
  std::string text;
  for (int i = 0; i < 12; ++i) text += "v " + std::to_string(i) + " 0 0\n";
  text += "f 1 2 17\n";  // line 13
  EXPECT_EQ(ErrorOf([&] { ParseObj(text, "chair.obj"); }),
            "chair.obj:13: f: vertex index 17 out of range (file has 12 vertices)");
}

TEST(ObjImportTest, ForwardReferenceIsAllowedWhenTheVertexExistsLater) {
  const ImportedMesh m = ParseObj("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", "fwd.obj");
  EXPECT_EQ(m.triangle_count(), 1u);
}

TEST(ObjImportTest, NegativeIndexBeforeEnoughVerticesIsAnError) {
  EXPECT_EQ(ErrorOf([] { ParseObj("v 0 0 0\nv 1 0 0\nf -1 -2 -3\n", "neg.obj"); }),
            "neg.obj:3: f: vertex index -3 out of range (2 vertices defined before this line)");
}

TEST(ObjImportTest, IndexZeroIsInvalid) {
  EXPECT_EQ(ErrorOf([] { ParseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "z.obj"); }),
            "z.obj:4: f: vertex index 0 is invalid (OBJ indices start at 1)");
}

TEST(ObjImportTest, MalformedInputNamesTheLineAndStatement) {
  EXPECT_EQ(ErrorOf([] { ParseObj("v 0 0 0\nv 1 0 abc\n", "a.obj"); }), "a.obj:2: v: not a finite number: 'abc'");
  EXPECT_EQ(ErrorOf([] { ParseObj("v nan 0 0\n", "a.obj"); }), "a.obj:1: v: not a finite number: 'nan'");
  EXPECT_EQ(ErrorOf([] { ParseObj("v 1 2\n", "a.obj"); }), "a.obj:1: v: expected 3 coordinates (got 2 values)");
  EXPECT_EQ(ErrorOf([] { ParseObj("v 0 0 0\nv 1 0 0\nf 1 2\n", "a.obj"); }),
            "a.obj:3: f: a face needs at least 3 vertices (got 2)");
  EXPECT_EQ(ErrorOf([] { ParseObj("v 0 0 0\nf 1/x 1 1\n", "a.obj"); }),
            "a.obj:2: f: malformed vertex reference '1/x' (expected v, v/vt, v//vn or v/vt/vn)");
  EXPECT_EQ(ErrorOf([] { ParseObj("v 1e13 0 0\n", "a.obj"); }),
            "a.obj:1: v: coordinate 1e13 is out of range (|x| <= 1e12 in the file's units)");
  EXPECT_EQ(ErrorOf([] { ParseObj("hello world\n", "a.obj"); }),
            "a.obj:1: hello: unknown OBJ statement 'hello' (expected v, f, vt, vn, ...)");
  EXPECT_EQ(ErrorOf([] { ParseObj("v 0 0 0\n", "a.obj"); }), "a.obj: f: no faces found (an OBJ world needs triangles)");
}

TEST(ObjImportTest, RandomBytesNeverCrashOnlyThrowWorldError) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 500; ++trial) {
    std::string text(static_cast<std::size_t>(rng() % 200), '\0');
    for (auto& c : text) c = static_cast<char>(rng() % 256);
    if (trial % 2 == 0) text = std::string(kCube).substr(0, rng() % 300) + text;
    try {
      ParseObj(text, "fuzz.obj");
    } catch (const WorldError&) {
      // expected for most inputs
    }
  }
}

TEST(ObjImportTest, LoadObjFileNamesAMissingFile) {
  testing::TempDir dir;
  const auto path = dir.path() / "missing.obj";
  EXPECT_EQ(ErrorOf([&] { LoadObjFile(path); }).rfind(path.string() + ": file: not found or not a regular file", 0), 0u);
}

TEST(ObjImportTest, ObjWorldBoundsContainMeshStartAndGoalWithPadding) {
  testing::TempDir dir;
  const auto path = dir.Write("cube.obj", kCube);
  const World w = WorldFromMesh(path, LoadObjFile(path), {}, Eigen::Vector3d(-3, 0.5, 0.5), Eigen::Vector3d(4, 0.5, 0.5), 2.0);
  EXPECT_EQ(w.bounds.min(), Eigen::Vector3d(-5, -2, -2));
  EXPECT_EQ(w.bounds.max(), Eigen::Vector3d(6, 3, 3));
  EXPECT_FALSE(w.ground.enabled);
  EXPECT_EQ(w.metadata.scenario, "custom");
  EXPECT_EQ(w.metadata.name, "cube");
  ASSERT_EQ(w.objects.size(), 1u);
  EXPECT_EQ(std::get<MeshObject>(w.objects[0]).path, "cube.obj");
}

}  // namespace
}  // namespace enavi::worlds
