#include "telemetry/gateway/server.h"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/ssl.h>

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <algorithm>
#include <chrono>
#include <ctime>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <set>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/gateway/foxglove_convert.h"
#include "telemetry/gateway/lcm_topics.h"

namespace plantscale::telemetry::gateway {

namespace asio = boost::asio;
namespace ssl = boost::asio::ssl;
namespace beast = boost::beast;
namespace http = boost::beast::http;
namespace websocket = boost::beast::websocket;
using tcp = boost::asio::ip::tcp;

namespace {
// Pending connections (TLS handshake or upgrade) one address may hold: a
// quarter of max_pending, so that a flood from one host cannot keep others
// out (results/2026-12-07-gateway-abuse.md).
int MaxPendingPerAddress(const GatewayOptions& o) { return std::max(1, o.max_pending / 4); }
}  // namespace

OptionErrors GatewayOptions::Validate() const {
  OptionErrors e;
  boost::system::error_code ec;
  asio::ip::make_address(host, ec);
  if (ec) e.push_back({"host", "must be an IP address (got '" + host + "')"});
  if (port < 0 || port > 65535)
    e.push_back({"port", "must be 0-65535 (got " + std::to_string(port) + ")"});
  if (insecure_loopback) {
    if (host != "127.0.0.1") {
      e.push_back({"insecure_loopback", "plain ws:// only on 127.0.0.1 (got host " + host + ")"});
    }
  } else {
    if (cert_file.empty()) e.push_back({"cert_file", "required (TLS is always on)"});
    if (key_file.empty()) e.push_back({"key_file", "required (TLS is always on)"});
  }
  if (max_clients < 1) e.push_back({"max_clients", "must be >= 1"});
  if (max_pending < 1) e.push_back({"max_pending", "must be >= 1"});
  if (handshake_timeout_s < 1) e.push_back({"handshake_timeout_s", "must be >= 1"});
  if (limits.max_message_bytes < 64) e.push_back({"limits.max_message_bytes", "must be >= 64"});
  if (refusal_burst < 1) e.push_back({"refusal_burst", "must be >= 1"});
  if (refusal_interval_us < 1) e.push_back({"refusal_interval_us", "must be >= 1"});
  if (grid_scene_interval_us < 0) e.push_back({"grid_scene_interval_us", "must be >= 0"});
  if (max_unsent_bytes < 1024) e.push_back({"max_unsent_bytes", "must be >= 1024"});
  if (!(stop_drain_s >= 0.0 && stop_drain_s <= 60.0)) {
    e.push_back({"stop_drain_s", "must be 0-60 s"});
  }
  for (auto& x : Prefixed("queue", queue.Validate())) e.push_back(std::move(x));
  return e;
}

namespace {

// What every session gets from its gateway (network thread only).
struct Hub;

class Session : public std::enable_shared_from_this<Session> {
 public:
  virtual ~Session() = default;
  virtual void Begin() = 0;
  virtual void Deliver(int topic, int64_t utime,
                       const std::shared_ptr<const std::string>& json) = 0;
  virtual void Abort() = 0;
  // The gateway is stopping: send what is queued, then close the WebSocket.
  virtual void Drain() = 0;
};

struct CachedMessage {
  int64_t utime = 0;
  std::shared_ptr<const std::string> json;  // or, on an LCM topic, the message's bytes
};

// The topics a session may subscribe to: Topics() (JSON), then LcmTopics()
// (the LCM bytes as they are) at index Topics().size() + i.
size_t TopicCount() { return Topics().size() + LcmTopics().size(); }
bool IsLcmTopic(int topic) { return topic >= static_cast<int>(Topics().size()); }
const LcmTopic& LcmTopicAt(int topic) {
  return LcmTopics()[static_cast<size_t>(topic) - Topics().size()];
}
TopicClass DropClassOf(int topic) {
  return IsLcmTopic(topic) ? LcmTopicAt(topic).drop_class
                           : Topics()[static_cast<size_t>(topic)].drop_class;
}
const std::string& ChannelOf(int topic) {
  return IsLcmTopic(topic) ? LcmTopicAt(topic).channel
                           : Topics()[static_cast<size_t>(topic)].lcm_channel;
}

}  // namespace

struct Gateway::Impl {
  GatewayOptions options;
  Users users;
  Transport& transport;
  asio::io_context ioc{1};
  std::optional<ssl::context> tls;
  tcp::acceptor acceptor{ioc};
  asio::steady_timer flush_timer{ioc};
  asio::steady_timer drain_timer{ioc};
  std::thread thread;
  std::string session_id = std::to_string(WallUtime());
  std::string certificate_warning;  // expired or not yet valid (constructor)

  // Network thread only.
  std::set<std::shared_ptr<Session>> sessions;  // from TCP accept to close
  std::map<asio::ip::address, int> pending_by_address;  // of those, before the upgrade
  int open_clients = 0;                         // of those, past the WebSocket upgrade
  std::vector<CachedMessage> latest;            // per topic
  std::map<std::pair<int, std::string>, CachedMessage> tiles;  // newest revision per topic and tile
  // Every plant's newest observation, as a plant_list_t of that one plant
  // (LCM bytes): sent to a client that subscribes to PLANTSCALE_PLANTS, so
  // that plants seen while its link was down reach it too.
  std::map<int64_t, CachedMessage> plants;
  size_t tile_bytes = 0;  // tiles' and plants' cached bytes (max_cached_tile_bytes)
  RefusalLimiter refusals;
  RefusalLimiter command_audit;

  int64_t last_scene_utime = INT64_MIN;  // transport thread only

  mutable std::mutex mutex;  // guards stats and outgoing
  GatewayStats stats;
  std::vector<std::pair<std::string, Bytes>> outgoing;
  int64_t event_seq = 0;

  Impl(const GatewayOptions& o, Users u, Transport& t)
      : options(o),
        users(std::move(u)),
        transport(t),
        refusals(o.refusal_burst, o.refusal_interval_us),
        command_audit(o.refusal_burst, o.refusal_interval_us) {}

  void Count(int64_t GatewayStats::*field, int64_t n = 1) {
    std::lock_guard lock(mutex);
    stats.*field += n;
  }
  void Publish(const std::string& channel, Bytes bytes) {
    std::lock_guard lock(mutex);
    outgoing.emplace_back(channel, std::move(bytes));
  }
  void Event(int8_t severity, const std::string& kind, const std::string& text) {
    plantscale_event_t e;
    e.utime = WallUtime();
    {
      std::lock_guard lock(mutex);
      e.seq = event_seq++;
    }
    e.severity = severity;
    e.kind = kind;
    e.text = text;
    Publish(channels::kGatewayEvents, Encode(e));
  }
  // A refused connection or command: counted, and an event unless held back.
  void Refuse(const std::string& text) {
    if (const auto line = refusals.Refused(WallUtime(), text)) {
      Count(&GatewayStats::refusal_events);
      Event(plantscale_event_t::SEVERITY_WARNING, "gateway_refused", *line);
    }
  }
  void Audit(const std::string& text) {
    if (const auto line = command_audit.Refused(WallUtime(), text)) {
      Event(plantscale_event_t::SEVERITY_INFO, "gateway_command", *line);
    }
  }
  void ScheduleFlush();
  // Stops the network thread once every session has closed or at `deadline`.
  void StopWhenDrained(std::chrono::steady_clock::time_point deadline);
  void Accept();
  void OnLcm(const ReceivedMessage& m);
  void Dispatch(const std::vector<Converted>& converted);
  void CachePlants(std::vector<std::pair<int64_t, CachedMessage>> updates);
};

namespace {

template <typename Stream>
class SessionT : public Session {
 public:
  SessionT(Gateway::Impl& hub, Stream&& stream, std::string remote, asio::ip::address address)
      : hub_(hub),
        ws_(std::move(stream)),
        remote_(std::move(remote)),
        address_(address),
        queue_(hub.options.queue) {
    ++hub_.pending_by_address[address_];
  }

  void Begin() override {
    beast::get_lowest_layer(ws_).expires_after(
        std::chrono::seconds(hub_.options.handshake_timeout_s));
    if constexpr (std::is_same_v<Stream, beast::ssl_stream<beast::tcp_stream>>) {
      ws_.next_layer().async_handshake(
          ssl::stream_base::server,
          [self = Self()](beast::error_code ec) { self->OnHandshake(ec); });
    } else {
      OnHandshake({});
    }
  }

  void Deliver(int topic, int64_t utime, const std::shared_ptr<const std::string>& json) override {
    const auto it = topic_subscription_.find(topic);
    if (it == topic_subscription_.end() || !open_) return;
    OutMessage m;
    m.drop = queue_.Classify(DropClassOf(topic), utime);
    m.binary = true;
    m.header =
        MessageDataHeader(it->second, static_cast<uint64_t>(std::max<int64_t>(utime, 0)) * 1000);
    m.payload = json;
    if (!queue_.Push(std::move(m))) {
      hub_.Count(&GatewayStats::slow_clients_closed);
      hub_.Event(plantscale_event_t::SEVERITY_WARNING, "gateway_slow_client",
                 "closed " + Who() + ": its link could not keep up with the essential channels (" +
                     std::to_string(queue_.bytes()) + " bytes queued)");
      Abort();
      return;
    }
    Write();
  }

  void Abort() override {
    open_ = false;
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

  void Drain() override {
    draining_ = true;
    if (!open_) {  // still in its handshake: nothing of the run was sent yet
      Abort();
      return End();
    }
    Write();
  }

 private:
  std::shared_ptr<SessionT> Self() {
    return std::static_pointer_cast<SessionT>(shared_from_this());
  }
  std::string Who() const {
    return (user_ ? user_->name + " (" + RoleName(user_->role) + ")" : "client") + " from " +
           remote_;
  }

  // Past the upgrade or closed: no longer one of its address's pending.
  void LeavePending() {
    if (!pending_) return;
    pending_ = false;
    const auto it = hub_.pending_by_address.find(address_);
    if (it != hub_.pending_by_address.end() && --it->second <= 0) hub_.pending_by_address.erase(it);
  }

  void End() {
    open_ = false;
    if (ended_) return;
    ended_ = true;
    LeavePending();
    if (accepted_) --hub_.open_clients;
    hub_.sessions.erase(shared_from_this());
    std::lock_guard lock(hub_.mutex);
    hub_.stats.clients = hub_.open_clients;
    hub_.stats.dropped_thumbnails += queue_.dropped(DropClass::kThumbnail) - reported_thumbnails_;
    hub_.stats.dropped_detail += queue_.dropped(DropClass::kDetail) - reported_detail_;
    reported_thumbnails_ = queue_.dropped(DropClass::kThumbnail);
    reported_detail_ = queue_.dropped(DropClass::kDetail);
  }

  void OnHandshake(beast::error_code ec) {
    if (ec) return End();  // not TLS, a bad certificate on the client's side, a timeout
    parser_.emplace();
    parser_->header_limit(8 * 1024);
    parser_->body_limit(0);
    http::async_read(ws_.next_layer(), buffer_, *parser_,
                     [self = Self()](beast::error_code e, size_t) { self->OnRequest(e); });
  }

  void OnRequest(beast::error_code ec) {
    if (ec) return End();
    request_ = parser_->release();
    lcm_ = QueryParameter(std::string_view(request_.target().data(), request_.target().size()),
                          "lcm") == "1";
    const std::string token =
        TokenFromRequest(std::string_view(request_.target().data(), request_.target().size()),
                         std::string_view(request_[http::field::authorization].data(),
                                          request_[http::field::authorization].size()));
    user_ = token.empty() ? nullptr : Authenticate(hub_.users, token);
    if (!user_) {
      const char* why = token.empty() ? "no token" : "unknown token";
      hub_.Count(&GatewayStats::refused);
      hub_.Refuse(std::string("refused a connection from ") + remote_ + ": " + why);
      return Reply(
          http::status::unauthorized,
          std::string(why) +
              ": connect with wss://HOST:PORT/?token=TOKEN or an Authorization: Bearer header");
    }
    if (!websocket::is_upgrade(request_)) {
      hub_.Count(&GatewayStats::refused);
      return Reply(http::status::upgrade_required,
                   "a Foxglove WebSocket gateway: open it in Foxglove or Lichtblick (subprotocol "
                   "foxglove.websocket.v1)");
    }
    const auto protocols = request_[http::field::sec_websocket_protocol];
    if (std::string_view(protocols.data(), protocols.size()).find(kSubprotocol) ==
        std::string_view::npos) {
      hub_.Count(&GatewayStats::refused);
      return Reply(http::status::bad_request,
                   std::string("subprotocol ") + kSubprotocol + " required");
    }
    if (hub_.open_clients >= hub_.options.max_clients) {
      hub_.Count(&GatewayStats::refused);
      hub_.Refuse("refused " + Who() + ": " + std::to_string(hub_.options.max_clients) +
                  " clients already");
      return Reply(http::status::service_unavailable, "too many clients");
    }
    beast::get_lowest_layer(ws_).expires_never();
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(hub_.options.limits.max_message_bytes);
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& res) {
      res.set(http::field::sec_websocket_protocol, kSubprotocol);
      res.set(http::field::server, "plantscale-gateway");
    }));
    ws_.async_accept(request_, [self = Self()](beast::error_code e) { self->OnAccept(e); });
  }

  void Reply(http::status status, const std::string& body) {
    response_.emplace(status, request_.version());
    response_->set(http::field::server, "plantscale-gateway");
    response_->set(http::field::content_type, "text/plain");
    if (status == http::status::unauthorized)
      response_->set(http::field::www_authenticate, "Bearer");
    response_->keep_alive(false);
    response_->body() = body + "\n";
    response_->prepare_payload();
    http::async_write(ws_.next_layer(), *response_, [self = Self()](beast::error_code, size_t) {
      self->Abort();
      self->End();
    });
  }

  void OnAccept(beast::error_code ec) {
    if (ec) return End();
    open_ = true;
    accepted_ = true;
    LeavePending();
    ++hub_.open_clients;
    {
      std::lock_guard lock(hub_.mutex);
      ++hub_.stats.connections;
      hub_.stats.clients = hub_.open_clients;
    }
    const bool op = user_->role == Role::kOperator;
    SendText(
        ServerInfo({hub_.options.name, hub_.session_id, op, user_->name, RoleName(user_->role)}));
    SendText(AdvertiseAll());
    if (lcm_) SendText(AdvertiseLcm());
    Read();
  }

  void SendText(std::string text) {
    OutMessage m;
    m.payload = std::make_shared<const std::string>(std::move(text));
    queue_.Push(std::move(m));
    Write();
  }
  void SendStatus(int level, const std::string& text) { SendText(Status(level, text)); }

  void Write() {
    if (writing_ || !open_ || closing_) return;
    while (queue_.empty() && !backlog_.empty()) {
      const Pending p = std::move(backlog_.front());
      backlog_.pop_front();
      if (auto m = Resolve(p)) queue_.Push(std::move(*m));
    }
    auto next = queue_.Pop();
    if (!next) {
      if (draining_) CloseWhenSent();
      return;
    }
    writing_ = true;
    current_ = std::move(*next);
    ws_.binary(current_.binary);
    const std::array<asio::const_buffer, 2> buffers{asio::buffer(current_.header),
                                                    asio::buffer(*current_.payload)};
    ws_.async_write(buffers, [self = Self()](beast::error_code ec, size_t) {
      self->writing_ = false;
      if (ec) {
        self->Abort();
        return self->End();
      }
      self->Write();
    });
  }

  // Everything queued was written: a WebSocket close, so that the client
  // reads all of it (a bare socket close may reset the connection and lose
  // what the kernel still held).
  void CloseWhenSent() {
    if (closing_) return;
    closing_ = true;
    ws_.async_close(websocket::close_code::going_away, [self = Self()](beast::error_code) {
      self->Abort();
      self->End();
    });
  }

  void Read() {
    ws_.async_read(read_buffer_,
                   [self = Self()](beast::error_code ec, size_t) { self->OnRead(ec); });
  }

  void OnRead(beast::error_code ec) {
    if (ec) {
      // Closed, reset, or a message over read_message_max.
      if (ec == websocket::error::message_too_big) {
        hub_.Count(&GatewayStats::protocol_errors);
        hub_.Refuse("closed " + Who() + ": a message over " +
                    std::to_string(hub_.options.limits.max_message_bytes) + " bytes");
      }
      Abort();
      return End();
    }
    const std::string data = beast::buffers_to_string(read_buffer_.data());
    read_buffer_.consume(read_buffer_.size());
    const ClientMessage message = ws_.got_text() ? ParseClientText(data, hub_.options.limits)
                                                 : ParseClientBinary(data, hub_.options.limits);
    std::visit([this](const auto& m) { Handle(m); }, message);
    if (open_) Read();
  }

  void Handle(const ProtocolError& e) {
    hub_.Count(&GatewayStats::protocol_errors);
    SendStatus(2, "refused: " + e.reason);
  }

  void Handle(const Subscribe& s) {
    for (const auto& item : s.subscriptions) {
      const int topic = static_cast<int>(item.channel_id) - 1;
      const int served = static_cast<int>(lcm_ ? TopicCount() : Topics().size());
      if (topic < 0 || topic >= served) {
        SendStatus(2, "no channel " + std::to_string(item.channel_id));
        continue;
      }
      if (subscription_topic_.count(item.id) || topic_subscription_.count(topic)) {
        SendStatus(2, "subscription " + std::to_string(item.id) + " or channel " +
                          std::to_string(item.channel_id) + " already subscribed");
        continue;
      }
      subscription_topic_[item.id] = topic;
      topic_subscription_[topic] = item.id;
      SendCached(topic, item.id);
    }
  }

  // A catch-up message waiting behind the live ones (backlog_).
  struct Pending {
    int topic;
    uint32_t subscription;
    std::string tile;   // a map tile's cache key, or
    int64_t plant = 0;  // a plant's id
  };

  OutMessage Cached(const CachedMessage& c, uint32_t subscription) const {
    OutMessage m;
    m.drop = DropClass::kEssential;
    m.binary = true;
    m.header = MessageDataHeader(subscription,
                                 static_cast<uint64_t>(std::max<int64_t>(c.utime, 0)) * 1000);
    m.payload = c.json;
    return m;
  }

  // The latest message of the topic now; for map tiles every tile's newest
  // revision and for plants every plant's newest observation, paced behind
  // the live messages (backlog_) and looked up when sent, so that what goes
  // is the newest then (a live message sent meanwhile is never undone).
  void SendCached(int topic, uint32_t subscription) {
    const std::string& channel = ChannelOf(topic);
    if (channel == channels::kMapTiles) {
      for (auto it = hub_.tiles.lower_bound({topic, std::string()});
           it != hub_.tiles.end() && it->first.first == topic; ++it) {
        backlog_.push_back({topic, subscription, it->first.second, 0});
      }
    } else if (hub_.latest[static_cast<size_t>(topic)].json) {
      queue_.Push(Cached(hub_.latest[static_cast<size_t>(topic)], subscription));
    }
    if (channel == channels::kPlants) {
      for (const auto& [id, cached] : hub_.plants) backlog_.push_back({topic, subscription, {}, id});
    }
    Write();
  }

  // A pending catch-up message as it is now: nothing when the client has
  // unsubscribed since or the entry is no longer cached.
  std::optional<OutMessage> Resolve(const Pending& p) const {
    const auto sub = topic_subscription_.find(p.topic);
    if (sub == topic_subscription_.end() || sub->second != p.subscription) return std::nullopt;
    if (!p.tile.empty()) {
      const auto it = hub_.tiles.find({p.topic, p.tile});
      if (it == hub_.tiles.end()) return std::nullopt;
      return Cached(it->second, p.subscription);
    }
    const auto it = hub_.plants.find(p.plant);
    if (it == hub_.plants.end()) return std::nullopt;
    if (IsLcmTopic(p.topic)) return Cached(it->second, p.subscription);
    // The JSON topic: the one plant's scene, converted now (only a client
    // catching up pays for it).
    std::string error;
    for (Converted& c :
         ConvertLcm(channels::kPlants, it->second.json->data(), it->second.json->size(), &error)) {
      if (c.topic != p.topic) continue;
      return Cached({c.utime, std::make_shared<const std::string>(std::move(c.json))},
                    p.subscription);
    }
    return std::nullopt;
  }

  void Handle(const Unsubscribe& u) {
    for (const uint32_t id : u.subscription_ids) {
      const auto it = subscription_topic_.find(id);
      if (it == subscription_topic_.end()) continue;
      topic_subscription_.erase(it->second);
      subscription_topic_.erase(it);
    }
  }

  void RefuseCommand(const std::string& why) {
    hub_.Count(&GatewayStats::commands_refused);
    hub_.Refuse("refused a command from " + Who() + ": " + why);
    SendStatus(2, "refused: " + why);
  }

  void Handle(const ClientAdvertise& a) {
    for (const auto& c : a.channels) {
      if (user_->role != Role::kOperator) {
        RefuseCommand("role viewer may not publish (topic " + c.topic.substr(0, 64) + ")");
      } else if (c.topic != channels::kCommand || c.encoding != "json") {
        RefuseCommand(std::string("only ") + channels::kCommand +
                      " with encoding json may be published");
      } else {
        client_channels_.insert(c.id);
      }
    }
  }

  void Handle(const ClientUnadvertise& u) {
    for (const uint32_t id : u.channel_ids) client_channels_.erase(id);
  }

  void Handle(const ClientMessageData& d) {
    if (user_->role != Role::kOperator) return RefuseCommand("role viewer may not publish");
    if (!client_channels_.count(d.channel_id)) {
      return RefuseCommand("client channel " + std::to_string(d.channel_id) +
                           " was not advertised");
    }
    const nlohmann::json j = nlohmann::json::parse(d.payload, nullptr, false);
    plantscale_command_t command;
    try {
      command = CommandFromJson(j);
    } catch (const DataError& e) {
      return RefuseCommand(e.what());
    }
    hub_.Publish(channels::kCommand, Encode(command));
    hub_.Count(&GatewayStats::commands_forwarded);
    hub_.Audit("forwarded command " + std::to_string(command.command) + " seq " +
               std::to_string(command.seq) + " from " + Who() +
               (command.mac_size ? " (signed)" : " (unsigned)"));
  }

  Gateway::Impl& hub_;
  websocket::stream<Stream> ws_;
  std::string remote_;
  asio::ip::address address_;
  bool pending_ = true;  // counted in hub_.pending_by_address
  ClientQueue queue_;
  std::deque<Pending> backlog_;
  beast::flat_buffer buffer_;
  beast::flat_buffer read_buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  http::request<http::empty_body> request_;
  std::optional<http::response<http::string_body>> response_;
  const User* user_ = nullptr;
  bool lcm_ = false;  // asked for the LCM topics (lcm=1)
  bool open_ = false;
  bool accepted_ = false;
  bool ended_ = false;
  bool writing_ = false;
  bool draining_ = false;  // the gateway is stopping (Drain)
  bool closing_ = false;   // the WebSocket close is under way
  OutMessage current_;
  std::map<uint32_t, int> subscription_topic_;
  std::map<int, uint32_t> topic_subscription_;
  std::set<uint32_t> client_channels_;
  int64_t reported_thumbnails_ = 0;
  int64_t reported_detail_ = 0;
};

}  // namespace

void Gateway::Impl::Accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec == asio::error::operation_aborted) return;
      return Accept();
    }
    beast::error_code ignored;
    const auto endpoint = socket.remote_endpoint(ignored);
    // A flood of connections that never finish their handshake: shed at
    // once, counted, no event (the flood would be the log's). One address
    // may hold at most a quarter of the pending slots, so that a flood from
    // one host does not keep everyone else out.
    const auto from = pending_by_address.find(endpoint.address());
    if (static_cast<int>(sessions.size()) - open_clients >= options.max_pending ||
        (from != pending_by_address.end() && from->second >= MaxPendingPerAddress(options))) {
      Count(&GatewayStats::shed);  // before the close the client sees
      socket.close(ignored);
      return Accept();
    }
    // No Nagle: small messages (a grid state, an event) go at once instead
    // of waiting a round trip for the last one's acknowledgement (on a
    // 300 ms link that was most of the station's lag; results/2026-12-07-gateway-link.md).
    socket.set_option(tcp::no_delay(true), ignored);
    // At most this much written but not yet sent held in the kernel: the
    // rest waits in the client's queue, where it is dropped by priority and
    // the live messages go before a catch-up. Without it the socket buffer
    // (megabytes, autotuned) filled with a reconnected client's map and the
    // live grid states queued behind it for seconds on a slow link.
    socket.set_option(asio::detail::socket_option::integer<IPPROTO_TCP, TCP_NOTSENT_LOWAT>(
                          static_cast<int>(options.max_unsent_bytes)),
                      ignored);
    const std::string remote =
        endpoint.address().to_string() + ":" + std::to_string(endpoint.port());
    std::shared_ptr<Session> session;
    if (tls) {
      session = std::make_shared<SessionT<beast::ssl_stream<beast::tcp_stream>>>(
          *this, beast::ssl_stream<beast::tcp_stream>(std::move(socket), *tls), remote,
          endpoint.address());
    } else {
      session = std::make_shared<SessionT<beast::tcp_stream>>(
          *this, beast::tcp_stream(std::move(socket)), remote, endpoint.address());
    }
    sessions.insert(session);
    session->Begin();
    Accept();
  });
}

void Gateway::Impl::StopWhenDrained(std::chrono::steady_clock::time_point deadline) {
  if (sessions.empty() || std::chrono::steady_clock::now() >= deadline) {
    const std::vector<std::shared_ptr<Session>> all(sessions.begin(), sessions.end());
    for (const auto& s : all) s->Abort();
    ioc.stop();
    return;
  }
  drain_timer.expires_after(std::chrono::milliseconds(20));
  drain_timer.async_wait([this, deadline](beast::error_code) { StopWhenDrained(deadline); });
}

void Gateway::Impl::ScheduleFlush() {
  flush_timer.expires_after(std::chrono::seconds(1));
  flush_timer.async_wait([this](beast::error_code ec) {
    if (ec) return;
    if (const auto line = refusals.Flush(WallUtime())) {
      Count(&GatewayStats::refusal_events);
      Event(plantscale_event_t::SEVERITY_WARNING, "gateway_refused", *line);
    }
    ScheduleFlush();
  });
}

void Gateway::Impl::OnLcm(const ReceivedMessage& m) {
  if (m.channel == channels::kOdometryIn) return;  // a sensor's input, not the vehicle's telemetry
  Count(&GatewayStats::lcm_messages);
  std::string error;
  std::vector<Converted> converted = ConvertLcm(m.channel, m.data, m.size, &error);
  if (!error.empty()) Count(&GatewayStats::lcm_rejected);
  // The bytes as they came, to the clients that decode LCM themselves.
  if (const int raw = LcmTopicIndex(m.channel); raw >= 0 && !converted.empty()) {
    Converted c{static_cast<int>(Topics().size()) + raw, converted.front().utime,
                std::string(static_cast<const char*>(m.data), m.size), converted.front().cache_key};
    converted.push_back(std::move(c));
  }
  static const int scene = TopicIndex(std::string(channels::kGrid) + "/scene");
  std::erase_if(converted, [&](const Converted& c) {
    if (c.topic != scene) return false;
    if (last_scene_utime != INT64_MIN && c.utime >= last_scene_utime &&
        c.utime - last_scene_utime < options.grid_scene_interval_us) {
      return true;
    }
    last_scene_utime = c.utime;
    return false;
  });
  if (converted.empty()) return;
  std::vector<std::pair<int64_t, CachedMessage>> plant_updates;
  if (m.channel == channels::kPlants) {
    plantscale_plant_list_t list;
    if (list.decode(m.data, 0, static_cast<int>(m.size)) >= 0) {
      for (const plantscale_plant_t& p : list.plants) {
        plantscale_plant_list_t one;
        one.utime = list.utime;
        one.seq = list.seq;
        one.frame_index = list.frame_index;
        one.num_plants = 1;
        one.plants = {p};
        const Bytes bytes = Encode(one);
        plant_updates.emplace_back(
            p.id, CachedMessage{list.utime, std::make_shared<const std::string>(bytes.begin(),
                                                                                 bytes.end())});
      }
    }
  }
  asio::post(ioc, [this, c = std::move(converted), p = std::move(plant_updates)]() mutable {
    Dispatch(c);
    CachePlants(std::move(p));
  });
}

void Gateway::Impl::CachePlants(std::vector<std::pair<int64_t, CachedMessage>> updates) {
  for (auto& [id, cached] : updates) {
    CachedMessage& slot = plants[id];
    const size_t before = slot.json ? slot.json->size() : 0;
    if (tile_bytes - before + cached.json->size() <= options.max_cached_tile_bytes) {
      tile_bytes = tile_bytes - before + cached.json->size();
      slot = std::move(cached);
    } else {
      if (!slot.json) plants.erase(id);
      Count(&GatewayStats::tiles_not_cached);
    }
  }
}

void Gateway::Impl::Dispatch(const std::vector<Converted>& converted) {
  for (const Converted& c : converted) {
    auto json = std::make_shared<const std::string>(c.json);
    CachedMessage cached{c.utime, json};
    latest[static_cast<size_t>(c.topic)] = cached;
    if (!c.cache_key.empty()) {
      CachedMessage& slot = tiles[{c.topic, c.cache_key}];
      const size_t before = slot.json ? slot.json->size() : 0;
      if (tile_bytes - before + json->size() <= options.max_cached_tile_bytes) {
        tile_bytes = tile_bytes - before + json->size();
        slot = cached;
      } else {
        if (!slot.json) tiles.erase({c.topic, c.cache_key});
        Count(&GatewayStats::tiles_not_cached);
      }
    }
    // Deliver may close (and erase) a session: iterate over a copy.
    const std::vector<std::shared_ptr<Session>> now(sessions.begin(), sessions.end());
    for (const auto& s : now) s->Deliver(c.topic, c.utime, json);
  }
}

Gateway::Gateway(const GatewayOptions& options, Users users, Transport& transport)
    : impl_(std::make_unique<Impl>(options, std::move(users), transport)) {
  ThrowIfInvalid("gateway", options.Validate());
  Impl& d = *impl_;
  d.latest.resize(TopicCount());
  if (!options.insecure_loopback) {
    d.tls.emplace(ssl::context::tls_server);
    d.tls->set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 |
                       ssl::context::no_sslv3 | ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1);
    boost::system::error_code ec;
    d.tls->use_certificate_chain_file(options.cert_file.string(), ec);
    if (ec) throw GatewayError("certificate " + options.cert_file.string() + ": " + ec.message());
    if (!std::ifstream(options.key_file).good()) {
      throw GatewayError("key " + options.key_file.string() + ": cannot be read");
    }
    d.tls->use_private_key_file(options.key_file.string(), ssl::context::pem, ec);
    if (ec && ec.message().find("mismatch") != std::string::npos) {
      throw GatewayError("key " + options.key_file.string() + " does not belong to certificate " +
                         options.cert_file.string() + " (" + ec.message() + ")");
    }
    if (ec) throw GatewayError("key " + options.key_file.string() + ": " + ec.message());
    if (SSL_CTX_check_private_key(d.tls->native_handle()) != 1) {
      throw GatewayError("key " + options.key_file.string() + " does not belong to certificate " +
                         options.cert_file.string());
    }
    // Served anyway (the clock may be what is wrong), but every client
    // will refuse it: said at start, not found out from each refusal.
    if (X509* cert = SSL_CTX_get0_certificate(d.tls->native_handle())) {
      const auto when = [](const ASN1_TIME* t) {
        std::tm tm{};
        char text[32] = "?";
        if (ASN1_TIME_to_tm(t, &tm) == 1) std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm);
        return std::string(text);
      };
      if (X509_cmp_current_time(X509_get0_notAfter(cert)) < 0) {
        d.certificate_warning = "certificate " + options.cert_file.string() + " expired " +
                                when(X509_get0_notAfter(cert)) + ": every client will refuse it";
      } else if (X509_cmp_current_time(X509_get0_notBefore(cert)) > 0) {
        d.certificate_warning = "certificate " + options.cert_file.string() + " is not valid before " +
                                when(X509_get0_notBefore(cert)) +
                                ": every client will refuse it until then (is this computer's clock right?)";
      }
    }
  }
  const tcp::endpoint endpoint(asio::ip::make_address(options.host),
                               static_cast<uint16_t>(options.port));
  boost::system::error_code ec;
  d.acceptor.open(endpoint.protocol(), ec);
  if (!ec) d.acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) d.acceptor.bind(endpoint, ec);
  if (!ec) d.acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    throw GatewayError("cannot listen on " + options.host + ":" + std::to_string(options.port) +
                       ": " + ec.message());
  }
  transport.Subscribe(".*", [this](const ReceivedMessage& m) { impl_->OnLcm(m); });
}

Gateway::~Gateway() { Stop(); }

void Gateway::Start() {
  Impl& d = *impl_;
  if (d.thread.joinable()) return;
  d.Accept();
  d.ScheduleFlush();
  d.thread = std::thread([&d] { d.ioc.run(); });
}

void Gateway::Stop() {
  Impl& d = *impl_;
  if (!d.thread.joinable()) return;
  asio::post(d.ioc, [&d] {
    beast::error_code ignored;
    d.acceptor.close(ignored);
    d.flush_timer.cancel();
    const std::vector<std::shared_ptr<Session>> all(d.sessions.begin(), d.sessions.end());
    for (const auto& s : all) s->Drain();
    d.StopWhenDrained(std::chrono::steady_clock::now() +
                      std::chrono::milliseconds(static_cast<int64_t>(1e3 * d.options.stop_drain_s)));
  });
  d.thread.join();
  d.sessions.clear();
}

const std::string& Gateway::certificate_warning() const { return impl_->certificate_warning; }

uint16_t Gateway::port() const {
  beast::error_code ec;
  return impl_->acceptor.local_endpoint(ec).port();
}

GatewayStats Gateway::stats() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

void Gateway::FlushOutgoing() {
  std::vector<std::pair<std::string, Bytes>> out;
  {
    std::lock_guard lock(impl_->mutex);
    out.swap(impl_->outgoing);
  }
  for (const auto& [channel, bytes] : out)
    impl_->transport.Publish(channel, bytes.data(), bytes.size());
}

void RunTransportLoop(Transport& transport, Gateway& gateway, const std::atomic<bool>& stop) {
  while (!stop.load()) {
    try {
      transport.Handle(50);
    } catch (const TransportError&) {
      if (stop.load()) break;  // the stopping signal interrupted LCM's wait
      throw;
    }
    gateway.FlushOutgoing();
  }
  // What the vehicle published last (its final map tiles) may still wait in
  // the socket: handled, so that Stop's drain sends it too.
  for (int i = 0; i < 1000; ++i) {
    try {
      if (!transport.Handle(0)) break;
    } catch (const TransportError&) {
      break;
    }
  }
  gateway.FlushOutgoing();
}

}  // namespace plantscale::telemetry::gateway
