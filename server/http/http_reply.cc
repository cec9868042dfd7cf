#include "server/http/http_reply.h"

#include <algorithm>
#include <stdexcept>

#include <httplib.h>

namespace enavi::server {

void Reply(httplib::Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  // Stored strings came from workers and users as bytes: invalid UTF-8 is replaced, not a 500.
  res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
}

void Error(httplib::Response& res, int status, const std::string& message) {
  Reply(res, status, {{"error", message}});
}

int ParseInt(const std::string& text, const std::string& field, std::int64_t lo, std::int64_t hi) {
  std::size_t used = 0;
  long long v = 0;
  try {
    v = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || v < lo || v > hi) {
    throw std::invalid_argument(field + ": '" + text + "': expected an integer in [" +
                                std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return static_cast<int>(v);
}

// httplib's own parser cuts "label=k=v" at the second '='.
std::vector<std::string> QueryValues(const httplib::Request& req, const std::string& name) {
  std::vector<std::string> out;
  const auto q = req.target.find('?');
  if (q == std::string::npos) return out;
  const std::string query = req.target.substr(q + 1);
  std::size_t at = 0;
  while (at <= query.size()) {
    const auto end = std::min(query.find('&', at), query.size());
    const std::string item = query.substr(at, end - at);
    if (item.rfind(name + "=", 0) == 0) {
      out.push_back(httplib::detail::decode_url(item.substr(name.size() + 1), true));
    }
    at = end + 1;
  }
  return out;
}

Page PageOf(const httplib::Request& req) {
  Page p;
  if (req.has_param("offset")) p.offset = ParseInt(req.get_param_value("offset"), "offset", 0, 1 << 30);
  if (req.has_param("limit")) p.limit = ParseInt(req.get_param_value("limit"), "limit", 1, 1000);
  return p;
}

}  // namespace enavi::server
