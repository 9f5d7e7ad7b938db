#include "telemetry/gateway/client_protocol.h"

#include <limits>

#include "telemetry/gateway/foxglove_convert.h"

namespace plantscale::telemetry::gateway {

namespace {

using nlohmann::json;

ProtocolError Error(std::string reason) { return ProtocolError{std::move(reason)}; }

bool Uint32(const json& j, const char* key, uint32_t& out) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number_integer()) return false;
  if (it->is_number_unsigned()) {
    const uint64_t v = it->get<uint64_t>();
    if (v > std::numeric_limits<uint32_t>::max()) return false;
    out = static_cast<uint32_t>(v);
    return true;
  }
  const int64_t v = it->get<int64_t>();
  if (v < 0 || v > int64_t{std::numeric_limits<uint32_t>::max()}) return false;
  out = static_cast<uint32_t>(v);
  return true;
}

bool BoundedString(const json& j, const char* key, size_t max, std::string& out) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_string()) return false;
  const auto& s = it->get_ref<const std::string&>();
  if (s.size() > max) return false;
  out = s;
  return true;
}

// The array `key` of `j`, checked for presence and size; null when bad.
const json* Items(const json& j, const char* key, size_t max_items, std::string& why) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_array()) {
    why = std::string("'") + key + "' must be an array";
    return nullptr;
  }
  if (it->size() > max_items) {
    why = std::string("'") + key + "' has " + std::to_string(it->size()) + " items (at most " +
          std::to_string(max_items) + ")";
    return nullptr;
  }
  return &*it;
}

ClientMessage ParseIds(const json& j, const char* key, const ProtocolLimits& limits,
                       bool unsubscribe) {
  std::string why;
  const json* items = Items(j, key, limits.max_items, why);
  if (!items) return Error(why);
  std::vector<uint32_t> ids;
  for (const json& v : *items) {
    const json wrapped = {{"v", v}};
    uint32_t id = 0;
    if (!Uint32(wrapped, "v", id)) return Error(std::string("'") + key + "' must hold uint32 ids");
    ids.push_back(id);
  }
  if (unsubscribe) return Unsubscribe{std::move(ids)};
  return ClientUnadvertise{std::move(ids)};
}

ClientMessage ParseSubscribe(const json& j, const ProtocolLimits& limits) {
  std::string why;
  const json* items = Items(j, "subscriptions", limits.max_items, why);
  if (!items) return Error(why);
  Subscribe s;
  for (const json& item : *items) {
    Subscribe::Item x;
    if (!item.is_object() || !Uint32(item, "id", x.id) ||
        !Uint32(item, "channelId", x.channel_id)) {
      return Error("each subscription needs uint32 'id' and 'channelId'");
    }
    s.subscriptions.push_back(x);
  }
  return s;
}

ClientMessage ParseAdvertise(const json& j, const ProtocolLimits& limits) {
  std::string why;
  const json* items = Items(j, "channels", limits.max_items, why);
  if (!items) return Error(why);
  ClientAdvertise a;
  for (const json& item : *items) {
    ClientAdvertise::Channel c;
    if (!item.is_object() || !Uint32(item, "id", c.id) ||
        !BoundedString(item, "topic", limits.max_string_bytes, c.topic) ||
        !BoundedString(item, "encoding", limits.max_string_bytes, c.encoding)) {
      return Error(
          "each client channel needs uint32 'id' and strings 'topic' and 'encoding' (at most " +
          std::to_string(limits.max_string_bytes) + " bytes)");
    }
    if (item.contains("schemaName") &&
        !BoundedString(item, "schemaName", limits.max_string_bytes, c.schema_name)) {
      return Error("'schemaName' must be a string of at most " +
                   std::to_string(limits.max_string_bytes) + " bytes");
    }
    a.channels.push_back(std::move(c));
  }
  return a;
}

}  // namespace

ClientMessage ParseClientText(std::string_view text, const ProtocolLimits& limits) {
  if (text.size() > limits.max_message_bytes) {
    return Error("message of " + std::to_string(text.size()) + " bytes (at most " +
                 std::to_string(limits.max_message_bytes) + ")");
  }
  const json j = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return Error("not valid JSON");
  if (!j.is_object()) return Error("not a JSON object");
  const auto op = j.find("op");
  if (op == j.end() || !op->is_string()) return Error("no 'op' string");
  const auto& name = op->get_ref<const std::string&>();
  if (name == "subscribe") return ParseSubscribe(j, limits);
  if (name == "unsubscribe") return ParseIds(j, "subscriptionIds", limits, true);
  if (name == "advertise") return ParseAdvertise(j, limits);
  if (name == "unadvertise") return ParseIds(j, "channelIds", limits, false);
  return Error("unsupported op '" + name.substr(0, 64) + "'");
}

ClientMessage ParseClientBinary(std::string_view bytes, const ProtocolLimits& limits) {
  if (bytes.size() > limits.max_message_bytes) {
    return Error("message of " + std::to_string(bytes.size()) + " bytes (at most " +
                 std::to_string(limits.max_message_bytes) + ")");
  }
  if (bytes.empty()) return Error("empty binary message");
  const auto opcode = static_cast<uint8_t>(bytes[0]);
  if (opcode != 0x01) return Error("unsupported binary opcode " + std::to_string(opcode));
  if (bytes.size() < 5) return Error("client message data shorter than its 5-byte header");
  ClientMessageData d;
  for (int i = 0; i < 4; ++i) {
    d.channel_id |= uint32_t{static_cast<uint8_t>(bytes[1 + static_cast<size_t>(i)])} << (8 * i);
  }
  d.payload = std::string(bytes.substr(5));
  return d;
}

std::string ServerInfo(const ServerInfoArgs& a) {
  json capabilities = json::array();
  if (a.client_publish) capabilities.push_back("clientPublish");
  json info = {{"op", "serverInfo"},
               {"name", a.name},
               {"capabilities", std::move(capabilities)},
               {"sessionId", a.session_id},
               {"metadata", {{"user", a.user}, {"role", a.role}}}};
  if (a.client_publish) info["supportedEncodings"] = json::array({"json"});
  return info.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string AdvertiseAll() {
  json channels = json::array();
  const auto& topics = Topics();
  for (size_t i = 0; i < topics.size(); ++i) {
    channels.push_back({{"id", i + 1},
                        {"topic", topics[i].name},
                        {"encoding", "json"},
                        {"schemaName", topics[i].schema_name},
                        {"schema", topics[i].schema.dump()},
                        {"schemaEncoding", "jsonschema"}});
  }
  return json{{"op", "advertise"}, {"channels", std::move(channels)}}.dump();
}

std::string Status(int level, const std::string& message) {
  return json{{"op", "status"}, {"level", level}, {"message", message}}.dump(
      -1, ' ', false, json::error_handler_t::replace);
}

std::string MessageDataHeader(uint32_t subscription_id, uint64_t timestamp_ns) {
  std::string h(13, '\0');
  h[0] = 0x01;
  for (int i = 0; i < 4; ++i)
    h[1 + static_cast<size_t>(i)] = static_cast<char>((subscription_id >> (8 * i)) & 0xff);
  for (int i = 0; i < 8; ++i)
    h[5 + static_cast<size_t>(i)] = static_cast<char>((timestamp_ns >> (8 * i)) & 0xff);
  return h;
}

}  // namespace plantscale::telemetry::gateway
