// OBJ meshes (worlds/obj_import.h): any bytes either parse into a mesh whose every triangle
// indexes an existing vertex, or are refused with a WorldError naming the file.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/fuzz_check.h"
#include "worlds/obj_import.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace enavi;
  constexpr const char* kSource = "fuzz-mesh.obj";
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const worlds::ImportedMesh mesh = worlds::ParseObj(text, kSource);
    for (const auto& v : mesh.vertices) fuzz::Check(v.allFinite(), "non-finite vertex");
    const auto n = static_cast<long>(mesh.vertices.size());
    for (const auto& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) fuzz::Check(t[k] >= 0 && t[k] < n, "triangle index out of range");
    }
  } catch (const worlds::WorldError& e) {
    fuzz::Check(e.file() == kSource, "WorldError names another file");
  } catch (const std::exception& e) {
    fuzz::CheckNamesSource(e, kSource);
  }
  return 0;
}
