#pragma once
// Content hashes: a policy is distributed, cached and recorded by the SHA-256 of its bytes.

#include <string>
#include <string_view>

namespace enavi::api {

/// SHA-256 of `bytes` as 64 lower-case hex digits (OpenSSL's implementation).
std::string Sha256Hex(std::string_view bytes);

}  // namespace enavi::api
