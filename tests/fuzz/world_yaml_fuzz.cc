// World files (worlds/world_io.h): any bytes either load as a valid world or are refused with a
// WorldError naming the file; a loaded world writes back to YAML that loads again.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "tests/fuzz/fuzz_check.h"
#include "worlds/world_io.h"

namespace {

constexpr const char* kSource = "fuzz-world.yaml";

// Mesh paths resolve under an empty directory: a mesh entry is refused, never read from the host.
const std::filesystem::path& BaseDir() {
  static const std::filesystem::path dir = [] {
    std::filesystem::path d = std::filesystem::temp_directory_path() / "enavi-fuzz-world";
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace enavi;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  worlds::WorldFileOptions options;
  options.max_objects = 2000;  // sandbox limits: a fuzz input must stay cheap
  worlds::World world;
  try {
    world = worlds::ParseWorld(text, kSource, BaseDir(), options);
  } catch (const worlds::WorldError& e) {
    fuzz::Check(e.file() == kSource, "WorldError names another file");
    fuzz::Check(!e.field().empty(), "WorldError without a field");
    return 0;
  } catch (const std::exception& e) {
    fuzz::CheckNamesSource(e, kSource);
    return 0;
  }
  // Accepted: the writer's text is a world file too.
  const std::string yaml = worlds::WorldToYaml(world);
  try {
    worlds::ParseWorld(yaml, "rewritten.yaml", BaseDir(), options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "a loaded world does not load again after WorldToYaml: %s\n%s\n", e.what(),
                 yaml.c_str());
    std::abort();
  }
  return 0;
}
