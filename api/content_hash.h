#pragma once
// Content hashes: a policy is distributed, cached and recorded by the SHA-256 of its bytes.

#include <filesystem>
#include <string>
#include <string_view>

namespace enavi::api {

/// SHA-256 of `bytes` as 64 lower-case hex digits (OpenSSL's implementation).
std::string Sha256Hex(std::string_view bytes);
/// SHA-256 of a file's content. @throws std::runtime_error naming the file when unreadable.
std::string Sha256File(const std::filesystem::path& path);

}  // namespace enavi::api
