#pragma once
// Shared by the cgroup tests: a control file's value as the kernel (or a plain-file tree) holds it.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace enavi::emulation::testing {

/// The file's contents without trailing newlines ("" if it cannot be read).
inline std::string ReadControlFile(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  while (!s.empty() && s.back() == '\n') s.pop_back();
  return s;
}

}  // namespace enavi::emulation::testing
