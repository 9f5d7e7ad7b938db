#include "engine/sim/vehicle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace plantscale::sim {
namespace {

// A vehicle with every error source switched off.
VehicleOptions Ideal() {
  VehicleOptions o;
  o.zigzag_amplitude_m = 0.0;
  o.heading_wander_sd_rad = 0.0;
  o.odometry_noise_fraction = 0.0;
  o.odometry_scale_error = 0.0;
  o.wheel_scale_difference = 0.0;
  o.slip_bursts_per_100m = 0.0;
  o.bump_pitch_sd_rad = 0.0;
  o.bump_roll_sd_rad = 0.0;
  o.bump_height_sd_m = 0.0;
  return o;
}

bool HasKey(const OptionErrors& errors, const std::string& key) {
  return std::any_of(errors.begin(), errors.end(),
                     [&](const OptionError& e) { return e.key == key; });
}

TEST(Vehicle, WithoutErrorsDrivesStraightAtSpeed) {
  VehicleOptions o = Ideal();
  o.speed_m_s = 0.8;
  o.odometry_rate_hz = 50.0;
  Vehicle vehicle(o, 11);
  constexpr int kSteps = 377;
  for (int i = 0; i < kSteps; ++i) {
    const OdometrySample s = vehicle.Step();
    // Odometry equals the true wheel speeds, and both equal the forward speed.
    EXPECT_NEAR(s.left_m_s, s.true_left_m_s, 1e-12);
    EXPECT_NEAR(s.right_m_s, s.true_right_m_s, 1e-12);
    EXPECT_NEAR(s.true_left_m_s, 0.8, 1e-12);
    EXPECT_NEAR(s.true_right_m_s, 0.8, 1e-12);
    EXPECT_FALSE(s.slipping);
    EXPECT_EQ(s.utime, (i + 1) * int64_t{20000});  // 1/50 s in µs, exactly
  }
  const double expected = kSteps * 0.8 / 50.0;
  EXPECT_NEAR(vehicle.distance_m(), expected, 1e-9);
  EXPECT_NEAR(vehicle.pose().y_m, expected, 1e-9);
  EXPECT_NEAR(vehicle.pose().x_m, 0.0, 1e-12);
  EXPECT_NEAR(vehicle.pose().heading_rad, 0.0, 1e-12);
  EXPECT_EQ(vehicle.utime(), kSteps * int64_t{20000});
  // No bounce either.
  EXPECT_EQ(vehicle.bounce().pitch_rad, 0.0);
  EXPECT_EQ(vehicle.bounce().roll_rad, 0.0);
  EXPECT_EQ(vehicle.bounce().height_m, 0.0);
}

TEST(Vehicle, StartsAtTheGivenOffsetAndKeepsIt) {
  VehicleOptions o = Ideal();
  o.start_offset_m = 0.12;
  Vehicle vehicle(o, 1);
  for (int i = 0; i < 200; ++i) vehicle.Step();
  EXPECT_NEAR(vehicle.pose().x_m, 0.12, 1e-12);
  EXPECT_NEAR(vehicle.pose().y_m, 200 * 0.7 / 50.0, 1e-9);
}

TEST(Vehicle, ZigzagStaysWithinAmplitudeAndOscillatesAtWavelength) {
  VehicleOptions o = Ideal();
  o.zigzag_amplitude_m = 0.05;
  o.zigzag_wavelength_m = 4.0;
  Vehicle vehicle(o, 5);
  const double k = 2.0 * std::numbers::pi / o.zigzag_wavelength_m;
  const double k_other = k / 1.5;  // a wavelength of 6 m: 2 whole periods in [4, 16]
  double max_abs_x = 0.0;
  double sin_sum = 0.0, cos_sum = 0.0, other_sin = 0.0, other_cos = 0.0;
  int samples = 0;
  std::vector<double> upward_crossings_y;
  double previous_x = 0.0;
  while (vehicle.pose().y_m < 16.0) {
    vehicle.Step();
    const Pose2& p = vehicle.pose();
    max_abs_x = std::max(max_abs_x, std::abs(p.x_m));
    if (p.y_m < 4.0) {  // one wavelength to settle
      previous_x = p.x_m;
      continue;
    }
    sin_sum += p.x_m * std::sin(k * p.y_m);
    cos_sum += p.x_m * std::cos(k * p.y_m);
    other_sin += p.x_m * std::sin(k_other * p.y_m);
    other_cos += p.x_m * std::cos(k_other * p.y_m);
    ++samples;
    if (previous_x < 0.0 && p.x_m >= 0.0) upward_crossings_y.push_back(p.y_m);
    previous_x = p.x_m;
  }
  // Lateral position within A plus 10 % of A (the pull-back overshoots a little).
  EXPECT_LE(max_abs_x, 0.05 * 1.1);
  // Fourier components over three whole wavelengths: x ≈ A sin(2πy/λ).
  const double amplitude = 2.0 * std::hypot(sin_sum, cos_sum) / samples;
  EXPECT_NEAR(amplitude, 0.05, 0.003);
  EXPECT_NEAR(2.0 * sin_sum / samples, 0.05, 0.003);  // in phase with the reference
  const double other_amplitude = 2.0 * std::hypot(other_sin, other_cos) / samples;
  EXPECT_LT(other_amplitude, 0.005);  // nothing at a 6 m wavelength (< 10 % of A)
  // Upward zero crossings one wavelength apart (±5 cm, ≈ 4 odometry steps).
  ASSERT_GE(upward_crossings_y.size(), 2U);
  for (size_t i = 1; i < upward_crossings_y.size(); ++i) {
    EXPECT_NEAR(upward_crossings_y[i] - upward_crossings_y[i - 1], 4.0, 0.05);
  }
}

TEST(Vehicle, WheelSpeedsFollowEquation43) {
  // Thesis eq. 4.3: forward speed = (v_l + v_r)/2, turn rate = (v_r − v_l)/W,
  // checked against the pose change of every step; a turn to the left (CCW,
  // positive heading) needs the right wheel faster.
  VehicleOptions o = Ideal();
  o.zigzag_amplitude_m = 0.08;
  o.zigzag_wavelength_m = 5.0;
  o.heading_wander_sd_rad = 0.01;
  o.track_width_m = 1.3;
  o.speed_m_s = 0.9;
  Vehicle vehicle(o, 17);
  const double dt = 1.0 / o.odometry_rate_hz;
  int left_turns = 0;
  int right_turns = 0;
  for (int i = 0; i < 600; ++i) {
    const Pose2 before = vehicle.pose();
    const OdometrySample s = vehicle.Step();
    const Pose2& after = vehicle.pose();
    const double forward = 0.5 * (s.true_left_m_s + s.true_right_m_s);
    const double turn_rate = (s.true_right_m_s - s.true_left_m_s) / o.track_width_m;
    EXPECT_NEAR(forward, 0.9, 1e-9);
    EXPECT_NEAR((after.heading_rad - before.heading_rad) / dt, turn_rate, 1e-9);
    EXPECT_NEAR(std::hypot(after.x_m - before.x_m, after.y_m - before.y_m), forward * dt, 1e-9);
    // Motion along the mean heading of the step: forward is (−sin ψ, cos ψ).
    const double mid = 0.5 * (before.heading_rad + after.heading_rad);
    EXPECT_NEAR(after.x_m - before.x_m, -forward * dt * std::sin(mid), 1e-12);
    EXPECT_NEAR(after.y_m - before.y_m, forward * dt * std::cos(mid), 1e-12);
    // Without odometry errors the measured speeds are the true ones.
    EXPECT_NEAR(s.left_m_s, s.true_left_m_s, 1e-12);
    EXPECT_NEAR(s.right_m_s, s.true_right_m_s, 1e-12);
    if (turn_rate > 1e-4) ++left_turns;
    if (turn_rate < -1e-4) ++right_turns;
  }
  // The zig-zag turns both ways, so both signs were exercised.
  EXPECT_GT(left_turns, 50);
  EXPECT_GT(right_turns, 50);
}

TEST(Vehicle, OdometryScaleErrorMakesDistanceLong) {
  VehicleOptions o = Ideal();
  o.odometry_scale_error = 0.05;
  o.odometry_noise_fraction = 0.02;
  o.zigzag_amplitude_m = 0.03;
  Vehicle vehicle(o, 23);
  const double dt = 1.0 / o.odometry_rate_hz;
  double measured = 0.0;
  constexpr int kSteps = 500;
  for (int i = 0; i < kSteps; ++i) {
    const OdometrySample s = vehicle.Step();
    measured += 0.5 * (s.left_m_s + s.right_m_s) * dt;
  }
  // Noise in the summed distance: sd = dt·0.02·v/√2·√N ≈ 0.0044 m over 7 m,
  // i.e. 0.06 % of the distance; the tolerance 0.3 % is five of those.
  const double fraction = measured / vehicle.distance_m() - 1.0;
  EXPECT_NEAR(fraction, 0.05, 0.003);
}

TEST(Vehicle, WheelScaleDifferenceReadsAsATurn) {
  VehicleOptions o = Ideal();
  o.wheel_scale_difference = 0.02;  // right long by 1 %, left short by 1 %
  Vehicle vehicle(o, 2);
  for (int i = 0; i < 20; ++i) {
    const OdometrySample s = vehicle.Step();
    EXPECT_NEAR(s.right_m_s, s.true_right_m_s * 1.01, 1e-12);
    EXPECT_NEAR(s.left_m_s, s.true_left_m_s * 0.99, 1e-12);
  }
}

TEST(Vehicle, SlipBurstsReadFasterThanTheGround) {
  VehicleOptions o = Ideal();
  o.slip_bursts_per_100m = 40.0;
  o.slip_burst_length_m = 0.3;
  o.slip_fraction = 0.15;
  Vehicle vehicle(o, 31);
  const double ds = o.speed_m_s / o.odometry_rate_hz;
  // Each burst lasts ceil(0.3 m / 14 mm) = 22 steps; a new burst may start
  // the step after one ends, so a completed run is a whole number of bursts.
  const int burst_steps = static_cast<int>(std::ceil(0.3 / ds));
  int slipping = 0;
  int bursts = 0;
  int run = 0;
  std::vector<int> completed_runs;
  for (int i = 0; i < 3000; ++i) {
    const OdometrySample s = vehicle.Step();
    if (s.slipping) {
      ++slipping;
      if (run == 0) ++bursts;
      ++run;
      // The wheels turn 15 % faster than the ground under them.
      EXPECT_GT(s.left_m_s, s.true_left_m_s);
      EXPECT_GT(s.right_m_s, s.true_right_m_s);
      EXPECT_NEAR(s.left_m_s, 1.15 * s.true_left_m_s, 1e-12);
      EXPECT_NEAR(s.right_m_s, 1.15 * s.true_right_m_s, 1e-12);
    } else {
      if (run > 0) completed_runs.push_back(run);
      run = 0;
      EXPECT_NEAR(s.left_m_s, s.true_left_m_s, 1e-12);
      EXPECT_NEAR(s.right_m_s, s.true_right_m_s, 1e-12);
    }
  }
  // 42 m driven at 40 bursts per 100 m, minus the slipping distance: about
  // 13 bursts (Poisson sd ≈ 3.6); accept 5..30.
  EXPECT_GE(bursts, 5);
  EXPECT_LE(bursts, 30);
  ASSERT_FALSE(completed_runs.empty());
  for (int length : completed_runs) EXPECT_EQ(length % burst_steps, 0) << length;
  EXPECT_GT(slipping, 0);
}

void ExpectSameSample(const OdometrySample& a, const OdometrySample& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.left_m_s, b.left_m_s);
  EXPECT_EQ(a.right_m_s, b.right_m_s);
  EXPECT_EQ(a.true_left_m_s, b.true_left_m_s);
  EXPECT_EQ(a.true_right_m_s, b.true_right_m_s);
  EXPECT_EQ(a.slipping, b.slipping);
}

TEST(Vehicle, SameSeedSameRunDifferentSeedDifferentRun) {
  VehicleOptions o;  // defaults: every noise source on
  o.slip_bursts_per_100m = 20.0;
  Vehicle a(o, 99);
  Vehicle b(o, 99);
  Vehicle c(o, 100);
  double max_difference = 0.0;
  for (int i = 0; i < 300; ++i) {
    const OdometrySample sa = a.Step();
    const OdometrySample sb = b.Step();
    const OdometrySample sc = c.Step();
    ExpectSameSample(sa, sb);
    EXPECT_EQ(a.pose().x_m, b.pose().x_m);
    EXPECT_EQ(a.pose().y_m, b.pose().y_m);
    EXPECT_EQ(a.pose().heading_rad, b.pose().heading_rad);
    EXPECT_EQ(a.bounce().pitch_rad, b.bounce().pitch_rad);
    EXPECT_EQ(a.bounce().roll_rad, b.bounce().roll_rad);
    EXPECT_EQ(a.bounce().height_m, b.bounce().height_m);
    max_difference = std::max(max_difference, std::abs(sa.left_m_s - sc.left_m_s));
  }
  // Different seeds: the odometry noise (sd 0.014 m/s) differs by far more than 1 mm/s.
  EXPECT_GT(max_difference, 1e-3);
}

TEST(Vehicle, ValidateNamesBadKeys) {
  EXPECT_TRUE(VehicleOptions{}.Validate().empty());
  {
    VehicleOptions o;
    o.speed_m_s = -0.5;
    o.track_width_m = 0.0;
    o.zigzag_wavelength_m = -1.0;
    o.slip_fraction = 1.5;
    const OptionErrors errors = o.Validate();
    EXPECT_TRUE(HasKey(errors, "speed_m_s"));
    EXPECT_TRUE(HasKey(errors, "track_width_m"));
    EXPECT_TRUE(HasKey(errors, "zigzag_wavelength_m"));
    EXPECT_TRUE(HasKey(errors, "slip_fraction"));
    EXPECT_EQ(errors.size(), 4U);
  }
  {
    VehicleOptions o;
    o.odometry_rate_hz = 10.0;  // below the 12.5 Hz frame rate
    EXPECT_TRUE(HasKey(o.Validate(), "odometry_rate_hz"));
  }
  {
    VehicleOptions o;
    o.odometry_noise_fraction = std::nan("");
    EXPECT_TRUE(HasKey(o.Validate(), "odometry_noise_fraction"));
  }
  VehicleOptions bad;
  bad.speed_m_s = 0.0;  // the range (0, 5] excludes a standing vehicle
  try {
    Vehicle vehicle(bad, 1);
    ADD_FAILURE() << "Vehicle accepted speed_m_s = 0";
  } catch (const InvalidOptionsError& e) {
    EXPECT_TRUE(HasKey(e.errors(), "speed_m_s"));
    EXPECT_NE(std::string(e.what()).find("speed_m_s"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace plantscale::sim
