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
  RequireInRange(e, "wheel_fault_factor", wheel_fault_factor, 1.0, 100.0);
  RequirePositive(e, "max_wheel_fault_s", max_wheel_fault_s);
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
  wheel_reference_ = {};
  held_difference_m_s_ = 0.0;
  wheel_fault_s_ = 0.0;
  faulty_wheel_ = 0;
  wheel_faults_ = 0;
}

double SlipGuard::Threshold(double speed, double span_s) const {
  return options_.jump_fraction * std::max(std::abs(speed), options_.min_speed_m_s) +
         options_.max_acceleration_m_s2 * span_s;
}

WheelSpeeds SlipGuard::CheckWheels(const WheelSpeeds& measured, double dt_s) {
  const double span = dt_s + options_.reference_time_s;
  WheelSpeeds& ref = wheel_reference_;
  if (faulty_wheel_ != 0) {
    wheel_fault_s_ += dt_s;
    const bool left = faulty_wheel_ == 1;
    const double good = left ? measured.right_m_s : measured.left_m_s;
    const double bad = left ? measured.left_m_s : measured.right_m_s;
    const double expected = good + (left ? held_difference_m_s_ : -held_difference_m_s_);
    if (std::abs(bad - expected) <= Threshold(expected, span) ||
        wheel_fault_s_ > options_.max_wheel_fault_s) {
      faulty_wheel_ = 0;  // back, or a real change that vision corrects
      ref = measured;
      return measured;
    }
    (left ? ref.right_m_s : ref.left_m_s) = good;
    return left ? WheelSpeeds{expected, good} : WheelSpeeds{good, expected};
  }
  if (!slipping_) {
    const double wide = options_.wheel_fault_factor;
    const bool left_jumped =
        std::abs(measured.left_m_s - ref.left_m_s) > wide * Threshold(ref.left_m_s, span);
    const bool right_jumped =
        std::abs(measured.right_m_s - ref.right_m_s) > wide * Threshold(ref.right_m_s, span);
    const bool left_kept =
        std::abs(measured.left_m_s - ref.left_m_s) <= Threshold(ref.left_m_s, span);
    const bool right_kept =
        std::abs(measured.right_m_s - ref.right_m_s) <= Threshold(ref.right_m_s, span);
    // And the two diverge: a wheel stalling or spinning alone pulls them
    // apart, where a steering change that jumps one wheel more than the
    // other (the vehicle straightening) may as well bring them together.
    const double before = ref.left_m_s - ref.right_m_s;
    const double after = measured.left_m_s - measured.right_m_s;
    const double ground = 0.5 * (ref.left_m_s + ref.right_m_s);
    const bool diverged = std::abs(after) > std::abs(before) + wide * Threshold(ground, span);
    if (diverged && ((left_jumped && right_kept) || (right_jumped && left_kept))) {
      faulty_wheel_ = left_jumped ? 1 : 2;
      wheel_fault_s_ = 0.0;
      held_difference_m_s_ = ref.left_m_s - ref.right_m_s;
      ++wheel_faults_;
      return CheckWheels(measured, 0.0);
    }
  }
  const double a = dt_s / (options_.reference_time_s + dt_s);
  ref.left_m_s += a * (measured.left_m_s - ref.left_m_s);
  ref.right_m_s += a * (measured.right_m_s - ref.right_m_s);
  return measured;
}

WheelSpeeds SlipGuard::Filter(const WheelSpeeds& raw, double dt_s) {
  if (!options_.enabled) return raw;
  if (!started_) {
    started_ = true;
    reference_m_s_ = 0.5 * (raw.left_m_s + raw.right_m_s);
    wheel_reference_ = raw;
    return raw;
  }
  const WheelSpeeds measured = CheckWheels(raw, dt_s);
  const double v = 0.5 * (measured.left_m_s + measured.right_m_s);
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
