#pragma once
// The station's subscriber: decodes every plantscale channel, keeps the
// latest state and bounded histories, counts what went wrong per channel
// (decode failures, invalid values, sequence gaps, restarts, unknown
// channels), and hands a consistent copy to the UI thread with Snapshot().
// Message handling (the transport thread, or a log reader calling Feed) and
// Snapshot (the UI thread) may run concurrently: one mutex guards the state.

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <plantscale_lcmtypes/plantscale_command_t.hpp>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>
#include <string>
#include <utility>
#include <vector>

#include "engine/common/options.h"
#include "telemetry/transport.h"
#include "telemetry/types.h"

namespace plantscale::telemetry {

struct SubscriberOptions {
  int history_length = 1000;  // grid and pose states kept (80 s at 12.5 Hz)
  int event_history = 200;
  int shot_history = 2000;
  int problem_history = 50;  // last problem lines kept
  // false: the snapshot's `tiles` holds only the tile last received (for a
  // reader that keeps the map itself, e.g. the station's run model: a 5 km
  // bed's tiles are ~100 MB, held once, not twice).
  bool keep_tiles = true;

  OptionErrors Validate() const;
};

struct ChannelStats {
  int64_t received = 0;
  int64_t bytes = 0;
  int64_t decode_failures = 0;  // could not decode (truncated, fingerprint)
  int64_t invalid = 0;          // decoded but rejected (NaN, bad sizes)
  int64_t lost = 0;             // sequence numbers skipped
  int64_t restarts = 0;         // sequence went backwards: sender restarted
  int64_t last_seq = -1;
  int64_t last_recv_utime = 0;
};

struct TelemetrySnapshot {
  std::optional<GridEstimate> grid;   // PLANTSCALE_GRID
  std::optional<GridEstimate> truth;  // PLANTSCALE_SIM_TRUTH
  std::deque<GridEstimate> grid_history;
  std::deque<GridEstimate> truth_history;
  std::optional<Pose> pose;
  std::optional<Pose> truth_pose;
  std::deque<std::pair<int64_t, Pose>> truth_pose_history;
  std::vector<PlantObservation> plants;               // latest frame's
  std::map<std::pair<int, int>, MapTileDelta> tiles;  // newest revision per tile
  std::optional<NozzleBar> nozzles;
  std::deque<NozzleShot> shots;
  std::optional<Health> health;
  int64_t health_recv_utime = 0;  // heartbeat age = now − this
  std::optional<plantscale_thumbnail_t> thumbnail;
  std::optional<plantscale_odometry_t> odometry;
  std::optional<plantscale_command_t> command;
  std::deque<plantscale_event_t> events;
  std::map<std::string, ChannelStats> channels;
  int64_t unknown_channel_messages = 0;
  std::deque<std::string> problems;  // newest last, one line each
};

class Subscriber {
 public:
  // Throws InvalidOptionsError.
  explicit Subscriber(const SubscriberOptions& options = {});
  // Subscribes to every channel of `transport` (".*"), so that unknown
  // channels are counted too.
  void Attach(Transport& transport);
  // One message (from a transport or a log); never throws on bad bytes.
  void Feed(const std::string& channel, const void* data, size_t size, int64_t recv_utime);
  TelemetrySnapshot Snapshot() const;
  // Called under the lock after every message with its channel, whether it
  // was applied (false: bad bytes, rejected values, unknown channel) and the
  // whole state, so that a consumer can accumulate more than the bounded
  // histories (the report, the station's run model) without copying the
  // state per message. Must not call back into this subscriber.
  using Observer =
      std::function<void(const std::string& channel, bool applied, const TelemetrySnapshot& state)>;
  void SetObserver(Observer observer);

 private:
  template <typename Message, typename Apply>
  void Take(const std::string& channel, const void* data, size_t size, int64_t recv_utime,
            Apply&& apply);
  void NoteProblem(std::string line);
  bool Dispatch(const std::string& channel, const void* data, size_t size, int64_t recv_utime);

  SubscriberOptions options_;
  mutable std::mutex mutex_;
  TelemetrySnapshot state_;
  Observer observer_;
};

}  // namespace plantscale::telemetry
