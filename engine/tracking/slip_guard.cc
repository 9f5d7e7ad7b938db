#include "engine/tracking/slip_guard.h"

#include <algorithm>
#include <cmath>

namespace plantscale::tracking {

OptionErrors SlipGuardOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "max_acceleration_m_s2", max_acceleration_m_s2);
  RequireInRange(e, "jump_fraction", jump_fraction, 0.0, 1.0, false, true);
  RequirePositive(e, "min_speed_m_s", min_speed_m_s);
  RequirePositive(e, "reference_time_s", reference_time_s);
  RequirePositive(e, "max_slip_s", max_slip_s);
  return e;
}

SlipGuard::SlipGuard(const SlipGuardOptions& options) : options_(options) {
  ThrowIfInvalid("slip guard", options_.Validate());
}

void SlipGuard::Reset() {
  started_ = false;
  slipping_ = false;
  reference_m_s_ = 0.0;
  slip_s_ = 0.0;
  bursts_ = 0;
}

double SlipGuard::Threshold(double speed, double span_s) const {
  return options_.jump_fraction * std::max(std::abs(speed), options_.min_speed_m_s) +
         options_.max_acceleration_m_s2 * span_s;
}

WheelSpeeds SlipGuard::Filter(const WheelSpeeds& measured, double dt_s) {
  const double v = 0.5 * (measured.left_m_s + measured.right_m_s);
  if (!options_.enabled) return measured;
  if (!started_) {
    started_ = true;
    reference_m_s_ = v;
    return measured;
  }
  if (slipping_) {
    slip_s_ += dt_s;
    // The wheels grip again once they agree with the ground speed held.
    if (std::abs(v - reference_m_s_) <= Threshold(reference_m_s_, dt_s) ||
        slip_s_ > options_.max_slip_s) {
      slipping_ = false;
      if (slip_s_ > options_.max_slip_s) reference_m_s_ = v;  // a real change of speed
    }
  } else if (std::abs(v - reference_m_s_) >
             Threshold(reference_m_s_, dt_s + options_.reference_time_s)) {
    slipping_ = true;
    slip_s_ = 0.0;
    ++bursts_;
  }
  if (slipping_) {
    // Both wheels scaled to the ground speed held.
    const double c = std::abs(v) > 1e-9 ? reference_m_s_ / v : 0.0;
    return {c * measured.left_m_s, c * measured.right_m_s};
  }
  const double a = dt_s / (options_.reference_time_s + dt_s);
  reference_m_s_ += a * (v - reference_m_s_);
  return measured;
}

}  // namespace plantscale::tracking
