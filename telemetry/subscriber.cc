#include "telemetry/subscriber.h"

#include <exception>

#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"

namespace plantscale::telemetry {
namespace {

template <typename T>
void PushBounded(std::deque<T>& history, T value, int limit) {
  history.push_back(std::move(value));
  while (static_cast<int>(history.size()) > limit) history.pop_front();
}

void TrackSequence(ChannelStats& s, int64_t seq) {
  if (s.last_seq >= 0 && seq > s.last_seq + 1) s.lost += seq - s.last_seq - 1;
  if (s.last_seq >= 0 && seq <= s.last_seq) ++s.restarts;
  s.last_seq = seq;
}

}  // namespace

OptionErrors SubscriberOptions::Validate() const {
  OptionErrors errors;
  RequirePositive(errors, "history_length", history_length);
  RequirePositive(errors, "event_history", event_history);
  RequirePositive(errors, "shot_history", shot_history);
  RequirePositive(errors, "problem_history", problem_history);
  return errors;
}

Subscriber::Subscriber(const SubscriberOptions& options) : options_(options) {
  ThrowIfInvalid("telemetry subscriber options", options_.Validate());
}

void Subscriber::Attach(Transport& transport) {
  transport.Subscribe(
      ".*", [this](const ReceivedMessage& m) { Feed(m.channel, m.data, m.size, m.recv_utime); });
}

void Subscriber::SetObserver(Observer observer) {
  std::lock_guard lock(mutex_);
  observer_ = std::move(observer);
}

TelemetrySnapshot Subscriber::Snapshot() const {
  std::lock_guard lock(mutex_);
  return state_;
}

void Subscriber::NoteProblem(std::string line) {
  PushBounded(state_.problems, std::move(line), options_.problem_history);
}

// Decodes, counts and applies one message under the lock. Bad bytes and
// rejected values are counted on the channel and described in `problems`.
template <typename Message, typename Apply>
void Subscriber::Take(const std::string& channel, const void* data, size_t size, int64_t recv_utime,
                      Apply&& apply) {
  std::string error;
  std::optional<Message> message = Decode<Message>(channel, data, size, &error);
  std::lock_guard lock(mutex_);
  ChannelStats& s = state_.channels[channel];
  ++s.received;
  s.bytes += static_cast<int64_t>(size);
  s.last_recv_utime = recv_utime;
  if (!message) {
    ++s.decode_failures;
    NoteProblem(error);
    if (observer_) observer_(channel, false, state_);
    return;
  }
  TrackSequence(s, message->seq);
  try {
    apply(*message);
  } catch (const std::exception& e) {
    ++s.invalid;
    NoteProblem("channel " + channel + ": " + e.what());
    if (observer_) observer_(channel, false, state_);
    return;
  }
  if (observer_) observer_(channel, true, state_);
}

void Subscriber::Feed(const std::string& channel, const void* data, size_t size,
                      int64_t recv_utime) {
  if (Dispatch(channel, data, size, recv_utime)) return;
  // LCM's own start-up check on udpm (lcm_udpm sends it to itself): not a
  // foreign program on the bus.
  if (channel == "LCM_SELF_TEST") return;
  std::lock_guard lock(mutex_);
  ++state_.unknown_channel_messages;
  ChannelStats& s = state_.channels[channel];
  ++s.received;
  s.bytes += static_cast<int64_t>(size);
  s.last_recv_utime = recv_utime;
  if (s.received == 1) NoteProblem("unknown channel " + channel + " (ignored)");
  if (observer_) observer_(channel, false, state_);
}

bool Subscriber::Dispatch(const std::string& channel, const void* data, size_t size, int64_t recv) {
  using namespace channels;
  const int n = options_.history_length;
  TelemetrySnapshot& st = state_;
  if (channel == kGrid || channel == kSimTruth) {
    const bool truth = channel == kSimTruth;
    Take<plantscale_grid_state_t>(channel, data, size, recv, [&](const auto& m) {
      GridEstimate e = FromLcm(m);
      (truth ? st.truth : st.grid) = e;
      PushBounded(truth ? st.truth_history : st.grid_history, std::move(e), n);
    });
  } else if (channel == kPose || channel == kSimTruthPose) {
    const bool truth = channel == kSimTruthPose;
    Take<plantscale_pose_t>(channel, data, size, recv, [&](const auto& m) {
      const Pose p = FromLcm(m);
      (truth ? st.truth_pose : st.pose) = p;
      if (truth) PushBounded(st.truth_pose_history, std::make_pair(m.utime, p), n);
    });
  } else if (channel == kPlants) {
    Take<plantscale_plant_list_t>(channel, data, size, recv, [&](const auto& m) {
      std::vector<PlantObservation> plants;
      for (const plantscale_plant_t& p : m.plants) plants.push_back(FromLcm(p));
      st.plants = std::move(plants);
    });
  } else if (channel == kMapTiles) {
    Take<plantscale_map_tile_t>(channel, data, size, recv, [&](const auto& m) {
      MapTileDelta t = FromLcm(m);
      if (!options_.keep_tiles) st.tiles.clear();
      MapTileDelta& slot = st.tiles[{t.tile_x, t.tile_y}];
      if (slot.cells.empty() || t.revision >= slot.revision) slot = std::move(t);
    });
  } else if (channel == kNozzles) {
    Take<plantscale_nozzles_t>(channel, data, size, recv, [&](const auto& m) {
      NozzleBar bar = FromLcm(m);
      for (const NozzleShot& s : bar.shots) PushBounded(st.shots, s, options_.shot_history);
      st.nozzles = std::move(bar);
    });
  } else if (channel == kHealth) {
    Take<plantscale_health_t>(channel, data, size, recv, [&](const auto& m) {
      st.health = FromLcm(m);
      st.health_recv_utime = recv;
    });
  } else if (channel == kThumbnail) {
    Take<plantscale_thumbnail_t>(channel, data, size, recv,
                                 [&](const auto& m) { st.thumbnail = m; });
  } else if (channel == kOdometry) {
    Take<plantscale_odometry_t>(channel, data, size, recv, [&](const auto& m) { st.odometry = m; });
  } else if (channel == kCommand) {
    Take<plantscale_command_t>(channel, data, size, recv, [&](const auto& m) { st.command = m; });
  } else if (channel == kEvents || channel == kGatewayEvents) {
    Take<plantscale_event_t>(channel, data, size, recv, [&](const auto& m) {
      PushBounded(st.events, m, options_.event_history);
    });
  } else {
    return false;
  }
  return true;
}

}  // namespace plantscale::telemetry
