#include "api/base64.h"

#include <openssl/evp.h>

#include <climits>
#include <stdexcept>
#include <string>

namespace enavi::api {
namespace {

bool IsBase64Char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' ||
         c == '/';
}

}  // namespace

std::string Base64Encode(std::string_view bytes) {
  if (bytes.size() > static_cast<std::size_t>(INT_MAX / 4 * 3)) throw std::length_error("Base64Encode: too many bytes");
  std::string text(4 * ((bytes.size() + 2) / 3), '\0');
  const int n = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(text.data()),
                                reinterpret_cast<const unsigned char*>(bytes.data()),
                                static_cast<int>(bytes.size()));
  text.resize(static_cast<std::size_t>(n));
  return text;
}

std::string Base64Decode(std::string_view text) {
  if (text.size() > static_cast<std::size_t>(INT_MAX)) throw std::invalid_argument("base64 text too long");
  if (text.size() % 4 != 0) {
    throw std::invalid_argument("base64 length " + std::to_string(text.size()) +
                                " is not a multiple of 4 (truncated?)");
  }
  // EVP_DecodeBlock skips surrounding whitespace and counts padding as zero bytes: check the
  // text strictly first, so a damaged payload is refused rather than silently shortened.
  std::size_t padding = 0;
  while (padding < 2 && padding < text.size() && text[text.size() - 1 - padding] == '=') ++padding;
  for (std::size_t i = 0; i + padding < text.size(); ++i) {
    if (!IsBase64Char(text[i])) {
      throw std::invalid_argument("character " + std::to_string(i) + " is not base64");
    }
  }
  std::string bytes(3 * (text.size() / 4), '\0');
  const int n = EVP_DecodeBlock(reinterpret_cast<unsigned char*>(bytes.data()),
                                reinterpret_cast<const unsigned char*>(text.data()),
                                static_cast<int>(text.size()));
  if (n < 0) throw std::invalid_argument("not valid base64");
  bytes.resize(static_cast<std::size_t>(n) - padding);
  return bytes;
}

}  // namespace enavi::api
