#pragma once
// Wheel slip from the wheels alone. A field vehicle's ground speed changes
// no faster than its traction and mass let it (a few tenths of m/s²), so a
// wheel speed that jumps within one odometry sample by more than that and
// more than the wheels' noise is the wheels spinning or locking, not the
// vehicle speeding up: while it lasts, the guard dead-reckons with the
// ground speed from before the jump (both wheels scaled alike, so the turn
// rate keeps its share) and lets the wheels back in when they return to
// it, or after max_slip_s (a real change of speed that vision corrects).
//
// A spinning wheel reads 10–20 % long for a few tenths of a metre; between
// camera frames the dead-reckoned grid runs ahead of the plants by that
// (8 mm a frame at 15 % and 0.7 m/s), and at the spray bar the nozzles
// fire that much late. A gradual onset (each sample's change within the
// threshold) is followed as a change of speed and left to the tracker's
// forward process noise.
//
// One wheel alone jumping (its encoder stalled or failed, or that wheel
// alone spinning on a wet patch) while the other keeps to its speed is
// that wheel's fault, not the vehicle's: a wheel reading 0 beside one at
// 0.7 m/s would be the vehicle pivoting at half a radian a second between
// its crop rows. While it lasts the faulty wheel is read as the good one
// plus the difference the two held before it (the turn rate held), until
// it returns to that or max_wheel_fault_s passes; the vision corrects the
// bearing meanwhile. Its threshold is wider than the ground speed's (one
// wheel's noise is √2 of the mean's, and a false alarm costs a turn rate),
// so the wheels' own noise never trips it.

#include "engine/common/options.h"

namespace plantscale::tracking {

struct SlipGuardOptions {
  bool enabled = true;
  double max_acceleration_m_s2 = 0.5;  // the vehicle's, beyond which wheels slip
  // A jump within a sample beyond this fraction of the speed (plus the
  // acceleration's share) is slip: about 4σ of the mean of two wheels
  // with 2 % noise each (field preset: 15 % slip is 10σ).
  double jump_fraction = 0.06;
  double min_speed_m_s = 0.1;     // the threshold's speed floor (starting, stopping)
  double reference_time_s = 0.05;  // the ground speed's smoothing (it lags a·τ when speeding up)
  double max_slip_s = 2.0;
  // One wheel's jump beyond this multiple of the ground speed's threshold,
  // with the other wheel within the threshold and the two pulled apart, is
  // a fault of that wheel alone
  // (about 8σ of one wheel with 2 % noise; a stalled encoder is 50σ).
  double wheel_fault_factor = 2.0;
  double max_wheel_fault_s = 30.0;  // a stalled encoder over 20 m at 0.7 m/s

  OptionErrors Validate() const;
};

// The σ of a faulty wheel's increment read from the other, as a fraction
// of the distance driven: the vehicle's steering over a few metres, which
// the held turn rate does not follow (field preset, tuning seeds 1–3 with
// the encoder stalled for 10 m: 0.1 and 0.3 alike).
inline constexpr double kWheelFaultSdFraction = 0.1;

struct WheelSpeeds {
  double left_m_s = 0.0;
  double right_m_s = 0.0;
};

class SlipGuard {
 public:
  explicit SlipGuard(const SlipGuardOptions& options = {});

  // One odometry sample of dt seconds: the wheel speeds to dead-reckon with.
  WheelSpeeds Filter(const WheelSpeeds& measured, double dt_s);
  bool slipping() const { return slipping_; }
  int bursts() const { return bursts_; }  // slips detected since Reset
  // One wheel's fault (0 none, 1 left, 2 right) and how many since Reset.
  int faulty_wheel() const { return faulty_wheel_; }
  int wheel_faults() const { return wheel_faults_; }
  void Reset();

 private:
  // How far a sample's speed may be from the reference: the jump fraction
  // of the speed, plus what the vehicle's acceleration may change over
  // `span_s`.
  double Threshold(double speed, double span_s) const;
  // The single-wheel check: the measured speeds with a faulty wheel read
  // from the other, and the per-wheel references kept.
  WheelSpeeds CheckWheels(const WheelSpeeds& measured, double dt_s);

  SlipGuardOptions options_;
  bool started_ = false;
  bool slipping_ = false;
  double reference_m_s_ = 0.0;  // smoothed ground speed
  double slip_s_ = 0.0;         // how long the current slip has lasted
  int bursts_ = 0;
  WheelSpeeds wheel_reference_;   // each wheel's smoothed speed
  double held_difference_m_s_ = 0.0;  // left − right when a wheel failed
  double wheel_fault_s_ = 0.0;
  int faulty_wheel_ = 0;
  int wheel_faults_ = 0;
};

}  // namespace plantscale::tracking
