#include "engine/tracking/slip_guard.h"

#include <gtest/gtest.h>

#include <random>

namespace plantscale::tracking {
namespace {

constexpr double kDt = 0.02;  // 50 Hz

TEST(SlipGuard, ABurstOfWheelSpinIsDeadReckonedAtTheGroundSpeedBeforeIt) {
  SlipGuard guard;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.014);  // 2 % of 0.7 m/s per wheel
  const double v = 0.7, spin = 1.15;
  double burst_error = 0.0, burst_error_raw = 0.0;
  for (int k = 0; k < 300; ++k) {
    const bool in_burst = k >= 100 && k < 130;  // 0.6 s, 0.42 m
    const double f = in_burst ? spin : 1.0;
    const WheelSpeeds measured{f * v + noise(rng), f * v + noise(rng)};
    const WheelSpeeds w = guard.Filter(measured, kDt);
    const double used = 0.5 * (w.left_m_s + w.right_m_s);
    if (in_burst) {
      EXPECT_TRUE(guard.slipping()) << "sample " << k;
      burst_error += (used - v) * kDt;
      burst_error_raw += (0.5 * (measured.left_m_s + measured.right_m_s) - v) * kDt;
    } else {
      EXPECT_FALSE(guard.slipping()) << "sample " << k;
      EXPECT_EQ(used, 0.5 * (measured.left_m_s + measured.right_m_s));
    }
  }
  EXPECT_EQ(guard.bursts(), 1);
  // The wheels said 63 mm too far over the burst; the guard's speed is off
  // only by the noise in the ground speed it held (sd 2.6 mm/s → 1.6 mm).
  EXPECT_NEAR(burst_error_raw, 0.063, 0.005);
  EXPECT_LT(std::abs(burst_error), 0.005);
}

TEST(SlipGuard, TheVehicleSpeedingUpWithinItsTractionIsNotSlip) {
  SlipGuard guard;
  double v = 0.2;
  for (int k = 0; k < 200; ++k) {
    v += 0.4 * kDt;  // 0.4 m/s², within the 0.5 m/s² limit
    const WheelSpeeds w = guard.Filter({v, v}, kDt);
    EXPECT_FALSE(guard.slipping()) << "sample " << k << " at " << v << " m/s";
    EXPECT_EQ(w.left_m_s, v);
  }
  EXPECT_EQ(guard.bursts(), 0);
}

TEST(SlipGuard, AJumpThatLastsIsTakenAsAChangeOfSpeedAfterMaxSlip) {
  SlipGuardOptions o;
  o.max_slip_s = 0.5;
  SlipGuard guard(o);
  for (int k = 0; k < 20; ++k) guard.Filter({0.7, 0.7}, kDt);
  int held = 0;
  for (int k = 0; k < 60; ++k) {
    const WheelSpeeds w = guard.Filter({0.9, 0.9}, kDt);
    if (guard.slipping()) {
      ++held;
      EXPECT_NEAR(w.left_m_s, 0.7, 1e-9);
    } else {
      EXPECT_EQ(w.left_m_s, 0.9);
    }
  }
  EXPECT_NEAR(held, 26, 1);  // 0.5 s of 20 ms samples, then the wheels are believed
  EXPECT_FALSE(guard.slipping());
}

// A stalled left encoder (reads 0 for 10 m) beside a right wheel at speed,
// in a gentle turn: the left wheel is read as the right one plus the
// difference they held, so speed and turn rate go on; the encoder's return
// ends it. Without the check the ground speed halved and, scaled back up,
// the right wheel alone drove a hard turn.
TEST(SlipGuard, AStalledEncoderIsReadFromTheOtherWheelWithTheTurnRateHeld) {
  SlipGuard guard;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.014);
  const double left = 0.68, right = 0.72;  // left − right: −0.04 m/s
  double distance_error = 0.0, turn_error = 0.0;
  for (int k = 0; k < 1200; ++k) {
    const bool stalled = k >= 100 && k < 814;  // 10 m at 0.7 m/s
    const WheelSpeeds measured{stalled ? 0.0 : left + noise(rng), right + noise(rng)};
    const WheelSpeeds w = guard.Filter(measured, kDt);
    EXPECT_FALSE(guard.slipping()) << "sample " << k;
    if (stalled) {
      EXPECT_EQ(guard.faulty_wheel(), 1) << "sample " << k;
      EXPECT_EQ(w.right_m_s, measured.right_m_s);
      distance_error += (0.5 * (w.left_m_s + w.right_m_s) - 0.7) * kDt;
      turn_error += (w.left_m_s - w.right_m_s - (left - right)) * kDt;
    } else if (k > 820) {
      EXPECT_EQ(guard.faulty_wheel(), 0) << "sample " << k;
      EXPECT_EQ(w.left_m_s, measured.left_m_s);
    }
  }
  EXPECT_EQ(guard.wheel_faults(), 1);
  EXPECT_EQ(guard.bursts(), 0);
  // Over the 10 m: the right wheel's noise (sd 14 mm/s, 714 samples: 7 mm)
  // and the held difference's (a few mm/s over 14 s).
  EXPECT_LT(std::abs(distance_error), 0.05);
  // Wheel-path difference, m: 0.15 m is 0.1 rad of heading at a 1.5 m track.
  EXPECT_LT(std::abs(turn_error), 0.15);
}

TEST(SlipGuard, BothWheelsSpinningIsSlipNotAWheelFaultAndNoiseTripsNeither) {
  SlipGuard guard;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.014);
  for (int k = 0; k < 20000; ++k) {  // 400 s, 280 m of noisy wheels
    const double f = (k >= 10000 && k < 10030) ? 1.3 : 1.0;
    guard.Filter({f * 0.7 + noise(rng), f * 0.7 + noise(rng)}, kDt);
    EXPECT_EQ(guard.faulty_wheel(), 0) << "sample " << k;
  }
  EXPECT_EQ(guard.wheel_faults(), 0);
  EXPECT_EQ(guard.bursts(), 1);
}

// The field preset's seed 5 starts in a turn and straightens within one
// sample: the right wheel jumps by 0.14 m/s, the left by 0.11. That brings
// the wheels together; it is steering, not one wheel's fault (read as one,
// it held the turn for 30 s and lost the grid).
TEST(SlipGuard, AVehicleStraighteningWithinASampleIsNotAWheelFault) {
  SlipGuard guard;
  for (int k = 0; k < 20; ++k) guard.Filter({0.833, 0.524}, kDt);
  guard.Filter({0.692, 0.668}, kDt);  // the samples the vehicle logged
  for (int k = 0; k < 20; ++k) {
    const WheelSpeeds w = guard.Filter({0.683, 0.703}, kDt);
    EXPECT_EQ(w.right_m_s, 0.703) << "sample " << k;
    EXPECT_EQ(w.left_m_s, 0.683) << "sample " << k;
  }
  EXPECT_EQ(guard.wheel_faults(), 0);
}

TEST(SlipGuard, OffPassesTheWheelsThroughAndBadOptionsAreNamed) {
  SlipGuardOptions o;
  o.enabled = false;
  SlipGuard guard(o);
  guard.Filter({0.7, 0.7}, kDt);
  const WheelSpeeds w = guard.Filter({1.4, 1.4}, kDt);
  EXPECT_EQ(w.left_m_s, 1.4);
  EXPECT_FALSE(guard.slipping());
  o.jump_fraction = 0.0;
  o.max_acceleration_m_s2 = -1.0;
  const OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].key, "max_acceleration_m_s2");
  EXPECT_EQ(e[1].key, "jump_fraction");
}

}  // namespace
}  // namespace plantscale::tracking
