// The viewer's checks of a request's host and origin (view/server.h: HostAllowed,
// OriginAllowed) and of its token (view/server_internal.h: RandomToken, ConstantTimeEqual).
#include <boost/asio/ip/address.hpp>

#include <cctype>
#include <cstdint>
#include <random>
#include <string>

#include "view/server.h"
#include "view/server_internal.h"

namespace candi::view {

namespace server_internal {

std::string RandomToken() {
  std::random_device device;  // /dev/urandom
  std::string hex;
  static const char* digits = "0123456789abcdef";
  for (int i = 0; i < 4; ++i) {
    const uint32_t word = device();
    for (int k = 0; k < 8; ++k) hex += digits[(word >> (4 * k)) & 15];
  }
  return hex;
}

bool ConstantTimeEqual(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

}  // namespace server_internal

namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool IsLoopback(const std::string& bind) { return bind == "127.0.0.1" || bind == "localhost" || bind == "::1"; }

bool IsIpLiteral(const std::string& host) {
  boost::system::error_code ec;
  net::ip::make_address(host, ec);
  return !ec;
}

// "host:port" or "[v6]:port" -> host (brackets removed) and port text.
bool SplitHostPort(const std::string& text, std::string* host, std::string* port) {
  if (!text.empty() && text[0] == '[') {
    const size_t close = text.find(']');
    if (close == std::string::npos) return false;
    *host = text.substr(1, close - 1);
    const std::string rest = text.substr(close + 1);
    if (rest.empty()) *port = "";
    else if (rest[0] == ':') *port = rest.substr(1);
    else return false;
    return true;
  }
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos) {
    *host = text;
    *port = "";
  } else {
    *host = text.substr(0, colon);
    *port = text.substr(colon + 1);
  }
  return host->find(':') == std::string::npos;
}

}  // namespace

bool HostAllowed(const std::string& header, const std::string& bind, int port) {
  std::string host, port_text;
  if (header.size() > 255 || !SplitHostPort(Lower(header), &host, &port_text)) return false;
  const std::string expected_port = std::to_string(port);
  if (port_text != expected_port && !(port == 80 && port_text.empty())) return false;
  if (host == "localhost" || host == "127.0.0.1" || host == "::1") return true;
  if (IsLoopback(bind)) return false;
  // Bound to an address of the network: that address, or any address literal when bound to all
  // of them; never a name (a name can be rebound to another address by its DNS).
  if (bind == "0.0.0.0" || bind == "::") return IsIpLiteral(host);
  return host == Lower(bind);
}

bool OriginAllowed(const std::string& origin, const std::string& bind, int port) {
  const std::string prefix = "http://";
  const std::string o = Lower(origin);
  if (o.compare(0, prefix.size(), prefix) != 0) return false;
  return HostAllowed(o.substr(prefix.size()), bind, port);
}

}  // namespace candi::view
