// The validated YAML reader: every refusal names source, line, field and reason.
#include "api/yaml_read.h"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace enavi::api {
namespace {

// The error text of `f`, which must throw std::invalid_argument.
template <typename F>
std::string Refusal(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

TEST(YamlReaderTest, ReadsValuesOfTheRightKind) {
  const YamlReader r("spec.yaml");
  const YAML::Node doc = r.Load("a: 1.5\nb: -7\nc: true\nd: [x, y]\ne: name\nf: +2\n");
  EXPECT_DOUBLE_EQ(r.Number(doc["a"], "a"), 1.5);
  EXPECT_DOUBLE_EQ(r.Number(doc["f"], "f"), 2.0);
  EXPECT_EQ(r.Integer(doc["b"], "b"), -7);
  EXPECT_TRUE(r.Bool(doc["c"], "c"));
  EXPECT_EQ(r.Items(doc["d"], "d").size(), 2u);
  EXPECT_EQ(r.Items(doc["e"], "e").size(), 1u);
  EXPECT_EQ(r.String(doc["e"], "e"), "name");
  EXPECT_DOUBLE_EQ(r.Range(doc["a"], "a", 0.0, 2.0), 1.5);
}

TEST(YamlReaderTest, RefusalsNameSourceLineFieldAndReason) {
  const YamlReader r("spec.yaml");
  const YAML::Node doc = r.Load("a: 1.5\nb: thin\nc: [1, 2]\nd: maybe\ne: .nan\nf: 2.5\n");
  EXPECT_EQ(Refusal([&] { r.Number(doc["b"], "b"); }), "spec.yaml:2: b: expected a finite number (got thin)");
  EXPECT_EQ(Refusal([&] { r.Number(doc["e"], "e"); }), "spec.yaml:5: e: expected a finite number (got .nan)");
  EXPECT_EQ(Refusal([&] { r.Scalar(doc["c"], "c"); }), "spec.yaml:3: c: expected a single value (got a sequence)");
  EXPECT_EQ(Refusal([&] { r.String(doc["c"], "c"); }), "spec.yaml:3: c: expected a string (got a sequence)");
  EXPECT_EQ(Refusal([&] { r.Bool(doc["d"], "d"); }), "spec.yaml:4: d: expected true or false (got maybe)");
  EXPECT_EQ(Refusal([&] { r.Integer(doc["f"], "f"); }), "spec.yaml:6: f: expected an integer (got 2.5)");
  EXPECT_EQ(Refusal([&] { r.Range(doc["a"], "a", 2.0, 3.0); }), "spec.yaml:1: a: must be >= 2.0 (got 1.5)");
  EXPECT_EQ(Refusal([&] { r.Range(doc["a"], "a", 1.5, 3.0, true); }), "spec.yaml:1: a: must be > 1.5 (got 1.5)");
  EXPECT_EQ(Refusal([&] { r.Range(doc["a"], "a", 0.0, 0.01); }), "spec.yaml:1: a: must be <= 0.01 (got 1.5)");
  EXPECT_EQ(Refusal([&] { r.String(doc["a"], "a", 2); }), "spec.yaml:1: a: longer than 2 characters");
}

TEST(YamlReaderTest, SyntaxErrorsNameTheLine) {
  const YamlReader r("spec.yaml");
  EXPECT_EQ(Refusal([&] { r.Load("a: 1\nb: [1, 2\n"); }).rfind("spec.yaml:3: yaml: ", 0), 0u);
}

TEST(YamlReaderTest, MapRefusesUnknownDuplicateAndMissingKeys) {
  const YamlReader r("w.yaml");
  const YAML::Node doc = r.Load("box:\n  size: 1\n  colour: red\n");
  EXPECT_EQ(Refusal([&] { YamlReader::Map(r, doc["box"], "box", {"size", "center"}); }),
            "w.yaml:3: box.colour: unknown key (allowed: size, center)");
  const YAML::Node twice = r.Load("a: 1\na: 2\n");
  EXPECT_EQ(Refusal([&] { r.CheckKeys(twice, "", {"a"}); }), "w.yaml:2: a: duplicate key");
  const YamlReader::Map box(r, r.Load("size: 1\n"), "box", {"size", "center"});
  EXPECT_TRUE(box.Has("size"));
  EXPECT_EQ(Refusal([&] { box.Get("center"); }), "w.yaml:1: box.center: missing (required)");
  EXPECT_EQ(Refusal([&] { YamlReader::Map(r, doc["box"]["size"], "box.size", {}); }),
            "w.yaml:2: box.size: expected a mapping (got a scalar)");
}

// A caller's own error type replaces std::invalid_argument, and the reader never goes on after it.
TEST(YamlReaderTest, ThrowsTheCallersErrorType) {
  struct SpecError : std::runtime_error {
    using std::runtime_error::runtime_error;
  };
  const YamlReader r("job.yaml", [](const std::string& source, int line, const std::string& field, const std::string& reason) {
    throw SpecError(source + "@" + std::to_string(line) + " " + field + " " + reason);
  });
  const YAML::Node doc = r.Load("seeds: x\n");
  try {
    r.Integer(doc["seeds"], "seeds");
    FAIL() << "no error";
  } catch (const SpecError& e) {
    EXPECT_STREQ(e.what(), "job.yaml@1 seeds expected an integer (got x)");
  }
}

TEST(YamlReaderTest, ShownCutsLongAndUnprintableText) {
  EXPECT_EQ(YamlReader::Shown("a\tb"), "a?b");
  EXPECT_EQ(YamlReader::Shown(std::string(50, 'x')), std::string(40, 'x') + "...");
}

}  // namespace
}  // namespace enavi::api
