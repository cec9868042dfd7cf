#include "api/yaml_read.h"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

#include "api/number_parse.h"

namespace enavi::api {

namespace {

// A range bound as people write it: the shortest exact text, with ".0" on whole numbers ("0.0",
// "6.2832", "0.01").
std::string Bound(double v) {
  std::string s = fmt::format("{}", v);
  if (s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

}  // namespace

void YamlReader::FailAtLine(int line, const std::string& field, const std::string& reason) const {
  if (thrower_) thrower_(source_, line, field, reason);
  // Also the fall-through of a thrower that returned: a reader never goes on after a failure.
  throw std::invalid_argument(source_ + ":" + std::to_string(line) + ": " + field + ": " + reason);
}

void YamlReader::Fail(const YAML::Node& at, const std::string& field, const std::string& reason) const {
  FailAtLine(Line(at), field, reason);
}

YAML::Node YamlReader::Load(const std::string& text) const {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    FailAtLine(e.mark.line + 1, "yaml", e.msg);
  }
}

int YamlReader::Line(const YAML::Node& n) {
  if (!n.IsDefined()) return 0;
  const YAML::Mark mark = n.Mark();
  return mark.is_null() || mark.line < 0 ? 0 : mark.line + 1;
}

const char* YamlReader::Describe(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Map: return "a mapping";
    case YAML::NodeType::Sequence: return "a sequence";
    case YAML::NodeType::Scalar: return "a scalar";
    case YAML::NodeType::Null: return "null";
    default: return "nothing";
  }
}

std::string YamlReader::Shown(const std::string& text) {
  constexpr std::size_t kMax = 40;
  std::string out;
  for (char ch : text.substr(0, kMax)) out += (ch >= 32 && ch < 127) ? ch : '?';
  if (text.size() > kMax) out += "...";
  return out;
}

std::string YamlReader::Scalar(const YAML::Node& n, const std::string& field) const {
  if (!n.IsScalar()) Fail(n, field, std::string("expected a single value (got ") + Describe(n) + ")");
  return n.Scalar();
}

std::string YamlReader::String(const YAML::Node& n, const std::string& field, std::size_t max_length) const {
  if (!n.IsScalar()) Fail(n, field, std::string("expected a string (got ") + Describe(n) + ")");
  const std::string& text = n.Scalar();
  if (text.size() > max_length) Fail(n, field, "longer than " + std::to_string(max_length) + " characters");
  return text;
}

double YamlReader::Number(const YAML::Node& n, const std::string& field) const {
  if (!n.IsScalar()) Fail(n, field, std::string("expected a number (got ") + Describe(n) + ")");
  double v = 0.0;
  if (!ParseFiniteDouble(n.Scalar(), &v)) Fail(n, field, "expected a finite number (got " + Shown(n.Scalar()) + ")");
  return v;
}

double YamlReader::Range(const YAML::Node& n, const std::string& field, double lo, double hi, bool lo_open) const {
  const double v = Number(n, field);
  if (lo_open ? !(v > lo) : !(v >= lo)) {
    Fail(n, field, std::string("must be ") + (lo_open ? "> " : ">= ") + Bound(lo) + " (got " + Shown(n.Scalar()) + ")");
  }
  if (!(v <= hi)) Fail(n, field, "must be <= " + Bound(hi) + " (got " + Shown(n.Scalar()) + ")");
  return v;
}

std::int64_t YamlReader::Integer(const YAML::Node& n, const std::string& field) const {
  const std::string text = Scalar(n, field);
  std::int64_t v = 0;
  if (!ParseInt64(text, &v)) Fail(n, field, "expected an integer (got " + Shown(text) + ")");
  return v;
}

bool YamlReader::Bool(const YAML::Node& n, const std::string& field) const {
  const std::string text = Scalar(n, field);
  if (text != "true" && text != "false") Fail(n, field, "expected true or false (got " + Shown(text) + ")");
  return text == "true";
}

std::vector<YAML::Node> YamlReader::Items(const YAML::Node& n, const std::string& field) const {
  std::vector<YAML::Node> out;
  if (n.IsScalar()) {
    out.push_back(n);
  } else if (n.IsSequence()) {
    for (const auto& item : n) out.push_back(item);
  } else {
    Fail(n, field, std::string("expected a value or a list (got ") + Describe(n) + ")");
  }
  return out;
}

namespace {

std::string JoinNames(std::initializer_list<const char*> names) {
  std::string out;
  for (const char* s : names) out += (out.empty() ? "" : ", ") + std::string(s);
  return out;
}

bool Allowed(std::initializer_list<const char*> allowed, const std::string& key) {
  return allowed.size() == 0 ||
         std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; }) != allowed.end();
}

}  // namespace

void YamlReader::CheckKeys(const YAML::Node& map, const std::string& field,
                           std::initializer_list<const char*> allowed) const {
  Map(*this, map, field, allowed);
}

YamlReader::Map::Map(const YamlReader& reader, const YAML::Node& node, std::string field,
                     std::initializer_list<const char*> allowed)
    : reader_(reader), node_(node), field_(std::move(field)) {
  const std::string where = field_.empty() ? "document" : field_;
  if (!node.IsMap()) reader.Fail(node, where, std::string("expected a mapping (got ") + Describe(node) + ")");
  for (auto it = node.begin(); it != node.end(); ++it) {
    const YAML::Node key = it->first;
    if (!key.IsScalar()) reader.Fail(key, where, "keys must be plain names");
    const std::string name = key.Scalar();
    if (!Allowed(allowed, name)) {
      reader.Fail(key, Join(field_, Shown(name)), "unknown key (allowed: " + JoinNames(allowed) + ")");
    }
    if (!entries_.emplace(name, std::make_pair(key, it->second)).second) reader.Fail(key, Join(field_, name), "duplicate key");
  }
}

const YAML::Node& YamlReader::Map::Get(const std::string& key) const {
  const auto it = entries_.find(key);
  if (it == entries_.end()) reader_.Fail(node_, Join(field_, key), "missing (required)");
  return it->second.second;
}

std::string YamlQuoted(const std::string& text) {
  static const char* kHex = "0123456789abcdef";
  std::string out = "\"";
  for (unsigned char ch : text) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += static_cast<char>(ch);
    } else if (ch < 0x20 || ch == 0x7f) {
      out += "\\x";
      out += kHex[ch >> 4];
      out += kHex[ch & 15];
    } else {
      out += static_cast<char>(ch);
    }
  }
  return out + "\"";
}

}  // namespace enavi::api
