#pragma once
// The HTTP API's small shared pieces (http_api.cc, dashboard_routes.cc): JSON replies, errors,
// and the query parameters every list route reads the same way.

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/store/queries.h"

namespace httplib {
struct Request;
struct Response;
}  // namespace httplib

namespace enavi::server {

/// `body` as the reply, with `status`.
void Reply(httplib::Response& res, int status, const nlohmann::json& body);
/// {"error": message}, with `status`.
void Error(httplib::Response& res, int status, const std::string& message);
/// An integer in [lo, hi]. @throws std::invalid_argument naming `field` (a 400).
int ParseInt(const std::string& text, const std::string& field, std::int64_t lo, std::int64_t hi);
/// Every value of query parameter `name`, split at the first '=' only, URL-decoded.
std::vector<std::string> QueryValues(const httplib::Request& req, const std::string& name);
/// ?offset=&limit= of the paged list routes.
Page PageOf(const httplib::Request& req);

}  // namespace enavi::server
