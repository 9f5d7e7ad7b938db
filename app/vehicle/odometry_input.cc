#include "app/vehicle/odometry_input.h"

#include <cmath>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>

#include "telemetry/channels.h"
#include "telemetry/codec.h"

namespace plantscale::vehicle {

namespace channels = telemetry::channels;
using telemetry::Decode;
using telemetry::ReceivedMessage;

void OdometryInput::Attach(Transport& transport) {
  transport.Subscribe(channels::kOdometryIn,
                      [this](const ReceivedMessage& m) { Feed(m.channel, m.data, m.size); });
}

void OdometryInput::Feed(const std::string& channel, const void* data, size_t size) {
  std::string error;
  const auto m = Decode<plantscale_odometry_t>(channel, data, size, &error);
  std::lock_guard lock(mutex_);
  ++received_;
  if (m && (!m->valid || !std::isfinite(m->left_m_s) || !std::isfinite(m->right_m_s))) {
    error = "channel " + channel + ": odometry sample marked invalid or not finite";
  }
  if (!error.empty()) {
    ++rejected_;
    last_problem_ = error;
    return;
  }
  pipeline::OdometrySample s;
  s.utime = m->utime;
  s.left_m_s = m->left_m_s;
  s.right_m_s = m->right_m_s;
  pending_.push_back(s);
  last_utime_ = m->utime;
}

std::vector<pipeline::OdometrySample> OdometryInput::Take() {
  std::lock_guard lock(mutex_);
  std::vector<pipeline::OdometrySample> out;
  out.swap(pending_);
  return out;
}

std::vector<std::string> OdometryInput::Faults(int64_t now_utime, double stale_s) const {
  std::lock_guard lock(mutex_);
  std::vector<std::string> faults;
  if (last_utime_ < 0) {
    faults.push_back(std::string("odometry: nothing received on ") + channels::kOdometryIn);
  } else if (1e-6 * static_cast<double>(now_utime - last_utime_) > stale_s) {
    faults.push_back("odometry: stale, last sample " +
                     std::to_string(1e-6 * static_cast<double>(now_utime - last_utime_)) +
                     " s old");
  }
  if (rejected_ > 0) {
    faults.push_back("odometry: " + std::to_string(rejected_) +
                     " bad messages, last: " + last_problem_);
  }
  return faults;
}

int64_t OdometryInput::received() const {
  std::lock_guard lock(mutex_);
  return received_;
}

}  // namespace plantscale::vehicle
