// Every test of the sanitizer tree, and every process it starts (the `enavi` binary in the CLI
// tests), runs with ENAVI_SANITIZER_ENV. It once did not: handed to gtest_discover_tests as a
// list, only the first variable survived, so LeakSanitizer's suppressions never reached a test.
#include <array>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include <gtest/gtest.h>

namespace {

std::string Env(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr ? v : "";
}

// What a child process started through the shell sees.
std::string ChildEnv(const char* name) {
  const std::string cmd = std::string("printf %s \"$") + name + "\"";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  if (!pipe) return "<popen failed>";
  std::string out;
  std::array<char, 256> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe.get()) != nullptr) out += buf.data();
  return out;
}

TEST(SanitizerEnvironmentTest, EveryVariableReachesTheTestAndItsChildren) {
  for (const char* name : {"ASAN_OPTIONS", "UBSAN_OPTIONS", "LSAN_OPTIONS"}) {
    EXPECT_NE(Env(name).find("="), std::string::npos) << name << " is not set in the test";
    EXPECT_EQ(ChildEnv(name), Env(name)) << name << " differs in a child process";
  }
  EXPECT_NE(Env("ASAN_OPTIONS").find("halt_on_error=1"), std::string::npos) << Env("ASAN_OPTIONS");
  EXPECT_NE(Env("LSAN_OPTIONS").find("suppressions="), std::string::npos) << Env("LSAN_OPTIONS");
}

}  // namespace
