#include "telemetry/gateway/lcm_topics.h"

#include <cstdio>
#include <nlohmann/json.hpp>
#include <plantscale_lcmtypes/plantscale_command_t.hpp>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <plantscale_lcmtypes/plantscale_grid_state_t.hpp>
#include <plantscale_lcmtypes/plantscale_health_t.hpp>
#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_nozzles_t.hpp>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_list_t.hpp>
#include <plantscale_lcmtypes/plantscale_pose_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>

#include "telemetry/channels.h"

namespace plantscale::telemetry::gateway {

namespace {

template <typename Message>
LcmTopic Of(const char* channel, TopicClass drop_class) {
  return {channel, Message::getTypeName(), Message::getHash(), drop_class};
}

std::vector<LcmTopic> MakeLcmTopics() {
  namespace ch = channels;
  using C = TopicClass;
  // The drop classes of the JSON topics fed by the same channel.
  return {
      Of<plantscale_grid_state_t>(ch::kGrid, C::kGrid),
      Of<plantscale_plant_list_t>(ch::kPlants, C::kEssential),
      Of<plantscale_map_tile_t>(ch::kMapTiles, C::kEssential),
      Of<plantscale_thumbnail_t>(ch::kThumbnail, C::kThumbnail),
      Of<plantscale_event_t>(ch::kEvents, C::kEssential),
      Of<plantscale_event_t>(ch::kGatewayEvents, C::kEssential),
      Of<plantscale_health_t>(ch::kHealth, C::kEssential),
      Of<plantscale_nozzles_t>(ch::kNozzles, C::kDetail),
      Of<plantscale_odometry_t>(ch::kOdometry, C::kDetail),
      Of<plantscale_pose_t>(ch::kPose, C::kDetail),
      Of<plantscale_grid_state_t>(ch::kSimTruth, C::kDetail),
      Of<plantscale_pose_t>(ch::kSimTruthPose, C::kDetail),
      Of<plantscale_command_t>(ch::kCommand, C::kEssential),
  };
}

}  // namespace

const std::vector<LcmTopic>& LcmTopics() {
  static const std::vector<LcmTopic> topics = MakeLcmTopics();
  return topics;
}

int LcmTopicIndex(const std::string& channel) {
  const auto& t = LcmTopics();
  for (size_t i = 0; i < t.size(); ++i) {
    if (t[i].channel == channel) return static_cast<int>(i);
  }
  return -1;
}

uint32_t LcmChannelId(size_t index) { return static_cast<uint32_t>(Topics().size() + 1 + index); }

std::string FingerprintHex(int64_t fingerprint) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx",
                static_cast<unsigned long long>(static_cast<uint64_t>(fingerprint)));
  return hex;
}

std::string AdvertiseLcm() {
  nlohmann::json channels = nlohmann::json::array();
  const auto& topics = LcmTopics();
  for (size_t i = 0; i < topics.size(); ++i) {
    channels.push_back({{"id", LcmChannelId(i)},
                        {"topic", topics[i].channel},
                        {"encoding", kLcmEncoding},
                        {"schemaName", topics[i].type_name},
                        {"schema", FingerprintHex(topics[i].fingerprint)},
                        {"schemaEncoding", "lcm-fingerprint"}});
  }
  return nlohmann::json{{"op", "advertise"}, {"channels", std::move(channels)}}.dump();
}

std::string QueryParameter(std::string_view target, std::string_view name) {
  const size_t q = target.find('?');
  if (q == std::string_view::npos) return {};
  std::string_view query = target.substr(q + 1);
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
    if (pair.size() > name.size() && pair.substr(0, name.size()) == name &&
        pair[name.size()] == '=') {
      return std::string(pair.substr(name.size() + 1));
    }
  }
  return {};
}

}  // namespace plantscale::telemetry::gateway
