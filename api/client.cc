#include "api/client.h"

#include <regex>
#include <stdexcept>

#include <httplib.h>

namespace enavi::api {
namespace {

std::string ErrorMessage(const httplib::Result& res) {
  try {
    const auto j = nlohmann::json::parse(res->body);
    if (j.is_object() && j.contains("error")) return j["error"].get<std::string>();
  } catch (const nlohmann::json::exception&) {
  }
  return res->body.empty() ? ("HTTP " + std::to_string(res->status)) : res->body;
}

}  // namespace

FarmClient::FarmClient(std::string url, std::string token)
    : url_(std::move(url)), token_(std::move(token)) {
  static const std::regex kUrl(R"(^https?://[A-Za-z0-9._\-\[\]:]+(:[0-9]+)?/?$)");
  if (!std::regex_match(url_, kUrl)) {
    throw std::invalid_argument("--server: '" + url_ + "' is not a URL like http://HOST:PORT");
  }
  while (!url_.empty() && url_.back() == '/') url_.pop_back();
}

FarmClient::~FarmClient() = default;

std::string FarmClient::RequestRaw(const std::string& method, const std::string& path,
                                   const std::string& body, const std::string& file_name,
                                   const std::string& content_type) {
  httplib::Client client(url_);
  client.set_connection_timeout(5, 0);
  client.set_read_timeout(120, 0);
  client.set_write_timeout(60, 0);
  httplib::Headers headers;
  if (!token_.empty()) headers.emplace("Authorization", "Bearer " + token_);
  if (!file_name.empty()) headers.emplace("X-Enavi-File", file_name);
  httplib::Result res = method == "GET" ? client.Get(path.c_str(), headers)
                                        : client.Post(path.c_str(), headers, body, content_type);
  if (!res) {
    // httplib names its errors in a word ("Connection"): say what it means here.
    const httplib::Error error = res.error();
    const std::string why = error == httplib::Error::Connection
                                ? "connection refused or timed out (is `enavi serve` running there? --server or "
                                  "ENAVI_SERVER names another)"
                                : httplib::to_string(error);
    throw std::runtime_error("cannot reach the farm server at " + url_ + ": " + why);
  }
  if (res->status >= 400 && res->status < 500) {
    // The request was at fault (bad spec, unknown job, missing token): bad input.
    throw std::invalid_argument(ErrorMessage(res));
  }
  if (res->status >= 300) {
    throw std::runtime_error("farm server " + url_ + path + ": HTTP " +
                             std::to_string(res->status) + ": " + ErrorMessage(res));
  }
  return res->body;
}

nlohmann::json FarmClient::Request(const std::string& method, const std::string& path,
                                   const std::string& body, const std::string& file_name) {
  const std::string reply = RequestRaw(method, path, body, file_name, "application/yaml");
  try {
    return nlohmann::json::parse(reply);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("farm server " + url_ + path + ": reply is not JSON: " + e.what());
  }
}

std::string FarmClient::UploadPolicy(const std::string& policy_json) {
  const std::string reply = RequestRaw("POST", "/api/policies", policy_json, "", "application/json");
  return nlohmann::json::parse(reply).at("hash").get<std::string>();
}

std::vector<StoredRollout> FarmClient::Rollouts(const std::string& job_id) {
  return DecodeRolloutStream(RequestRaw("GET", "/api/jobs/" + job_id + "/rollouts", "", "", ""),
                             url_ + "/api/jobs/" + job_id + "/rollouts");
}

FarmClient::Submitted FarmClient::Submit(const std::string& yaml, const std::string& file_name) {
  const auto j = Request("POST", "/api/jobs", yaml, file_name);
  return {j.at("job_id").get<std::string>(), j.value("name", std::string()),
          j.at("episodes").get<int>()};
}

JobProgress FarmClient::Status(const std::string& job_id) {
  return Request("GET", "/api/jobs/" + job_id).get<JobProgress>();
}

std::vector<JobProgress> FarmClient::Jobs(const std::map<std::string, std::string>& labels) {
  // Label characters are URL-safe (api::LabelError) except '+', which a query reads as a space.
  std::string query;
  for (const auto& [k, v] : labels) {
    query += query.empty() ? "?label=" : "&label=";
    query += k;
    query += '=';
    for (char c : v) {
      if (c == '+') {
        query += "%2B";
      } else {
        query += c;
      }
    }
  }
  return Request("GET", "/api/jobs" + query).get<std::vector<JobProgress>>();
}

nlohmann::json FarmClient::Results(const std::string& job_id) {
  return Request("GET", "/api/jobs/" + job_id + "/results");
}

nlohmann::json FarmClient::Episodes(const std::string& job_id) {
  return Request("GET", "/api/jobs/" + job_id + "/episodes");
}

nlohmann::json FarmClient::Trend(const std::string& label, const std::string& metric) {
  return Request("GET", "/api/trend?label=" + httplib::detail::encode_query_param(label) +
                            "&metric=" + httplib::detail::encode_query_param(metric) + "&limit=1000");
}

JobProgress FarmClient::Cancel(const std::string& job_id) {
  return Request("POST", "/api/jobs/" + job_id + "/cancel").get<JobProgress>();
}

nlohmann::json FarmClient::Workers() { return Request("GET", "/api/workers"); }

nlohmann::json FarmClient::Health() { return Request("GET", "/api/health"); }

}  // namespace enavi::api
