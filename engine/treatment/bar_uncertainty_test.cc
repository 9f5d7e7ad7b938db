// Fail-safe on uncertainty: the 95 % ellipse of the plants' position at the
// bar, its prediction ahead checked against finite differences, and the
// scheduler closing the bar on it with the reason.
#include "engine/treatment/bar_uncertainty.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <numbers>

#include "engine/geometry/test_cameras.h"
#include "engine/treatment/nozzle_scheduler.h"
#include "engine/treatment/test_bar.h"
#include "engine/treatment/treatment_map.h"
#include "engine/treatment/treatment_system.h"

namespace plantscale::treatment {
namespace {

using geometry::GridState;
using geometry::Matrix5d;

TEST(EllipseReach, IsTheHalfExtentOfTheNinetyFivePercentEllipse) {
  Eigen::Matrix2d c;
  c << 4e-4, 1.5e-4, 1.5e-4, 1e-4;  // σ 20 mm across, 10 mm along, correlated
  const PlantReach r = EllipseReach(c);
  EXPECT_NEAR(r.across_m, std::sqrt(5.991 * 4e-4), 1e-12);
  EXPECT_NEAR(r.along_m, std::sqrt(5.991 * 1e-4), 1e-12);
  // The ellipse's boundary pᵀ C⁻¹ p = 5.991, walked: it reaches exactly so far.
  const Eigen::Matrix2d l = c.llt().matrixL();
  double across = 0.0, along = 0.0;
  for (int k = 0; k < 100000; ++k) {
    const double a = 2.0 * std::numbers::pi * k / 100000.0;
    const Eigen::Vector2d p = std::sqrt(5.991) * l * Eigen::Vector2d(std::cos(a), std::sin(a));
    across = std::max(across, std::abs(p.x()));
    along = std::max(along, std::abs(p.y()));
  }
  EXPECT_NEAR(r.across_m, across, 1e-6);
  EXPECT_NEAR(r.along_m, along, 1e-6);
}

TEST(LineAt, FindsThePlantNearestTheBar) {
  const GridState s{0.03, 0.7, 0.05, 0.475, 0.45};
  for (int n = -1; n <= 1; ++n) {
    for (double bar_y : {-0.6, -1.1, 0.2}) {
      const Eigen::Vector2d p = geometry::PlantInVehicle(s, LineAt(s, n, bar_y), n);
      EXPECT_LE(std::abs(p.y() - bar_y), 0.5 * s.plant_spacing_m * std::cos(s.bearing_rad) + 1e-9)
          << "row " << n << " bar " << bar_y;
    }
  }
}

// A tracker holding `state` with covariance `p`, its wheels at these speeds.
tracking::GridTracker Holding(const tracking::TrackerOptions& o, const GridState& state,
                              const Matrix5d& p, double left_m_s, double right_m_s) {
  static const geometry::CameraModel camera(geometry::testing::ThesisCamera());
  tracking::GridTracker t(camera, o);
  EXPECT_TRUE(t.AddOdometry(0, left_m_s, right_m_s).accepted);
  t.Initialise(0, state, p);
  return t;
}

tracking::TrackerOptions NoProcessNoise() {
  tracking::TrackerOptions o;
  o.wheel_sd_fraction = 0.0;
  o.forward_sd_per_sqrt_m = 0.0;
  o.lateral_sd_per_sqrt_m = 0.0;
  o.bearing_sd_per_sqrt_m = 0.0;
  o.estimate_odometry_scale = false;
  return o;
}

// Without process noise the plant's covariance at the bar is F P Fᵀ, F the
// Jacobian of "drive d ahead, then the plant at the bar" (the transitions of
// eq. 4.3 chained, then eq. A.1): against central differences of that map.
TEST(PredictAhead, PlantAtTheBarMatchesFiniteDifferencesOfTheDrive) {
  const tracking::TrackerOptions o = NoProcessNoise();
  const GridState x0{0.03, 0.8, 0.04, 0.48, 0.46};
  Matrix5d p0 = Matrix5d::Zero();
  p0.diagonal() << 4e-6, 9e-6, 1e-5, 4e-6, 2.5e-5;
  p0(0, 2) = p0(2, 0) = 3e-6;
  const double ahead = 1.6, step = 0.014, bar_y = -0.6;
  const double left = 0.70, right = 0.66;  // a gentle turn: Ψ changes on the way
  const tracking::GridAhead a = Holding(o, x0, p0, left, right).PredictAhead(ahead, step);
  EXPECT_GT(std::abs(a.state.bearing_rad - x0.bearing_rad), 0.01);
  for (int n = -1; n <= 1; ++n) {
    const int m = LineAt(a.state, n, bar_y);
    Eigen::Matrix<double, 2, 5> f;
    for (int i = 0; i < 5; ++i) {
      const double h = 1e-6;
      const auto at = [&](double sign) {
        const geometry::Vector5d x = x0.AsVector() + sign * h * geometry::Vector5d::Unit(i);
        const GridState s = GridState::FromVector(x);
        return geometry::PlantInVehicle(Holding(o, s, p0, left, right).PredictAhead(ahead, step).state, m, n);
      };
      f.col(i) = (at(1.0) - at(-1.0)) / (2.0 * h);
    }
    const Eigen::Matrix2d expected = f * p0 * f.transpose();
    const Eigen::Matrix2d got = PlantCovarianceAt(a.state, a.covariance, n, bar_y);
    EXPECT_LT((got - expected).norm(), 1e-4 * expected.norm()) << "row " << n << "\n"
                                                               << got << "\n" << expected;
  }
}

// The process noise over the distance: forward σ² grows by q_f·d from the
// forward walk and by (σ_w·δ)²/2 per increment δ from the two wheels.
TEST(PredictAhead, ForwardVarianceGrowsByTheDeadReckoningNoise) {
  tracking::TrackerOptions o = NoProcessNoise();
  o.forward_sd_per_sqrt_m = 0.005;
  o.wheel_sd_fraction = 0.03;
  const GridState x0{0.0, 0.8, 0.0, 0.475, 0.45};
  Matrix5d p0 = Matrix5d::Zero();
  p0.diagonal() << 1e-6, 1e-6, 1e-6, 1e-6, 1e-6;
  const tracking::GridTracker t = Holding(o, x0, p0, 0.7, 0.7);
  const double ahead = 1.4, step = 0.014;
  const tracking::GridAhead a = t.PredictAhead(ahead, step);
  const double expected = 1e-6 + 0.005 * 0.005 * ahead + 0.5 * std::pow(0.03 * step, 2) * ahead / step;
  EXPECT_NEAR(a.covariance(1, 1), expected, 1e-3 * expected);
  // Nothing ahead: the filter's own covariance.
  EXPECT_NEAR(t.PredictAhead(0.0, step).covariance(1, 1), 1e-6, 1e-15);
}

TEST(PlantReachAtBar, ZeroWhenTheGridIsNotHeld) {
  static const geometry::CameraModel camera(geometry::testing::ThesisCamera());
  tracking::GridTracker t(camera, tracking::TrackerOptions{});
  const PlantReach r = PlantReachAtBar(t, 0.05, 0.6, 0.014);
  EXPECT_EQ(r.across_m, 0.0);
  EXPECT_EQ(r.along_m, 0.0);
}

TEST(PlantReachAtBar, GrowsWithTheGridsCovarianceTheBarsOffsetAndTheDistanceDeadReckoned) {
  const tracking::TrackerOptions o;
  const GridState x0{0.0, 0.8, 0.0, 0.475, 0.45};
  Matrix5d p0 = Matrix5d::Zero();
  p0.diagonal() << 4e-6, 4e-6, 1e-6, 1e-6, 1e-6;
  const PlantReach near = PlantReachAtBar(Holding(o, x0, p0, 0.7, 0.7), 0.042, 0.6, 0.014);
  EXPECT_NEAR(near.ahead_m, 0.042, 1e-12);
  const PlantReach far = PlantReachAtBar(Holding(o, x0, p0, 0.7, 0.7), 0.042, 1.6, 0.014);
  const PlantReach coasted = PlantReachAtBar(Holding(o, x0, p0, 0.7, 0.7), 1.4, 0.6, 0.014);
  const PlantReach loose = PlantReachAtBar(Holding(o, x0, 4.0 * p0, 0.7, 0.7), 0.042, 0.6, 0.014);
  // A bar further behind: Ψ's and l̄'s lever arms are longer.
  EXPECT_GT(far.along_m, near.along_m);
  EXPECT_GT(far.across_m, near.across_m);
  EXPECT_GT(coasted.along_m, near.along_m);
  EXPECT_GT(coasted.across_m, near.across_m);
  EXPECT_GT(loose.along_m, near.along_m);
  // At least the filter's own σ(Y) = 2 mm, times √5.991.
  EXPECT_GT(near.along_m, std::sqrt(5.991) * 0.002);
}

// The shared test bar, its valves at the default latency, with the
// fail-safe's reach limits this file's plants are judged against.
SchedulerOptions Bar() {
  SchedulerOptions o = testing::TestBar(SprayBarOptions{}.valve_latency_s);
  o.fail_safe.max_reach_across_m = 0.036;
  o.fail_safe.max_reach_along_m = 0.025;
  return o;
}

using testing::Healthy;

TEST(NozzleScheduler, ClosesWhileThePlantsPositionAtTheBarIsUncertainAndSaysWhy) {
  TreatmentMapOptions mo;
  mo.majority_threshold = 1;
  TreatmentMap map(mo);
  map.AddFootprint({Eigen::Vector2d(-1.0, -1.0), Eigen::Vector2d(1.0, -1.0),
                    Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(-1.0, 1.0)},
                   true);  // crop everywhere under the bar
  uint64_t last = 0;
  NozzleScheduler scheduler(Bar(), [&](int64_t, uint64_t m) { last = m; });
  BedPose pose;
  pose.distance_m = 0.5;
  const int64_t now = 1'000'000;
  SafetyInputs in = Healthy(now);
  in.reach_across_m = 0.036;  // at the margins: still open
  in.reach_along_m = 0.025;
  EXPECT_EQ(scheduler.Tick(now, pose, map, in).open_mask, 0xFFu);
  in.reach_along_m = 0.031;
  TickResult r = scheduler.Tick(now, pose, map, in);
  EXPECT_EQ(r.open_mask, 0u);
  EXPECT_EQ(last, 0u);
  EXPECT_EQ(r.fail_reasons, kPositionUncertain);
  ASSERT_EQ(r.messages.size(), 1u);
  EXPECT_EQ(r.messages[0], "plant position uncertain at the bar (95 % ellipse reaches 31 mm along > 25 mm)");
  in.reach_along_m = 0.01;
  in.reach_across_m = 0.04;
  r = scheduler.Tick(now, pose, map, in);
  EXPECT_EQ(r.fail_reasons, kPositionUncertain);
  EXPECT_EQ(r.messages.at(0), "plant position uncertain at the bar (95 % ellipse reaches 40 mm across > 36 mm)");
  EXPECT_EQ(FailReasonMessages(r.fail_reasons).at(0), "plant position uncertain");
  // A lost grid is its own reason: its reach means nothing.
  in.tracking = false;
  EXPECT_EQ(scheduler.Tick(now, pose, map, in).fail_reasons, kTrackerLost);
}

TEST(NozzleScheduler, ReachMarginsArePositive) {
  SchedulerOptions o = Bar();
  o.fail_safe.max_reach_along_m = 0.0;
  o.fail_safe.max_reach_across_m = std::nan("");
  const OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].key, "fail_safe.max_reach_across_m");
  EXPECT_EQ(e[1].key, "fail_safe.max_reach_along_m");
  o.fail_safe.max_reach_along_m = std::numeric_limits<double>::infinity();
  o.fail_safe.max_reach_across_m = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(o.Validate().empty());
}

TEST(TreatmentOptions, UncertaintyMarginIsDerivedFromTheFootprintUnlessSet) {
  TreatmentOptions o;
  o.close_on_uncertainty = true;
  o.crop_footprint_min_half_m = 0.025;
  o.scheduler.bar.nozzle_spacing_m = 0.0225;
  // Across: the footprint's least half size and half a nozzle; along: the half size.
  EXPECT_NEAR(o.UncertaintyMargin().x(), 0.025 + 0.01125, 1e-12);
  EXPECT_NEAR(o.UncertaintyMargin().y(), 0.025, 1e-12);
  // For the field's crop (0.14 m): the scaled box, 42 mm.
  o.crop_footprint_scale = 0.30;
  EXPECT_NEAR(o.UncertaintyMargin(0.14).y(), 0.042, 1e-12);
  EXPECT_NEAR(o.UncertaintyMargin(0.14).x(), 0.042 + 0.01125, 1e-12);
  EXPECT_NEAR(o.UncertaintyMargin(0.05).y(), 0.025, 1e-12);  // at least the least half size
  o.uncertainty_margin_along_m = 0.04;
  EXPECT_NEAR(o.UncertaintyMargin().y(), 0.04, 1e-12);
  o.close_on_uncertainty = false;
  EXPECT_TRUE(std::isinf(o.UncertaintyMargin().x()));
  EXPECT_TRUE(o.Validate().empty());
  o.close_on_uncertainty = true;
  o.uncertainty_margin_across_m = -0.01;
  OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].key, "uncertainty_margin_across_m");
  // Nothing to derive from: say so.
  o.uncertainty_margin_across_m = 0.0;
  o.uncertainty_margin_along_m = 0.0;
  o.crop_footprint_min_half_m = 0.0;
  e = o.Validate();
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].reason.find("derives no margin"), std::string::npos);
}

// The treatment's scheduler takes the margins it derives.
TEST(TreatmentSystem, SchedulerClosesOnTheDerivedMargins) {
  const geometry::CameraModel camera(geometry::testing::ThesisCamera());
  TreatmentOptions o;
  o.close_on_uncertainty = true;
  const TreatmentSystem system(camera, o);
  EXPECT_NEAR(system.options().scheduler.fail_safe.max_reach_across_m, o.UncertaintyMargin().x(), 1e-12);
  EXPECT_NEAR(system.options().scheduler.fail_safe.max_reach_along_m, o.UncertaintyMargin().y(), 1e-12);
  // The thesis camera sees the ground from about 1 m ahead.
  EXPECT_GT(system.view_near_y_m(), 0.3);
  EXPECT_LT(system.view_near_y_m(), 2.0);
}

}  // namespace
}  // namespace plantscale::treatment
