// Which requests the viewer answers at all: the checks against the attacks a web server on the user's own machine
// meets from the user's own browser. A page on another site can send requests to 127.0.0.1 (a form or a `text/plain`
// POST needs no CORS preflight) and, by rebinding its own host name to 127.0.0.1 (DNS rebinding), read the answers as
// its own. The Host header tells a rebound request (it names the attacker's host), the Origin header a cross-site
// one, and a JSON content type forces the browser to ask first (a preflight the viewer never grants).
#pragma once

#include <string>

namespace mipnerf::view {

// The address the server is bound to (as given to --host) and its port: the Host a request must name.
struct BoundAddress {
  std::string host = "127.0.0.1";  // "127.0.0.1", "localhost", "::1", "0.0.0.0", "192.168.1.5", …
  int port = 0;                    // 0 while not bound: no Host matches
};

// Whether `host_header` (the request's Host, "name[:port]", IPv6 names in brackets) names this server: the port is the
// bound one (80 when the header has none) and the name is `localhost`, `127.0.0.1`, `[::1]` or the bound address.
// A server bound to every address (0.0.0.0 or ::) cannot know the names it is reached by: there any name passes and
// the token, which such a server always requires, is what guards it.
bool host_allowed(const std::string& host_header, const BoundAddress& bound);

// Whether an Origin header ("http://name:port", "null", or absent: empty) may make a state-changing request: absent
// (a client that is not a browser, or a same-origin navigation), or http:// with a Host that host_allowed accepts.
bool origin_allowed(const std::string& origin_header, const BoundAddress& bound);

// Whether a Content-Type header is JSON ("application/json", any parameters, any case): a type a cross-site page
// cannot send without a CORS preflight.
bool is_json_content_type(const std::string& content_type_header);

}  // namespace mipnerf::view
