// The corpus check: every malformed world, mesh, SDF and job file of tests/corpus/malformed/ is
// refused by each command that reads a user's file (`enavi world check`, `enavi fly --world`,
// `enavi submit --dry-run`), and every malformed policy file of tests/corpus/policy/ by
// `enavi fly --policy` and `enavi policy convert`, with exit code 2 and a message naming the
// file: never a crash (a signal, a sanitizer report: exit 1), never a hang (killed after
// kTimeoutS).
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/worlds/test_util.h"

namespace enavi {
namespace {

namespace fs = std::filesystem;
using worlds::testing::ReadFile;
using worlds::testing::TempDir;

constexpr int kTimeoutS = 60;

fs::path CorpusDir() { return fs::path(ENAVI_SOURCE_DIR) / "tests/corpus/malformed"; }
fs::path PolicyCorpusDir() { return fs::path(ENAVI_SOURCE_DIR) / "tests/corpus/policy"; }

std::vector<std::string> CorpusFiles(const fs::path& dir = CorpusDir()) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

struct Outcome {
  bool exited = false;
  int code = -1;  ///< exit code; the signal number when !exited
  std::string err;
};

// Runs `enavi ARGS` in the corpus directory (mesh paths and --world-root resolve there),
// killed after kTimeoutS (timeout(1) then exits 137).
Outcome Enavi(const TempDir& dir, const std::string& args) {
  const fs::path err = dir.path() / "stderr.txt";
  const std::string cmd = "cd '" + CorpusDir().string() + "' && timeout -s KILL " + std::to_string(kTimeoutS) + " " +
                          std::string(ENAVI_BINARY_DIR) + "/bin/enavi " + args + " >/dev/null 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  Outcome o;
  o.exited = WIFEXITED(status);
  o.code = o.exited ? WEXITSTATUS(status) : WTERMSIG(status);
  o.err = ReadFile(err);
  return o;
}

// Mesh and SDF worlds take their start and goal from the command line.
std::string PlacementFlags(const std::string& file) {
  const std::string ext = fs::path(file).extension().string();
  return ext == ".yaml" ? "" : " --start 0,0,1 --goal 5,0,1";
}

class MalformedInputTest : public ::testing::TestWithParam<std::string> {
 protected:
  void ExpectRefused(const std::string& args) {
    TempDir dir;
    const Outcome o = Enavi(dir, args);
    const std::string& file = GetParam();
    ASSERT_TRUE(o.exited) << "enavi " << args << ": killed by signal " << o.code << "\n" << o.err;
    ASSERT_NE(o.code, 137) << "enavi " << args << ": hung (killed after " << kTimeoutS << " s)";
    EXPECT_EQ(o.code, 2) << "enavi " << args << "\n" << o.err;
    EXPECT_NE(o.err.find(file), std::string::npos) << "enavi " << args << ": the message does not name the file\n"
                                                   << o.err;
  }
};

TEST_P(MalformedInputTest, WorldCheckRefusesIt) { ExpectRefused("world check " + GetParam() + PlacementFlags(GetParam())); }

TEST_P(MalformedInputTest, FlyRefusesIt) {
  ExpectRefused("fly --world " + GetParam() + PlacementFlags(GetParam()) + " --board tx2 --method fixed");
}

TEST_P(MalformedInputTest, SubmitDryRunRefusesIt) { ExpectRefused("submit --dry-run --world-root . " + GetParam()); }

std::string TestName(const ::testing::TestParamInfo<std::string>& info) {
  std::string name;
  for (char c : info.param) name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(Corpus, MalformedInputTest, ::testing::ValuesIn(CorpusFiles()), TestName);

using MalformedPolicyTest = MalformedInputTest;

TEST_P(MalformedPolicyTest, FlyRefusesIt) {
  ExpectRefused("fly --world s3 --board tx2 --method enavi --policy " + (PolicyCorpusDir() / GetParam()).string());
}

TEST_P(MalformedPolicyTest, ConvertRefusesItAndWritesNothing) {
  TempDir dir;
  const fs::path out = dir.path() / "converted.json";
  ExpectRefused("policy convert " + (PolicyCorpusDir() / GetParam()).string() + " --out " + out.string());
  EXPECT_FALSE(fs::exists(out));
}

INSTANTIATE_TEST_SUITE_P(Corpus, MalformedPolicyTest, ::testing::ValuesIn(CorpusFiles(PolicyCorpusDir())), TestName);

}  // namespace
}  // namespace enavi
