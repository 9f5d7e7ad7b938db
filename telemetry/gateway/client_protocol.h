#pragma once
// The Foxglove WebSocket protocol (subprotocol foxglove.websocket.v1,
// github.com/foxglove/ws-protocol docs/spec.md) as the gateway speaks it,
// without networking: the client messages it accepts, parsed from untrusted
// bytes (never throws, bounded), and the server messages it writes.
//
// Accepted from clients: text "subscribe", "unsubscribe", "advertise"
// (client channels), "unadvertise"; binary opcode 0x01 (client message data:
// uint32 channel id, payload). Anything else is an error the server answers
// with a status message.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace plantscale::telemetry::gateway {

inline constexpr char kSubprotocol[] = "foxglove.websocket.v1";

// Bounds on what a client may send (a message beyond max_message_bytes is
// refused by the WebSocket layer before it is parsed).
struct ProtocolLimits {
  size_t max_message_bytes = 64 * 1024;
  size_t max_items = 256;         // subscriptions or channels in one message
  size_t max_string_bytes = 256;  // topic, encoding, schema name
};

struct Subscribe {
  struct Item {
    uint32_t id = 0;          // chosen by the client
    uint32_t channel_id = 0;  // an advertised channel
  };
  std::vector<Item> subscriptions;
};
struct Unsubscribe {
  std::vector<uint32_t> subscription_ids;
};
struct ClientAdvertise {
  struct Channel {
    uint32_t id = 0;
    std::string topic;
    std::string encoding;
    std::string schema_name;
  };
  std::vector<Channel> channels;
};
struct ClientUnadvertise {
  std::vector<uint32_t> channel_ids;
};
struct ClientMessageData {
  uint32_t channel_id = 0;
  std::string payload;
};
struct ProtocolError {
  std::string reason;  // one line, for a status message to the client
};

using ClientMessage = std::variant<Subscribe, Unsubscribe, ClientAdvertise, ClientUnadvertise,
                                   ClientMessageData, ProtocolError>;

// A text frame: one JSON object with an "op". Never throws.
ClientMessage ParseClientText(std::string_view text, const ProtocolLimits& limits = {});
// A binary frame: opcode byte, then the opcode's fields. Never throws.
ClientMessage ParseClientBinary(std::string_view bytes, const ProtocolLimits& limits = {});

// Server messages.
struct ServerInfoArgs {
  std::string name;
  std::string session_id;
  bool client_publish = false;  // the capability, for operators only
  std::string user;
  std::string role;
};
std::string ServerInfo(const ServerInfoArgs& args);
// Every topic of foxglove_convert.h's Topics(), channel id = index + 1.
std::string AdvertiseAll();
// level: 0 info, 1 warning, 2 error.
std::string Status(int level, const std::string& message);
// The 13-byte header of a message data frame (opcode 0x01, little-endian
// uint32 subscription id, uint64 nanoseconds); the JSON payload follows.
std::string MessageDataHeader(uint32_t subscription_id, uint64_t timestamp_ns);

}  // namespace plantscale::telemetry::gateway
