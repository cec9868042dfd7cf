#include "navstack/rl/json_read.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace enavi::navstack::rl::detail {

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

std::int64_t JsonReader::Integer(const nlohmann::json& j, const std::string& field) const {
  if (!j.is_number_integer()) Fail(field, "expected an integer, got " + std::string(j.type_name()));
  return j.get<std::int64_t>();
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

Eigen::VectorXd JsonReader::Vector(const nlohmann::json& j, const std::string& field,
                                   Eigen::Index expected) const {
  Array(j, field);
  if (expected >= 0 && static_cast<Eigen::Index>(j.size()) != expected) {
    Fail(field, "expected " + std::to_string(expected) + " numbers, got " + std::to_string(j.size()));
  }
  Eigen::VectorXd v(static_cast<Eigen::Index>(j.size()));
  for (std::size_t i = 0; i < j.size(); ++i) v[static_cast<Eigen::Index>(i)] = Number(j[i], Index(field, i));
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

void WriteFileAtomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write '" + tmp + "'");
    out << text;
    out.flush();
    if (!out) throw std::runtime_error("write to '" + tmp + "' failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot rename '" + tmp + "' to '" + path + "'");
  }
}

nlohmann::json ToJson(const Eigen::Ref<const Eigen::VectorXd>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

}  // namespace enavi::navstack::rl::detail
