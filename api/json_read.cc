#include "api/json_read.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace enavi::api {

void JsonReader::Fail(const std::string& field, const std::string& reason) const {
  throw std::invalid_argument(source_ + ": " + (field.empty() ? "(root)" : field) + ": " + reason);
}

const nlohmann::json& JsonReader::Field(const nlohmann::json& obj, const std::string& field,
                                        const std::string& key) const {
  if (!obj.is_object()) Fail(field, "expected an object");
  const auto it = obj.find(key);
  if (it == obj.end()) Fail(Join(field, key), "missing");
  return *it;
}

double JsonReader::Number(const nlohmann::json& j, const std::string& field) const {
  if (!j.is_number()) Fail(field, "expected a number, got " + std::string(j.type_name()));
  const double v = j.get<double>();
  if (!std::isfinite(v)) Fail(field, "expected a finite number");
  return v;
}

const nlohmann::json* JsonReader::Optional(const nlohmann::json& obj, const std::string& field,
                                          const std::string& key) const {
  if (!obj.is_object()) Fail(field, "expected an object");
  const auto it = obj.find(key);
  return it == obj.end() || it->is_null() ? nullptr : &*it;
}

std::int64_t JsonReader::Integer(const nlohmann::json& j, const std::string& field) const {
  if (!j.is_number_integer()) Fail(field, "expected an integer, got " + std::string(j.type_name()));
  return j.get<std::int64_t>();
}

std::uint64_t JsonReader::Unsigned(const nlohmann::json& j, const std::string& field) const {
  if (!j.is_number_unsigned())
    Fail(field, "expected an integer >= 0, got " + (j.is_number() ? j.dump() : std::string(j.type_name())));
  return j.get<std::uint64_t>();
}

bool JsonReader::Bool(const nlohmann::json& j, const std::string& field) const {
  if (!j.is_boolean()) Fail(field, "expected true or false");
  return j.get<bool>();
}

std::string JsonReader::String(const nlohmann::json& j, const std::string& field) const {
  if (!j.is_string()) Fail(field, "expected a string, got " + std::string(j.type_name()));
  return j.get<std::string>();
}

const nlohmann::json& JsonReader::Array(const nlohmann::json& j, const std::string& field) const {
  if (!j.is_array()) Fail(field, "expected an array, got " + std::string(j.type_name()));
  return j;
}

const nlohmann::json& JsonReader::Object(const nlohmann::json& j, const std::string& field) const {
  if (!j.is_object()) Fail(field, "expected an object, got " + std::string(j.type_name()));
  return j;
}

std::vector<double> JsonReader::Numbers(const nlohmann::json& j, const std::string& field, long expected) const {
  Array(j, field);
  if (expected >= 0 && static_cast<long>(j.size()) != expected) {
    Fail(field, "expected " + std::to_string(expected) + " numbers, got " + std::to_string(j.size()));
  }
  std::vector<double> v(j.size());
  for (std::size_t i = 0; i < j.size(); ++i) v[i] = Number(j[i], Index(field, i));
  return v;
}

nlohmann::json ParseJson(const std::string& text, const std::string& source) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(source + ": not valid JSON (byte " + std::to_string(e.byte) +
                                "; truncated or corrupt file?): " + e.what());
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(source + ": not valid JSON: " + e.what());
  }
}

nlohmann::json ReadJsonFile(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(what + " '" + path + "': cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw std::invalid_argument(what + " '" + path + "': read error");
  return ParseJson(ss.str(), what + " '" + path + "'");
}

}  // namespace enavi::api
