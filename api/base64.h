#pragma once
// Base64 (RFC 4648, standard alphabet, padded) for binary payloads inside JSON documents, such as
// a policy file's weights. OpenSSL's implementation (EVP_EncodeBlock / EVP_DecodeBlock).

#include <string>
#include <string_view>

namespace enavi::api {

/// `bytes` as padded base64 without line breaks.
std::string Base64Encode(std::string_view bytes);

/// The bytes `text` encodes. Only canonical input is accepted: no whitespace or line breaks, a
/// length that is a multiple of 4, at most two '=' and only at the end.
/// @throws std::invalid_argument with the reason (and the offset of a bad character); the caller
///   adds the source and field.
std::string Base64Decode(std::string_view text);

}  // namespace enavi::api
