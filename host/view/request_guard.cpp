// Host, Origin and Content-Type checks of the viewer's requests.
#include "view/request_guard.hpp"

#include <algorithm>
#include <cctype>

namespace mipnerf::view {
namespace {

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

std::string trim(const std::string& text) {
  const size_t first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  const size_t last = text.find_last_not_of(" \t");
  return text.substr(first, last - first + 1);
}

// The bound address as a Host header names it: lower case, IPv6 in brackets.
std::string host_name_of(const std::string& bound_host) {
  const std::string name = lower(bound_host);
  if (name.find(':') != std::string::npos && name.front() != '[') return "[" + name + "]";
  return name;
}

bool is_wildcard(const std::string& name) { return name == "0.0.0.0" || name == "[::]" || name.empty(); }

// Splits "name[:port]" ("[v6][:port]"); false when malformed (a port that is not 1..65535 digits).
bool split_host(const std::string& header, std::string& name, int& port) {
  std::string text = lower(trim(header));
  if (text.empty()) return false;
  size_t colon = std::string::npos;
  if (text.front() == '[') {
    const size_t close = text.find(']');
    if (close == std::string::npos) return false;
    if (close + 1 < text.size()) {
      if (text[close + 1] != ':') return false;
      colon = close + 1;
    }
  } else {
    colon = text.find(':');
    if (colon != std::string::npos && text.find(':', colon + 1) != std::string::npos) return false;  // bare IPv6
  }
  name = text.substr(0, colon);
  port = 80;
  if (colon != std::string::npos) {
    const std::string digits = text.substr(colon + 1);
    if (digits.empty() || digits.size() > 5 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      return false;
    }
    port = std::stoi(digits);
  }
  return !name.empty() && port > 0 && port <= 65535;
}

}  // namespace

bool host_allowed(const std::string& host_header, const BoundAddress& bound) {
  std::string name;
  int port = 0;
  if (bound.port <= 0 || !split_host(host_header, name, port) || port != bound.port) return false;
  const std::string bound_name = host_name_of(bound.host);
  if (is_wildcard(bound_name)) return true;
  return name == "localhost" || name == "127.0.0.1" || name == "[::1]" || name == bound_name;
}

bool origin_allowed(const std::string& origin_header, const BoundAddress& bound) {
  const std::string origin = trim(origin_header);
  if (origin.empty()) return true;
  const std::string scheme = "http://";
  if (lower(origin.substr(0, scheme.size())) != scheme) return false;  // "null", https://, file://, …
  const std::string rest = origin.substr(scheme.size());
  if (rest.find('/') != std::string::npos) return false;  // an origin has no path
  return host_allowed(rest, bound);
}

bool is_json_content_type(const std::string& content_type_header) {
  const std::string media = lower(trim(content_type_header.substr(0, content_type_header.find(';'))));
  return media == "application/json";
}

}  // namespace mipnerf::view
