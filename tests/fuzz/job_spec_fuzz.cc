// Job specs (api/job_spec.h): any bytes either parse and validate into a job that expands to at
// most max_episodes episodes, all of known boards and methods, or are refused with a
// JobSpecError naming the file.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "api/job_spec.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

constexpr const char* kSource = "fuzz-job.yaml";

enavi::api::JobSpecOptions Options() {
  using namespace enavi::api;
  JobSpecOptions o;
  // World and policy files resolve under an empty directory: a file entry is refused.
  const auto root = std::filesystem::temp_directory_path() / "enavi-fuzz-job";
  std::filesystem::create_directories(root);
  o.allowed_roots = {root};
  o.max_episodes = 500;  // the server's limit is larger; small keeps an input cheap
  o.catalog = enavi::fuzz::Catalog();
  return o;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace enavi;
  static const api::JobSpecOptions options = Options();
  const std::string text(reinterpret_cast<const char*>(data), size);
  api::JobSpec job;
  try {
    job = api::ParseJobSpec(text, kSource, options);
  } catch (const api::JobSpecError& e) {
    fuzz::Check(std::string(e.what()).rfind(kSource, 0) == 0, "JobSpecError does not start with the file");
    return 0;
  } catch (const std::exception& e) {
    fuzz::CheckNamesSource(e, kSource);
    return 0;
  }
  fuzz::Check(job.MatrixSize() <= options.max_episodes, "accepted job above max_episodes");
  const auto episodes = api::ExpandJob(job);
  fuzz::Check(episodes.size() == job.MatrixSize(), "ExpandJob size differs from MatrixSize");
  for (const api::EpisodeSpec& e : episodes) {
    fuzz::Check(std::find(options.catalog.boards.begin(), options.catalog.boards.end(), e.board) !=
                    options.catalog.boards.end(),
                "episode on an unknown board");
    fuzz::Check(options.catalog.Find(e.method) != nullptr, "episode of an unknown method");
  }
  return 0;
}
