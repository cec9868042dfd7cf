#pragma once
// The validated reader for JSON (docs/design.md, "Reliability rules"): every read names the
// source and the field, so bad input reads "<source>: <field>: <reason>"
// (std::invalid_argument, exit 2 at the command line).

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace enavi::api {

class JsonReader {
 public:
  explicit JsonReader(std::string source) : source_(std::move(source)) {}
  const std::string& source() const { return source_; }

  [[noreturn]] void Fail(const std::string& field, const std::string& reason) const;

  /// obj[key], which must exist; `field` is obj's own path ("" for the root).
  const nlohmann::json& Field(const nlohmann::json& obj, const std::string& field,
                              const std::string& key) const;
  /// obj[key], or null when it is absent or null.
  const nlohmann::json* Optional(const nlohmann::json& obj, const std::string& field,
                                 const std::string& key) const;
  double Number(const nlohmann::json& j, const std::string& field) const;  ///< finite
  std::int64_t Integer(const nlohmann::json& j, const std::string& field) const;
  std::uint64_t Unsigned(const nlohmann::json& j, const std::string& field) const;
  bool Bool(const nlohmann::json& j, const std::string& field) const;
  std::string String(const nlohmann::json& j, const std::string& field) const;
  const nlohmann::json& Array(const nlohmann::json& j, const std::string& field) const;
  const nlohmann::json& Object(const nlohmann::json& j, const std::string& field) const;
  /// Array of finite numbers; expected < 0 accepts any length.
  std::vector<double> Numbers(const nlohmann::json& j, const std::string& field, long expected = -1) const;

  static std::string Join(const std::string& parent, const std::string& key) {
    return parent.empty() ? key : parent + "." + key;
  }
  static std::string Index(const std::string& parent, std::size_t i) {
    return parent + "[" + std::to_string(i) + "]";
  }

 private:
  std::string source_;
};

/// Parses text, turning a syntax error into invalid_argument naming the source and byte offset.
nlohmann::json ParseJson(const std::string& text, const std::string& source);
/// Reads and parses a file. @throws std::invalid_argument when it cannot be opened or parsed.
nlohmann::json ReadJsonFile(const std::string& path, const std::string& what);

}  // namespace enavi::api
