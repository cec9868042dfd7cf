// Base64 (api/base64.h): the RFC 4648 test vectors, exact round trips of every length and byte,
// and refusal of anything but canonical text.

#include "api/base64.h"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace enavi::api {
namespace {

TEST(Base64Test, EncodesTheRfc4648Vectors) {
  EXPECT_EQ(Base64Encode(""), "");
  EXPECT_EQ(Base64Encode("f"), "Zg==");
  EXPECT_EQ(Base64Encode("fo"), "Zm8=");
  EXPECT_EQ(Base64Encode("foo"), "Zm9v");
  EXPECT_EQ(Base64Encode("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64Encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(Base64Encode("foobar"), "Zm9vYmFy");
}

TEST(Base64Test, RoundTripsEveryLengthAndByte) {
  std::string bytes;
  for (int n = 0; n < 300; ++n) {
    EXPECT_EQ(Base64Decode(Base64Encode(bytes)), bytes) << n << " bytes";
    bytes.push_back(static_cast<char>(n * 37 % 256));
  }
}

TEST(Base64Test, RefusesNonCanonicalText) {
  EXPECT_THROW(Base64Decode("Zm9vYg="), std::invalid_argument) << "length not a multiple of 4";
  EXPECT_THROW(Base64Decode("Zm9v\nYmFy"), std::invalid_argument) << "a line break";
  EXPECT_THROW(Base64Decode(" Zm9vYmF"), std::invalid_argument) << "whitespace";
  EXPECT_THROW(Base64Decode("Zm=vYmFy"), std::invalid_argument) << "padding inside";
  EXPECT_THROW(Base64Decode("Zg=="
                            "===="),
               std::invalid_argument)
      << "padding only";
  EXPECT_THROW(Base64Decode("Zm9*"), std::invalid_argument) << "not in the alphabet";
  try {
    Base64Decode("Zm9vY*Fy");
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("character 5"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace enavi::api
