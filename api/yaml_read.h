#pragma once
// The validated reader for YAML (docs/design.md, "Reliability rules"), the twin of JsonReader:
// every read names the source, the line and the field, so bad input reads
// "<source>:<line>: <field>: <reason>" (std::invalid_argument, or the caller's own error type;
// exit 2 at the command line). Used by world files, job specs, board profiles and compare rules.

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace enavi::api {

class YamlReader {
 public:
  /// Throws the caller's error for (source, line, field, reason); line is 1-based, 0 when unknown.
  using Thrower = std::function<void(const std::string& source, int line, const std::string& field,
                                     const std::string& reason)>;

  /// Without a thrower, errors are std::invalid_argument("<source>:<line>: <field>: <reason>").
  explicit YamlReader(std::string source, Thrower thrower = nullptr)
      : source_(std::move(source)), thrower_(std::move(thrower)) {}
  const std::string& source() const { return source_; }

  [[noreturn]] void Fail(const YAML::Node& at, const std::string& field, const std::string& reason) const;
  [[noreturn]] void FailAtLine(int line, const std::string& field, const std::string& reason) const;

  /// One YAML document; a syntax error fails as "<source>:<line>: yaml: <message>".
  YAML::Node Load(const std::string& text) const;

  /// The value itself, as text: any scalar (not a list or a map).
  std::string Scalar(const YAML::Node& n, const std::string& field) const;
  /// A scalar of at most max_length characters.
  std::string String(const YAML::Node& n, const std::string& field, std::size_t max_length = 256) const;
  /// A finite number (decimal text, exactly as written: std::from_chars).
  double Number(const YAML::Node& n, const std::string& field) const;
  /// A finite number in [lo, hi] (lo excluded when lo_open); the message gives the allowed range.
  double Range(const YAML::Node& n, const std::string& field, double lo, double hi, bool lo_open = false) const;
  std::int64_t Integer(const YAML::Node& n, const std::string& field) const;
  /// true or false, nothing else.
  bool Bool(const YAML::Node& n, const std::string& field) const;
  /// A scalar or a list of scalars, as nodes.
  std::vector<YAML::Node> Items(const YAML::Node& n, const std::string& field) const;
  /// Refuses keys of `map` outside `allowed` (when not empty) and keys given twice.
  void CheckKeys(const YAML::Node& map, const std::string& field, std::initializer_list<const char*> allowed) const;

  /// A mapping's entries by key: unknown, duplicate and non-scalar keys refused when it is built.
  class Map {
   public:
    Map(const YamlReader& reader, const YAML::Node& node, std::string field, std::initializer_list<const char*> allowed);
    bool Has(const std::string& key) const { return entries_.count(key) != 0; }
    /// The value of a required key ("missing (required)" when absent).
    const YAML::Node& Get(const std::string& key) const;
    int KeyLine(const std::string& key) const { return Line(entries_.at(key).first); }
    std::string Field(const std::string& key) const { return Join(field_, key); }
    const YAML::Node& node() const { return node_; }

   private:
    const YamlReader& reader_;
    YAML::Node node_;
    std::string field_;
    std::map<std::string, std::pair<YAML::Node, YAML::Node>> entries_;
  };

  static int Line(const YAML::Node& n);  ///< 1-based; 0 when unknown
  /// "a mapping", "a sequence", "a scalar", "null", "nothing": for "(got ...)".
  static const char* Describe(const YAML::Node& n);
  /// Value text for a message, printable and cut short so a hostile file cannot flood it.
  static std::string Shown(const std::string& text);
  static std::string Join(const std::string& parent, const std::string& key) {
    return parent.empty() ? key : parent + "." + key;
  }

 private:
  std::string source_;
  Thrower thrower_;
};

/// The writers' side: `text` as a double-quoted YAML scalar (quote and backslash escaped, control
/// characters as \xHH), which any YAML reader reads back as exactly `text`.
std::string YamlQuoted(const std::string& text);

}  // namespace enavi::api
