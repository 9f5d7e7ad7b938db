#pragma once
// Wheel odometry arriving over LCM for `plantscale run`: plantscale_odometry_t
// on PLANTSCALE_ODOMETRY_IN (50 Hz; utime, left_m_s, right_m_s measured
// ground speeds of the wheels, valid = 0 when the odometry box reports a
// fault; seq and distance_m are ignored). Samples are queued until the next
// camera frame takes them; bad messages are counted and reported as faults.

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "engine/pipeline/pipeline.h"
#include "telemetry/transport.h"

namespace plantscale::vehicle {

using telemetry::Transport;

class OdometryInput {
 public:
  void Attach(Transport& transport);
  void Feed(const std::string& channel, const void* data, size_t size);
  // Every valid sample received since the previous call, oldest first.
  std::vector<pipeline::OdometrySample> Take();
  // Faults: no odometry for more than `stale_s` before `now_utime`, invalid
  // samples, undecodable messages. Empty when all is well.
  std::vector<std::string> Faults(int64_t now_utime, double stale_s = 0.5) const;
  int64_t received() const;

 private:
  mutable std::mutex mutex_;
  std::vector<pipeline::OdometrySample> pending_;
  int64_t received_ = 0;
  int64_t rejected_ = 0;
  int64_t last_utime_ = -1;
  std::string last_problem_;
};

}  // namespace plantscale::vehicle
