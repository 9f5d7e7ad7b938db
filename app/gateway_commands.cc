#include "app/gateway_commands.h"

#include <atomic>
#include <csignal>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>

#include "app/config/config_loader.h"
#include "telemetry/gateway/server.h"
#include "telemetry/gateway/users.h"
#include "telemetry/transport.h"

namespace plantscale::app {

namespace {

namespace gw = plantscale::telemetry::gateway;
namespace tm = plantscale::telemetry;

std::atomic<bool> g_stop{false};
void OnStopSignal(int) { g_stop = true; }

struct GatewayArgs {
  std::string lcm_url = tm::LcmTransportOptions{}.url;
  std::string listen = "127.0.0.1:8765";
  std::string cert;
  std::string key;
  std::string users;
  bool insecure_loopback = false;
  int max_clients = gw::GatewayOptions{}.max_clients;
};

struct UsersAddArgs {
  std::string name;
  std::string role;
  std::string users;
  bool replace = false;
};

// "HOST:PORT" (an IPv4 address); ConfigError naming `flag` (--listen, --gateway) otherwise.
void ParseListen(const std::string& listen, const char* flag, gw::GatewayOptions& o) {
  const size_t colon = listen.rfind(':');
  const auto bad = [&](const std::string& why) {
    throw ConfigError("command line", flag,
                      "'" + listen + "': " + why + " (e.g. 0.0.0.0:8765)");
  };
  if (colon == std::string::npos || colon == 0) bad("must be HOST:PORT");
  o.host = listen.substr(0, colon);
  const std::string port = listen.substr(colon + 1);
  if (port.empty() || port.size() > 5 ||
      port.find_first_not_of("0123456789") != std::string::npos) {
    bad("the port must be a number 1-65535");
  }
  o.port = std::stoi(port);
  if (o.port < 1 || o.port > 65535) bad("the port must be a number 1-65535");
}

gw::GatewayOptions ServeOptions(const GatewayServeArgs& a, const char* listen_flag) {
  gw::GatewayOptions o;
  ParseListen(a.listen, listen_flag, o);
  o.insecure_loopback = a.insecure_loopback;
  o.cert_file = a.cert;
  o.key_file = a.key;
  o.max_clients = a.max_clients;
  if (a.insecure_loopback && (!a.cert.empty() || !a.key.empty())) {
    throw ConfigError("command line", "--insecure-loopback",
                      "plain ws:// takes no --cert or --key");
  }
  const OptionErrors errors = o.Validate();
  if (!errors.empty()) {
    std::map<std::string, std::string> flag = {{"host", listen_flag},
                                               {"port", listen_flag},
                                               {"cert_file", "--cert"},
                                               {"key_file", "--key"},
                                               {"insecure_loopback", "--insecure-loopback"},
                                               {"max_clients", "--max-clients"}};
    const auto it = flag.find(errors[0].key);
    throw ConfigError("command line", it != flag.end() ? it->second : errors[0].key,
                      errors[0].reason);
  }
  return o;
}

gw::Users ServeUsers(const GatewayServeArgs& a) {
  try {
    return gw::ReadUsers(a.users);
  } catch (const gw::UsersError& e) {
    throw ConfigError("command line", "--users", e.what());
  }
}

std::unique_ptr<gw::Gateway> MakeGateway(const gw::GatewayOptions& o, const gw::Users& users,
                                         tm::Transport& transport) {
  try {
    auto gateway = std::make_unique<gw::Gateway>(o, users, transport);
    if (!gateway->certificate_warning().empty()) {
      std::cerr << "plantscale: warning: --cert: " << gateway->certificate_warning() << '\n';
    }
    return gateway;
  } catch (const gw::GatewayError& e) {
    // A certificate or key that cannot be used is bad input; an address
    // that cannot be bound is not.
    const std::string what = e.what();
    if (what.rfind("cannot listen", 0) == 0) throw;
    throw ConfigError("command line", what.rfind("key", 0) == 0 ? "--key" : "--cert", what);
  }
}

int RunGateway(const GatewayArgs& a) {
  const GatewayServeArgs serve{a.listen, a.cert, a.key, a.users, a.insecure_loopback, a.max_clients};
  const gw::GatewayOptions o = ServeOptions(serve, "--listen");
  const gw::Users users = ServeUsers(serve);
  tm::LcmTransport lcm(a.lcm_url);  // TransportError: exit 1 naming the URL
  std::unique_ptr<gw::Gateway> gateway = MakeGateway(o, users, lcm);
  gateway->Start();
  const std::string scheme = a.insecure_loopback ? "ws" : "wss";
  std::cout << "gateway: " << scheme << "://" << o.host << ":" << gateway->port() << "/ for "
            << users.users.size() << " users of " << a.users << ", LCM " << a.lcm_url
            << "; connect with " << scheme << "://HOST:" << gateway->port() << "/?token=TOKEN"
            << std::endl;
  if (a.insecure_loopback) {
    std::cerr
        << "plantscale: warning: --insecure-loopback: plain ws:// (no TLS) on 127.0.0.1 only\n";
  }
  g_stop = false;
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);
  gw::RunTransportLoop(lcm, *gateway, g_stop);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  gateway->Stop();
  std::cout << "gateway: stopped; " << GatewayStatsText(gateway->stats()) << '\n';
  return 0;
}

int RunUsersAdd(const UsersAddArgs& a) {
  const auto role = gw::ParseRole(a.role);
  if (!role)
    throw ConfigError("command line", "--role",
                      "must be viewer or operator (got '" + a.role + "')");
  std::string token;
  try {
    token = gw::AddUser(a.users, a.name, *role, a.replace);
  } catch (const gw::UsersWriteError&) {
    throw;  // I/O: exit 1 naming the file
  } catch (const gw::UsersError& e) {
    throw ConfigError("command line", "--users", e.what());
  }
  std::cout << "users: " << (a.replace ? "set" : "added") << " " << a.name << " ("
            << gw::RoleName(*role) << ") in " << a.users
            << " (mode 0600, only a salted hash of the token is kept).\n"
            << "Give the token below to " << a.name
            << " (wss://HOST:PORT/?token=TOKEN); it is shown this once:\n"
            << token << "\n";
  return 0;
}

}  // namespace

std::string GatewayStatsText(const gw::GatewayStats& s) {
  std::ostringstream out;
  out << s.connections << " connections, " << s.refused << " refused (" << s.refusal_events
      << " refusal events), " << s.lcm_messages << " LCM messages (" << s.lcm_rejected
      << " rejected), " << s.commands_forwarded << " commands forwarded, " << s.commands_refused
      << " refused, " << s.protocol_errors << " protocol errors, dropped "
      << s.dropped_thumbnails << " thumbnails and " << s.dropped_detail << " detail messages, "
      << s.slow_clients_closed << " slow clients closed, " << s.shed
      << " connections shed at accept (too many pending handshakes)";
  return out.str();
}

BackgroundGateway::BackgroundGateway(const GatewayServeArgs& args, const std::string& lcm_url) {
  if (lcm_url.rfind("memq://", 0) == 0) {
    throw ConfigError("command line", "--gateway",
                      "needs a udpm:// LCM URL: memq:// stays inside one LCM instance");
  }
  if (args.users.empty()) throw ConfigError("command line", "--users", "required with --gateway");
  const gw::GatewayOptions o = ServeOptions(args, "--gateway");
  const gw::Users users = ServeUsers(args);
  lcm_ = std::make_unique<tm::LcmTransport>(lcm_url);
  gateway_ = MakeGateway(o, users, *lcm_);
  scheme_ = args.insecure_loopback ? "ws" : "wss";
  host_ = o.host;
  gateway_->Start();
  loop_ = std::thread([this] {
    try {
      gw::RunTransportLoop(*lcm_, *gateway_, stop_);
    } catch (const std::exception& e) {
      std::cerr << "plantscale: gateway: " << e.what() << '\n';
    }
  });
}

BackgroundGateway::~BackgroundGateway() {
  if (!stopped_) Stop();
}

std::string BackgroundGateway::address() const {
  return scheme_ + "://" + host_ + ":" + std::to_string(gateway_->port()) + "/";
}

gw::GatewayStats BackgroundGateway::Stop() {
  if (!stopped_) {
    stopped_ = true;
    stop_ = true;
    if (loop_.joinable()) loop_.join();
    gateway_->Stop();
  }
  return gateway_->stats();
}

void AddVehicleGatewayOptions(CLI::App* cmd, GatewayServeArgs& a) {
  cmd->option_defaults()->group("Remote gateway");
  cmd->add_option("--gateway", a.listen,
                  "also serve the run over wss:// on HOST:PORT from this process (Foxglove, "
                  "Lichtblick, the station; docs/remote.md); needs a udpm:// LCM URL");
  cmd->add_option("--cert", a.cert, "with --gateway: TLS certificate chain, PEM");
  cmd->add_option("--key", a.key, "with --gateway: the certificate's private key, PEM");
  cmd->add_option("--users", a.users, "with --gateway: users file (plantscale users add)");
  cmd->option_defaults()->group("Options");
}

void AddGatewayCommands(CommandRegistry& registry) {
  GatewayArgs& g = registry.Keep(GatewayArgs{});
  CLI::App* gateway = registry.Add(
      "gateway",
      "serve the vehicle's LCM channels over wss:// to Foxglove, Lichtblick and the station",
      [&g] { return RunGateway(g); });
  gateway->add_option("--lcm-url", g.lcm_url, "LCM URL of the vehicle's channels")
      ->capture_default_str();
  gateway
      ->add_option("--listen", g.listen, "HOST:PORT to listen on (0.0.0.0:PORT: every interface)")
      ->capture_default_str();
  gateway->add_option("--cert", g.cert, "TLS certificate chain, PEM (docs/remote.md: openssl req)");
  gateway->add_option("--key", g.key, "the certificate's private key, PEM");
  gateway->add_option("--users", g.users, "users file (plantscale users add), mode 0600")
      ->required();
  gateway->add_flag(
      "--insecure-loopback", g.insecure_loopback,
      "plain ws:// without TLS, only with --listen 127.0.0.1:PORT (tests, a local tunnel)");
  gateway->add_option("--max-clients", g.max_clients, "connections at once; more are refused (503)")
      ->capture_default_str();

  CLI::App* users = registry.Add("users", "the users file of the gateway", nullptr);
  users->require_subcommand(1);
  UsersAddArgs& u = registry.Keep(UsersAddArgs{});
  CLI::App* add = registry.Add(
      "add",
      "add a user with a new token (printed once, alone on the last line); stores only its hash",
      [&u] { return RunUsersAdd(u); }, users);
  add->add_option("NAME", u.name, "user name (1-64 of A-Z a-z 0-9 . _ @ -)")->required();
  add->add_option("--role", u.role, "viewer (sees) or operator (may also send commands)")
      ->required();
  add->add_option("--users", u.users, "users file (created with mode 0600 when missing)")
      ->required();
  add->add_flag("--replace", u.replace,
                "give an existing user a new token (the old one stops working)");
}

}  // namespace plantscale::app
