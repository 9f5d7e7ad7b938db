#include "telemetry/gateway/client.h"

#include <openssl/ssl.h>
#include <openssl/x509v3.h>

#include <utility>  // before Boost.Asio, whose awaitable.hpp needs std::exchange

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <ctime>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <plantscale_lcmtypes/plantscale_command_t.hpp>
#include <thread>
#include <type_traits>

#include "telemetry/channels.h"
#include "telemetry/gateway/client_protocol.h"
#include "telemetry/gateway/foxglove_convert.h"
#include "telemetry/gateway/lcm_topics.h"
#include "telemetry/transport.h"

namespace plantscale::telemetry::gateway {

namespace asio = boost::asio;
namespace ssl = boost::asio::ssl;
namespace beast = boost::beast;
namespace http = boost::beast::http;
namespace websocket = boost::beast::websocket;
using tcp = boost::asio::ip::tcp;
using Clock = std::chrono::steady_clock;

namespace {

constexpr uint32_t kCommandChannelId = 1;  // the client channel the station advertises

// "2026-12-06 20:10:00 UTC".
std::string Asn1TimeText(const ASN1_TIME* t) {
  std::tm tm{};
  if (t == nullptr || ASN1_TIME_to_tm(t, &tm) != 1) return "?";
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return text;
}

// The names a certificate is for: "DNS:vehicle.farm.lan, IP:10.0.0.7", or
// its subject's CN when it has no subjectAltName (which a client checking
// a name does not accept).
std::string CertificateNames(X509* cert) {
  std::string names;
  auto* sans = static_cast<GENERAL_NAMES*>(X509_get_ext_d2i(cert, NID_subject_alt_name, nullptr, nullptr));
  for (int i = 0; sans != nullptr && i < sk_GENERAL_NAME_num(sans); ++i) {
    const GENERAL_NAME* n = sk_GENERAL_NAME_value(sans, i);
    std::string one;
    if (n->type == GEN_DNS) {
      one = "DNS:" + std::string(reinterpret_cast<const char*>(ASN1_STRING_get0_data(n->d.dNSName)),
                                 static_cast<size_t>(ASN1_STRING_length(n->d.dNSName)));
    } else if (n->type == GEN_IPADD) {
      const unsigned char* a = ASN1_STRING_get0_data(n->d.iPAddress);
      const int len = ASN1_STRING_length(n->d.iPAddress);
      boost::system::error_code ec;
      if (len == 4) {
        one = "IP:" + asio::ip::address_v4({a[0], a[1], a[2], a[3]}).to_string(ec);
      } else if (len == 16) {
        asio::ip::address_v6::bytes_type b;
        std::copy(a, a + 16, b.begin());
        one = "IP:" + asio::ip::address_v6(b).to_string(ec);
      }
    }
    if (!one.empty()) names += (names.empty() ? "" : ", ") + one;
  }
  GENERAL_NAMES_free(sans);
  if (!names.empty()) return names;
  char cn[256] = "";
  X509_NAME_get_text_by_NID(X509_get_subject_name(cert), NID_commonName, cn, sizeof cn);
  return std::string("no subjectAltName, only CN=") + cn;
}

// The first certificate check that failed in a TLS handshake: what the
// verify callback saw, for a message that says which certificate and why.
struct VerifyFailure {
  int error = X509_V_OK;
  int depth = 0;
  std::string subject;     // one line, e.g. "CN=127.0.0.1"
  std::string not_before;  // UTC
  std::string not_after;
  std::string names;  // subjectAltName
};

// Why the gateway's certificate was refused, in words: expired, not yet
// valid, not for this host or address, or not trusted (signed by a CA not
// given). `ca_file` empty: the system's roots.
std::string CertificateRefusal(const VerifyFailure& f, const std::string& host, const std::string& ca_file) {
  const std::string which = f.depth == 0 ? "the gateway's certificate (" + f.subject + ")"
                                         : "the certificate at depth " + std::to_string(f.depth) +
                                               " of the gateway's chain (" + f.subject + ")";
  switch (f.error) {
    case X509_V_ERR_CERT_HAS_EXPIRED:
      return which + " has expired: not valid after " + f.not_after +
             " (renew it: docs/remote.md, \"A certificate\"; or check this computer's clock)";
    case X509_V_ERR_CERT_NOT_YET_VALID:
      return which + " is not yet valid: not before " + f.not_before + " (check this computer's and the vehicle's clocks)";
    case X509_V_ERR_HOSTNAME_MISMATCH:
      return which + " is not for host '" + host + "': it names " + f.names +
             " (connect with a name it names, or give the gateway a certificate for this one)";
    case X509_V_ERR_IP_ADDRESS_MISMATCH:
      return which + " is not for address " + host + ": it names " + f.names +
             " (connect with a name or address it names, or give the gateway a certificate for this one)";
    default:
      return std::string("the gateway's certificate is not trusted: ") + X509_verify_cert_error_string(f.error) +
             " (" + which + "; " +
             (ca_file.empty() ? "give its certificate or CA with --ca)" : "checked against --ca " + ca_file + ")");
  }
}

}  // namespace

// One connection: resolve, TCP, TLS, upgrade, subscribe, read until it
// fails. Network thread only.
class Connection : public std::enable_shared_from_this<Connection> {
 public:
  virtual ~Connection() = default;
  virtual void Begin() = 0;
  virtual void Send(std::string frame, bool binary) = 0;
  virtual void Close() = 0;
};

struct GatewayClient::Impl {
  GatewayClientOptions options;
  OnMessage on_message;
  asio::io_context ioc{1};
  std::optional<ssl::context> tls;
  asio::steady_timer retry{ioc};
  std::optional<asio::executor_work_guard<asio::io_context::executor_type>> work;
  std::shared_ptr<Connection> current;  // network thread only
  int generation = 0;                   // of `current`
  std::thread thread;

  mutable std::mutex mutex;  // guards what follows
  std::condition_variable changed;
  GatewayLinkStatus status;
  Clock::time_point next_attempt{};

  void Connect();
  // The connection of `gen` ended: why, and whether a retry can mend it.
  void Ended(int gen, const std::string& why, bool fatal);
  void Update(const std::function<void(GatewayLinkStatus&)>& change) {
    {
      std::lock_guard lock(mutex);
      change(status);
    }
    changed.notify_all();
  }
};

namespace {

template <typename Next>
class ConnectionT : public Connection {
 public:
  ConnectionT(GatewayClient::Impl& client, int generation, websocket::stream<Next>&& ws)
      : client_(client), generation_(generation), resolver_(client.ioc), ws_(std::move(ws)) {}

  void Begin() override {
    const GatewayUrl& u = client_.options.url;
    beast::get_lowest_layer(ws_).expires_after(Timeout());
    resolver_.async_resolve(u.host, std::to_string(u.port),
                            [self = Self()](beast::error_code ec, tcp::resolver::results_type r) {
                              if (ec) return self->Fail("cannot resolve " + self->client_.options.url.host + ": " + ec.message());
                              self->OnResolve(r);
                            });
  }

  void Send(std::string frame, bool binary) override {
    if (!open_) return;
    out_.push_back({std::move(frame), binary});
    Write();
  }

  void Close() override {
    done_ = true;
    open_ = false;
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

 private:
  static constexpr bool kTls = std::is_same_v<Next, beast::ssl_stream<beast::tcp_stream>>;

  std::shared_ptr<ConnectionT> Self() { return std::static_pointer_cast<ConnectionT>(shared_from_this()); }
  std::chrono::steady_clock::duration Timeout() const {
    return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(client_.options.connect_timeout_s));
  }

  void Fail(const std::string& why, bool fatal = false) {
    if (done_) return;
    Close();
    client_.Ended(generation_, why, fatal);
  }

  void OnResolve(const tcp::resolver::results_type& results) {
    beast::get_lowest_layer(ws_).expires_after(Timeout());
    beast::get_lowest_layer(ws_).async_connect(
        results, [self = Self()](beast::error_code ec, const tcp::endpoint&) {
          if (ec) return self->Fail(ec == beast::error::timeout ? "TCP connect timed out" : ec.message());
          self->OnConnect();
        });
  }

  void OnConnect() {
    // No Nagle: on a link of 300 ms round trip it held each small write
    // (a handshake's, a pong, a command) for an acknowledgement.
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().set_option(tcp::no_delay(true), ignored);
    if constexpr (kTls) {
      const std::string& host = client_.options.url.host;
      SSL* ssl = ws_.next_layer().native_handle();
      boost::system::error_code ec;
      asio::ip::make_address(host, ec);
      if (ec) {  // a name: SNI, and the certificate must name it
        SSL_ctrl(ssl, SSL_CTRL_SET_TLSEXT_HOSTNAME, TLSEXT_NAMETYPE_host_name,
               const_cast<char*>(host.c_str()));  // SSL_set_tlsext_host_name, without its C cast
        SSL_set1_host(ssl, host.c_str());
      } else {   // an address: the certificate must list it (subjectAltName IP)
        X509_VERIFY_PARAM_set1_ip_asc(SSL_get0_param(ssl), host.c_str());
      }
      ws_.next_layer().set_verify_callback([this](bool preverified, ssl::verify_context& ctx) {
        X509_STORE_CTX* store = ctx.native_handle();
        if (!preverified && failure_.error == X509_V_OK) {
          failure_.error = X509_STORE_CTX_get_error(store);
          failure_.depth = X509_STORE_CTX_get_error_depth(store);
          if (X509* cert = X509_STORE_CTX_get_current_cert(store)) {
            char subject[512] = "";
            X509_NAME_oneline(X509_get_subject_name(cert), subject, sizeof subject);
            failure_.subject = subject[0] == '/' ? subject + 1 : subject;
            failure_.not_before = Asn1TimeText(X509_get0_notBefore(cert));
            failure_.not_after = Asn1TimeText(X509_get0_notAfter(cert));
            failure_.names = CertificateNames(cert);
          }
        }
        return preverified;
      });
      beast::get_lowest_layer(ws_).expires_after(Timeout());
      ws_.next_layer().async_handshake(ssl::stream_base::client,
                                       [self = Self()](beast::error_code e) { self->OnTls(e); });
    } else {
      Upgrade();
    }
  }

  void OnTls(beast::error_code ec) {
    if constexpr (kTls) {
      if (!ec) return Upgrade();
      const long verify = SSL_get_verify_result(ws_.next_layer().native_handle());
      if (verify != X509_V_OK) {
        if (failure_.error == X509_V_OK) failure_.error = static_cast<int>(verify);
        return Fail(CertificateRefusal(failure_, client_.options.url.host, client_.options.ca_file.string()), true);
      }
      Fail(ec == beast::error::timeout ? "TLS handshake timed out" : "TLS handshake failed: " + ec.message());
    }
  }

  void Upgrade() {
    beast::get_lowest_layer(ws_).expires_never();
    websocket::stream_base::timeout t;
    t.handshake_timeout = Timeout();
    t.idle_timeout = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(client_.options.idle_timeout_s));
    t.keep_alive_pings = true;
    ws_.set_option(t);
    ws_.read_message_max(client_.options.max_message_bytes);
    const std::string token = client_.options.token;
    ws_.set_option(websocket::stream_base::decorator([token](websocket::request_type& req) {
      req.set(http::field::sec_websocket_protocol, kSubprotocol);
      req.set(http::field::authorization, "Bearer " + token);
      req.set(http::field::user_agent, "plantscale-station");
    }));
    const GatewayUrl& u = client_.options.url;
    std::string target = u.target;
    target += (target.find('?') == std::string::npos ? "?" : "&");
    target += "lcm=1";
    ws_.async_handshake(response_, u.host + ":" + std::to_string(u.port), target,
                        [self = Self()](beast::error_code ec) { self->OnUpgrade(ec); });
  }

  void OnUpgrade(beast::error_code ec) {
    const unsigned code = response_.result_int();
    if (ec && code == 401) {
      std::string body = response_.body();
      body = body.substr(0, body.find('\n'));
      return Fail("the gateway refused the token (HTTP 401: " + body + ")", true);
    }
    if (ec && code != 0 && code != 101) {
      return Fail("not a plantscale gateway: HTTP " + std::to_string(code) + " " + std::string(response_.reason()) +
                      " to the WebSocket upgrade",
                  true);
    }
    if (ec) return Fail(ec == beast::error::timeout ? "WebSocket handshake timed out" : ec.message());
    const auto protocol = response_[http::field::sec_websocket_protocol];
    if (std::string_view(protocol.data(), protocol.size()) != kSubprotocol) {
      return Fail(std::string("not a Foxglove gateway (no subprotocol ") + kSubprotocol + ")", true);
    }
    open_ = true;
    Read();
  }

  void Read() {
    ws_.async_read(buffer_, [self = Self()](beast::error_code ec, size_t) {
      if (ec) {
        const std::string why = ec == beast::error::timeout ? "no data or ping reply for " +
                                                                  SecondsText(self->client_.options.idle_timeout_s)
                                                            : ec.message();
        return self->Fail("link lost: " + why);
      }
      const std::string data = beast::buffers_to_string(self->buffer_.data());
      self->buffer_.consume(self->buffer_.size());
      if (self->ws_.got_text()) {
        self->OnText(data);
      } else {
        self->OnBinary(data);
      }
      if (self->open_) self->Read();
    });
  }

  void OnText(const std::string& text) {
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (!j.is_object() || !j.contains("op") || !j["op"].is_string()) return;
    const std::string op = j["op"].get<std::string>();
    if (op == "serverInfo") return OnServerInfo(j);
    if (op == "advertise") return OnAdvertise(j);
    if (op == "status" && j.contains("message") && j["message"].is_string()) {
      const std::string message = j["message"].get<std::string>();
      client_.Update([&](GatewayLinkStatus& s) { s.last_status = message; });
    }
  }

  void OnServerInfo(const nlohmann::json& j) {
    const nlohmann::json meta = j.value("metadata", nlohmann::json::object());
    const std::string user = meta.is_object() ? meta.value("user", "") : "";
    const std::string role = meta.is_object() ? meta.value("role", "") : "";
    bool publish = false;
    if (j.contains("capabilities") && j["capabilities"].is_array()) {
      for (const auto& c : j["capabilities"]) publish = publish || c == "clientPublish";
    }
    operator_ = publish;
    client_.Update([&](GatewayLinkStatus& s) {
      s.user = user;
      s.role = role.empty() ? (publish ? "operator" : "viewer") : role;
      s.operator_role = publish;
    });
  }

  void OnAdvertise(const nlohmann::json& j) {
    if (!j.contains("channels") || !j["channels"].is_array()) return;
    nlohmann::json subscriptions = nlohmann::json::array();
    for (const auto& c : j["channels"]) {
      if (!c.is_object() || c.value("encoding", "") != kLcmEncoding) continue;
      const std::string topic = c.value("topic", "");
      const int index = LcmTopicIndex(topic);
      if (index < 0 || !c.contains("id") || !c["id"].is_number_unsigned()) continue;
      const LcmTopic& mine = LcmTopics()[static_cast<size_t>(index)];
      if (c.value("schemaName", "") != mine.type_name || c.value("schema", "") != FingerprintHex(mine.fingerprint)) {
        return Fail("the gateway's " + topic + " is " + c.value("schemaName", "?") + " " + c.value("schema", "?") +
                        ", this station's " + mine.type_name + " " + FingerprintHex(mine.fingerprint) +
                        ": the station and the vehicle are of different plantscale versions",
                    true);
      }
      const uint32_t id = c["id"].get<uint32_t>();
      channels_[id] = topic;
      subscriptions.push_back({{"id", id}, {"channelId", id}});
    }
    if (subscriptions.empty()) return;  // the JSON topics' advertisement
    // The odometry and poses first: the gateway sends each channel's latest
    // message in the order subscribed, and the run model places a grid
    // state at the distance driven by its time, so after a cut the latest
    // odometry must come before the latest grid (else the grid is drawn at
    // the distance before the cut).
    std::stable_partition(subscriptions.begin(), subscriptions.end(), [&](const nlohmann::json& s) {
      const std::string& ch = channels_[s["id"].get<uint32_t>()];
      return ch == channels::kOdometry || ch == channels::kPose || ch == channels::kSimTruthPose;
    });
    Send(nlohmann::json{{"op", "subscribe"}, {"subscriptions", subscriptions}}.dump(), false);
    if (operator_) {
      const nlohmann::json command = {{"id", kCommandChannelId},
                                      {"topic", channels::kCommand},
                                      {"encoding", "json"},
                                      {"schemaName", "plantscale.Command"}};
      Send(nlohmann::json{{"op", "advertise"}, {"channels", {command}}}.dump(), false);
    }
    client_.Update([&](GatewayLinkStatus& s) {
      s.state = LinkState::kConnected;
      ++s.connections;
      s.failures = 0;
      s.last_error.clear();
    });
  }

  void OnBinary(const std::string& data) {
    // Message data: opcode 0x01, uint32 subscription id, uint64 ns, payload.
    if (data.size() < 13 || static_cast<uint8_t>(data[0]) != 0x01) return;
    uint32_t id = 0;
    for (int i = 0; i < 4; ++i) id |= uint32_t{static_cast<uint8_t>(data[1 + static_cast<size_t>(i)])} << (8 * i);
    const auto it = channels_.find(id);
    if (it == channels_.end()) return;
    client_.on_message(it->second, data.data() + 13, data.size() - 13, WallUtime());
    std::lock_guard lock(client_.mutex);
    ++client_.status.messages;
    client_.status.bytes += static_cast<int64_t>(data.size());
  }

  void Write() {
    if (writing_ || out_.empty() || !open_) return;
    writing_ = true;
    current_ = std::move(out_.front());
    out_.pop_front();
    ws_.binary(current_.second);
    ws_.async_write(asio::buffer(current_.first), [self = Self()](beast::error_code ec, size_t) {
      self->writing_ = false;
      if (ec) return self->Fail("link lost: " + ec.message());
      self->Write();
    });
  }

  GatewayClient::Impl& client_;
  int generation_;
  tcp::resolver resolver_;
  websocket::stream<Next> ws_;
  websocket::response_type response_;
  VerifyFailure failure_;  // the TLS handshake's first failed certificate check
  beast::flat_buffer buffer_;
  std::map<uint32_t, std::string> channels_;  // subscription id (= channel id) → LCM channel
  std::deque<std::pair<std::string, bool>> out_;
  std::pair<std::string, bool> current_;
  bool operator_ = false;
  bool open_ = false;
  bool done_ = false;
  bool writing_ = false;
};

}  // namespace

void GatewayClient::Impl::Connect() {
  ++generation;
  Update([](GatewayLinkStatus& s) { s.state = LinkState::kConnecting; });
  if (tls) {
    current = std::make_shared<ConnectionT<beast::ssl_stream<beast::tcp_stream>>>(
        *this, generation, websocket::stream<beast::ssl_stream<beast::tcp_stream>>(ioc, *tls));
  } else {
    current = std::make_shared<ConnectionT<beast::tcp_stream>>(*this, generation,
                                                               websocket::stream<beast::tcp_stream>(ioc));
  }
  current->Begin();
}

void GatewayClient::Impl::Ended(int gen, const std::string& why, bool fatal) {
  if (gen != generation) return;
  current.reset();
  double delay = 0.0;
  Update([&](GatewayLinkStatus& s) {
    s.last_error = why;
    if (fatal) {
      s.state = LinkState::kRefused;
      return;
    }
    ++s.failures;
    delay = options.reconnect.DelayS(s.failures);
    s.state = LinkState::kWaiting;
    next_attempt = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(delay));
  });
  if (fatal) return;
  retry.expires_after(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(delay)));
  retry.async_wait([this](beast::error_code ec) {
    if (!ec) Connect();
  });
}

GatewayClient::GatewayClient(const GatewayClientOptions& options, OnMessage on_message)
    : impl_(std::make_shared<Impl>()) {
  ThrowIfInvalid("gateway client", options.Validate());
  Impl& d = *impl_;
  d.options = options;
  d.on_message = std::move(on_message);
  d.status.url = options.url.text;
  if (options.url.tls) {
    d.tls.emplace(ssl::context::tls_client);
    d.tls->set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 | ssl::context::no_sslv3 |
                       ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1);
    d.tls->set_verify_mode(ssl::verify_peer);
    boost::system::error_code ec;
    if (options.ca_file.empty()) {
      d.tls->set_default_verify_paths(ec);
    } else {
      if (!std::ifstream(options.ca_file).good()) {
        throw GatewayClientError("--ca " + options.ca_file.string() + ": cannot be read");
      }
      d.tls->load_verify_file(options.ca_file.string(), ec);
      if (ec) throw GatewayClientError("--ca " + options.ca_file.string() + ": not a PEM certificate (" + ec.message() + ")");
    }
  }
  d.work.emplace(asio::make_work_guard(d.ioc));
  asio::post(d.ioc, [&d] { d.Connect(); });
  d.thread = std::thread([&d] { d.ioc.run(); });
}

GatewayClient::~GatewayClient() {
  Impl& d = *impl_;
  asio::post(d.ioc, [&d] {
    ++d.generation;  // a failing connection no longer schedules a retry
    d.retry.cancel();
    if (d.current) d.current->Close();
    d.current.reset();
    d.work.reset();
    d.ioc.stop();
  });
  d.thread.join();
}

void GatewayClient::WaitFirstAttempt(double timeout_s) {
  Impl& d = *impl_;
  std::unique_lock lock(d.mutex);
  d.changed.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] {
    return d.status.state == LinkState::kConnected || d.status.state == LinkState::kRefused;
  });
  if (d.status.state == LinkState::kRefused) throw GatewayClientError(d.status.url + ": " + d.status.last_error);
}

GatewayLinkStatus GatewayClient::status() const {
  std::lock_guard lock(impl_->mutex);
  GatewayLinkStatus s = impl_->status;
  if (s.state == LinkState::kWaiting) {
    s.retry_in_s = std::max(0.0, std::chrono::duration<double>(impl_->next_attempt - Clock::now()).count());
  }
  return s;
}

std::string GatewayClient::PublishCommand(const plantscale_command_t& command) {
  Impl& d = *impl_;
  {
    std::lock_guard lock(d.mutex);
    if (d.status.state != LinkState::kConnected) return "not sent: not connected to the gateway";
    if (!d.status.operator_role) {
      return "refused: " + d.status.user + " has role " + d.status.role + " at the gateway; only an operator may command";
    }
    ++d.status.commands_sent;
  }
  std::string frame(5, '\0');
  frame[0] = 0x01;
  for (int i = 0; i < 4; ++i) frame[1 + static_cast<size_t>(i)] = static_cast<char>((kCommandChannelId >> (8 * i)) & 0xff);
  frame += CommandJson(command).dump();
  asio::post(d.ioc, [&d, frame = std::move(frame)]() mutable {
    if (d.current) d.current->Send(std::move(frame), true);
  });
  return "sent";
}

}  // namespace plantscale::telemetry::gateway
