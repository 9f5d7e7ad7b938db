// The gateway client's options in words: the URL, the token file, the
// reconnect policy and the link's line for the HUD (client.h). No
// networking here.
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "telemetry/gateway/client.h"
#include "telemetry/gateway/lcm_topics.h"

namespace plantscale::telemetry::gateway {

namespace {

[[noreturn]] void BadUrl(const std::string& url, const std::string& why) {
  throw GatewayClientError("--connect " + url + ": " + why);
}

uint16_t ParsePort(const std::string& url, const std::string& text) {
  if (text.empty() || text.size() > 5 || text.find_first_not_of("0123456789") != std::string::npos) {
    BadUrl(url, "port '" + text + "' is not a number 1-65535");
  }
  const int port = std::stoi(text);
  if (port < 1 || port > 65535) BadUrl(url, "port " + text + " is not 1-65535");
  return static_cast<uint16_t>(port);
}

}  // namespace

std::string SecondsText(double s) {
  std::ostringstream out;
  out.precision(1);
  out << std::fixed << s << " s";
  return out.str();
}

GatewayUrl ParseGatewayUrl(const std::string& url) {
  GatewayUrl u;
  u.text = url;
  std::string rest;
  if (url.rfind("wss://", 0) == 0) {
    rest = url.substr(6);
  } else if (url.rfind("ws://", 0) == 0) {
    u.tls = false;
    rest = url.substr(5);
  } else {
    BadUrl(url, "must start with wss:// (the gateway speaks TLS only)");
  }
  const size_t end = rest.find_first_of("/?#");
  const std::string authority = rest.substr(0, end);
  u.target = end == std::string::npos ? "/" : rest.substr(end);
  if (u.target.find('#') != std::string::npos) u.target.erase(u.target.find('#'));
  if (u.target.empty() || u.target.front() != '/') u.target = "/" + u.target;
  if (authority.find('@') != std::string::npos) BadUrl(url, "user names in the URL are not used: the token goes in --token-file");
  std::string port_text;
  if (!authority.empty() && authority.front() == '[') {
    const size_t close = authority.find(']');
    if (close == std::string::npos) BadUrl(url, "an IPv6 address without its closing ]");
    u.host = authority.substr(1, close - 1);
    if (close + 1 < authority.size()) {
      if (authority[close + 1] != ':') BadUrl(url, "expected :PORT after the IPv6 address");
      port_text = authority.substr(close + 2);
      if (port_text.empty()) BadUrl(url, "an empty port");
    }
  } else {
    const size_t colon = authority.rfind(':');
    u.host = authority.substr(0, colon);
    if (colon != std::string::npos) {
      port_text = authority.substr(colon + 1);
      if (port_text.empty()) BadUrl(url, "an empty port");
    }
  }
  if (u.host.empty()) BadUrl(url, "no host");
  u.port = port_text.empty() ? (u.tls ? 443 : 80) : ParsePort(url, port_text);
  if (!u.tls && u.host != "127.0.0.1") {
    BadUrl(url, "plain ws:// only to 127.0.0.1 (a gateway started with --insecure-loopback); use wss://");
  }
  if (!QueryParameter(u.target, "token").empty()) {
    BadUrl(url, "the token belongs in --token-file, not in the URL (a command line shows in ps and in shell history)");
  }
  return u;
}

std::string ReadTokenFile(const std::filesystem::path& file) {
  const auto fail = [&](const std::string& why) -> void {
    throw GatewayClientError("--token-file " + file.string() + ": " + why);
  };
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) fail(std::string("cannot read: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) fail("not a regular file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    fail(std::string("has mode ") + mode + ": a token is a password, group and others must have no access (chmod 600 " +
         file.string() + ")");
  }
  std::ifstream in(file);
  std::string line;
  if (!in || !std::getline(in, line)) fail("cannot read, or empty");
  const size_t first = line.find_first_not_of(" \t\r");
  if (first == std::string::npos) fail("the first line is empty (expected the token `plantscale users add` printed)");
  const size_t last = line.find_last_not_of(" \t\r");
  const std::string token = line.substr(first, last - first + 1);
  for (const char c : token) {
    if (static_cast<unsigned char>(c) <= 0x20 || c == 0x7f) {
      fail("the token holds white space or control characters (expected the token alone on the first line)");
    }
  }
  return token;
}

double ReconnectPolicy::DelayS(int attempt) const {
  const double d = first_delay_s * std::pow(factor, std::max(0, attempt - 1));
  return std::min(d, max_delay_s);
}

OptionErrors ReconnectPolicy::Validate() const {
  OptionErrors e;
  if (!(first_delay_s > 0.0)) e.push_back({"first_delay_s", "must be > 0"});
  if (!(factor >= 1.0)) e.push_back({"factor", "must be >= 1"});
  if (!(max_delay_s >= first_delay_s)) e.push_back({"max_delay_s", "must be >= first_delay_s"});
  return e;
}

OptionErrors GatewayClientOptions::Validate() const {
  OptionErrors e;
  if (url.host.empty()) e.push_back({"url", "no host (ParseGatewayUrl)"});
  if (token.empty()) e.push_back({"token", "required"});
  if (!(connect_timeout_s > 0.0)) e.push_back({"connect_timeout_s", "must be > 0"});
  if (!(idle_timeout_s >= 1.0)) e.push_back({"idle_timeout_s", "must be >= 1"});
  if (max_message_bytes < 1024) e.push_back({"max_message_bytes", "must be >= 1024"});
  for (auto& x : Prefixed("reconnect", reconnect.Validate())) e.push_back(std::move(x));
  return e;
}

std::string LinkText(const GatewayLinkStatus& s) {
  const std::string who = s.user.empty() ? "" : " as " + s.user + " (" + s.role + ")";
  switch (s.state) {
    case LinkState::kConnected:
      return "connected to " + s.url + who;
    case LinkState::kConnecting:
      return (s.connections > 0 ? "reconnecting to " : "connecting to ") + s.url +
             (s.last_error.empty() ? "" : " (last: " + s.last_error + ")");
    case LinkState::kWaiting:
      return "GATEWAY LINK DOWN: " + s.last_error + "; retrying " + s.url + " in " + SecondsText(s.retry_in_s);
    case LinkState::kRefused:
      return "REFUSED by " + s.url + ": " + s.last_error;
  }
  return "";
}


}  // namespace plantscale::telemetry::gateway
