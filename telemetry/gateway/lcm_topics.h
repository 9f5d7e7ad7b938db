#pragma once
// The vehicle's LCM channels as they are, for a client that decodes LCM
// itself (the station, `station --connect`): each a Foxglove channel of
// encoding "lcm" whose schemaName is the LCM type and whose schema is the
// type's fingerprint (16 hex digits), so a client built from other .lcm
// files says so instead of failing to decode.
//
// Only a client that asks for them (`lcm=1` in the upgrade request's query)
// is advertised these channels: Foxglove and Lichtblick list a channel of an
// encoding they cannot read as an error. Their channel ids follow the JSON
// topics' (foxglove_convert.h): LcmTopics()[i] is Topics().size() + 1 + i.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "telemetry/gateway/foxglove_convert.h"

namespace plantscale::telemetry::gateway {

inline constexpr char kLcmEncoding[] = "lcm";

struct LcmTopic {
  std::string channel;    // the LCM channel, also the Foxglove topic
  std::string type_name;  // the lcm-gen type, e.g. plantscale_grid_state_t
  int64_t fingerprint = 0;
  TopicClass drop_class = TopicClass::kEssential;  // as its JSON topic's
};

const std::vector<LcmTopic>& LcmTopics();
// Index into LcmTopics() of `channel`, or -1.
int LcmTopicIndex(const std::string& channel);
// The advertised channel id of LcmTopics()[index].
uint32_t LcmChannelId(size_t index);
// The fingerprint as the channel's schema: 16 lower-case hex digits.
std::string FingerprintHex(int64_t fingerprint);
// An "advertise" message of every LCM topic.
std::string AdvertiseLcm();
// The value of `name` in the query of a request target ("/?a=1&b=2"),
// undecoded; empty when absent.
std::string QueryParameter(std::string_view target, std::string_view name);

}  // namespace plantscale::telemetry::gateway
