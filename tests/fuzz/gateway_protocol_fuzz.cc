// Fuzz target: what a gateway client sends (telemetry/gateway/, issue 58).
// Byte 0 picks the path; the rest is the input:
//   0: a text frame through ParseClientText, 1: a binary frame through
//   ParseClientBinary: never throw, and what they accept stays within the
//   limits (items, string bytes) and keeps the payload whole;
//   2: an operator's command payload: JSON parse and CommandFromJson may
//   refuse only with DataError, and what they accept encodes to LCM;
//   3: an upgrade request's target and Authorization header (split at the
//   first newline) through TokenFromRequest: never throws;
//   4: LCM bytes on the channel picked by byte 1 through ConvertLcm, the
//   gateway's conversion of what the vehicle sends: never throws, and every
//   JSON it writes parses.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <variant>

#include "engine/common/options.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/gateway/client_protocol.h"
#include "telemetry/gateway/foxglove_convert.h"
#include "telemetry/gateway/users.h"

namespace {

namespace gw = plantscale::telemetry::gateway;
namespace ch = plantscale::telemetry::channels;

void Check(bool ok) {
  if (!ok) std::abort();
}

void CheckParsed(const gw::ClientMessage& m, const gw::ProtocolLimits& limits, size_t input_size) {
  if (const auto* s = std::get_if<gw::Subscribe>(&m))
    Check(s->subscriptions.size() <= limits.max_items);
  if (const auto* u = std::get_if<gw::Unsubscribe>(&m))
    Check(u->subscription_ids.size() <= limits.max_items);
  if (const auto* a = std::get_if<gw::ClientAdvertise>(&m)) {
    Check(a->channels.size() <= limits.max_items);
    for (const auto& c : a->channels) {
      Check(c.topic.size() <= limits.max_string_bytes &&
            c.encoding.size() <= limits.max_string_bytes &&
            c.schema_name.size() <= limits.max_string_bytes);
    }
  }
  if (const auto* d = std::get_if<gw::ClientMessageData>(&m))
    Check(d->payload.size() + 5 == input_size);
  if (const auto* e = std::get_if<gw::ProtocolError>(&m)) Check(!e->reason.empty());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string_view input(reinterpret_cast<const char*>(data) + 1, size - 1);
  gw::ProtocolLimits limits;
  limits.max_message_bytes = 4096;  // small, so the fuzzer reaches the bound
  limits.max_items = 8;
  limits.max_string_bytes = 16;
  switch (data[0] % 5) {
    case 0:
      CheckParsed(gw::ParseClientText(input, limits), limits, input.size());
      break;
    case 1:
      CheckParsed(gw::ParseClientBinary(input, limits), limits, input.size());
      break;
    case 2: {
      const nlohmann::json j = nlohmann::json::parse(input.begin(), input.end(), nullptr, false);
      try {
        const plantscale_command_t c = gw::CommandFromJson(j);
        Check(c.mac_size == 0 || c.mac_size == plantscale_command_t::MAC_SIZE);
        const auto bytes = plantscale::telemetry::Encode(c);
        Check(!bytes.empty());
      } catch (const plantscale::DataError&) {
      }
      break;
    }
    case 3: {
      const size_t nl = input.find('\n');
      const std::string_view target = input.substr(0, nl);
      const std::string_view header =
          nl == std::string_view::npos ? std::string_view() : input.substr(nl + 1);
      const std::string token = gw::TokenFromRequest(target, header);
      Check(token.size() <= input.size());
      break;
    }
    default: {
      if (input.empty()) return 0;
      static const char* const kChannels[] = {ch::kGrid,      ch::kPlants,   ch::kMapTiles,
                                              ch::kThumbnail, ch::kEvents,   ch::kHealth,
                                              ch::kNozzles,   ch::kOdometry, ch::kPose,
                                              ch::kSimTruth,  ch::kCommand,  ch::kGatewayEvents};
      const std::string channel = kChannels[static_cast<uint8_t>(input[0]) % std::size(kChannels)];
      std::string error;
      const auto out = gw::ConvertLcm(channel, input.data() + 1, input.size() - 1, &error);
      for (const auto& c : out) {
        Check(!nlohmann::json::parse(c.json, nullptr, false).is_discarded());
      }
      break;
    }
  }
  return 0;
}
