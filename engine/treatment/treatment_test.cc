#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "engine/geometry/grid_model.h"
#include "engine/treatment/bed_frame.h"
#include "engine/treatment/nozzle_scheduler.h"
#include "engine/treatment/plant_registry.h"
#include "engine/treatment/simulated_bar.h"
#include "engine/treatment/test_bar.h"
#include "engine/treatment/treatment_map.h"
#include "engine/treatment/treatment_system.h"

namespace plantscale::treatment {
namespace {

BedPose Pose(double offset, double bearing, double distance, double speed = 0.0) {
  BedPose p;
  p.offset_m = offset;
  p.bearing_rad = bearing;
  p.distance_m = distance;
  p.speed_m_s = speed;
  return p;
}

Quad Square(double x, double y, double half) {
  return {Eigen::Vector2d(x - half, y - half), Eigen::Vector2d(x + half, y - half),
          Eigen::Vector2d(x + half, y + half), Eigen::Vector2d(x - half, y + half)};
}

TEST(BedFrame, RoundTripAndGridPlantsStayPut) {
  const BedPose p = Pose(0.03, 0.05, 2.0);
  const Eigen::Vector2d v(0.4, 1.3);
  EXPECT_NEAR((BedToVehicle(p, VehicleToBed(p, v)) - v).norm(), 0.0, 1e-12);
  // A quad's corners each as a point.
  const Quad q{v, Eigen::Vector2d(0.5, 1.3), Eigen::Vector2d(0.5, 1.6), Eigen::Vector2d(0.4, 1.6)};
  const Quad bed = VehicleToBed(p, q);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(bed[i], VehicleToBed(p, q[i]));
  EXPECT_GT((bed[2] - bed[0]).norm(), 0.3);
  // Plant (m, n) of a grid state maps to bed (n r̄, s + m l̄ + Y); after a
  // reference shift (m → m − 1, Y → Y + l̄) the same plant keeps its place.
  geometry::GridState g;
  g.offset_m = 0.03;
  g.bearing_rad = 0.05;
  g.forward_m = 0.2;
  const double s = 2.0 - g.forward_m;  // forward_distance = passed − Y
  const Eigen::Vector2d b1 =
      VehicleToBed(BedPoseFromGrid(0, g, s, 0.0), geometry::PlantInVehicle(g, 2, 1));
  EXPECT_NEAR(b1.x(), g.row_spacing_m, 1e-12);
  EXPECT_NEAR(b1.y(), 2.0 + 2 * g.plant_spacing_m, 1e-12);
  geometry::GridState shifted = g;
  shifted.forward_m += g.plant_spacing_m;
  const Eigen::Vector2d b2 = VehicleToBed(BedPoseFromGrid(0, shifted, s, 0.0),
                                          geometry::PlantInVehicle(shifted, 1, 1));
  EXPECT_NEAR((b1 - b2).norm(), 0.0, 1e-12);
}

TEST(TreatmentMap, MajorityWithThreshold) {
  TreatmentMapOptions o;
  o.majority_threshold = 2;
  TreatmentMap map(o);
  const Eigen::Vector2d c(0.1, 1.0);
  // A 40 mm square covers 3 × 3 cells of 13.33 mm.
  EXPECT_EQ(map.AddFootprint(Square(c.x(), c.y(), 0.02), true), 9);
  EXPECT_EQ(map.ClassAt(c), CellClass::kSoil);  // one vote < threshold
  map.AddFootprint(Square(c.x(), c.y(), 0.02), true);
  EXPECT_EQ(map.ClassAt(c), CellClass::kCrop);
  map.AddFootprint(Square(c.x(), c.y(), 0.02), false);
  map.AddFootprint(Square(c.x(), c.y(), 0.02), false);
  EXPECT_EQ(map.ClassAt(c), CellClass::kCrop);  // 2 : 2 goes to crop
  map.AddFootprint(Square(c.x(), c.y(), 0.02), false);
  EXPECT_EQ(map.ClassAt(c), CellClass::kWeed);
  EXPECT_EQ(map.ClassAt({0.3, 1.0}), CellClass::kSoil);
  EXPECT_TRUE(map.AnyIn(0.09, 0.11, 0.99, 1.01, CellClass::kWeed));
  EXPECT_FALSE(map.AnyIn(0.2, 0.3, 0.99, 1.01, CellClass::kWeed));
  map.Clear();
  EXPECT_EQ(map.ClassAt(c), CellClass::kSoil);
}

// A weed cell may need fewer votes than a crop cell (spray-weed mode: a
// weed missed costs more than a drop of herbicide); 0 takes the crop's.
TEST(TreatmentMap, WeedCellsHaveTheirOwnThreshold) {
  TreatmentMapOptions o;
  o.majority_threshold = 3;
  o.weed_majority_threshold = 1;
  TreatmentMap map(o);
  const Eigen::Vector2d w(0.1, 1.0), c(0.5, 1.0);
  map.AddFootprint(Square(w.x(), w.y(), 0.02), false);
  EXPECT_EQ(map.ClassAt(w), CellClass::kWeed);  // one vote is enough for a weed
  map.AddFootprint(Square(c.x(), c.y(), 0.02), true);
  map.AddFootprint(Square(c.x(), c.y(), 0.02), true);
  EXPECT_EQ(map.ClassAt(c), CellClass::kSoil);  // two are not for a crop
  map.AddFootprint(Square(c.x(), c.y(), 0.02), false);
  map.AddFootprint(Square(c.x(), c.y(), 0.02), false);
  EXPECT_EQ(map.ClassAt(c), CellClass::kSoil);  // 2 : 2, the crop short of its threshold
  map.AddFootprint(Square(c.x(), c.y(), 0.02), false);
  EXPECT_EQ(map.ClassAt(c), CellClass::kWeed);  // 2 : 3
  map.AddFootprint(Square(c.x(), c.y(), 0.02), true);
  EXPECT_EQ(map.ClassAt(c), CellClass::kCrop);  // 3 : 3 goes to crop
  // Doubt votes (touching plants merged) hold a crop cell back but make no weed.
  const Eigen::Vector2d d(0.9, 1.0);
  for (int k = 0; k < 3; ++k) map.AddFootprint(Square(d.x(), d.y(), 0.02), true);
  EXPECT_EQ(map.ClassAt(d), CellClass::kCrop);
  for (int k = 0; k < 4; ++k) map.AddDoubt(Square(d.x(), d.y(), 0.02));
  EXPECT_EQ(map.ClassAt(d), CellClass::kSoil);  // 3 crop against 4 doubt
  map.AddFootprint(Square(d.x(), d.y(), 0.02), true);
  EXPECT_EQ(map.ClassAt(d), CellClass::kCrop);  // 4 : 4
  map.AddFootprint(Square(d.x(), d.y(), 0.02), false);
  EXPECT_EQ(map.ClassAt(d), CellClass::kSoil);  // 4 against 1 weed + 4 doubt, and no weed cell
  EXPECT_EQ(map.Counts(0, 0).doubt, 0);
  o.weed_majority_threshold = 0;  // as the crop's
  TreatmentMap same(o);
  same.AddFootprint(Square(w.x(), w.y(), 0.02), false);
  same.AddFootprint(Square(w.x(), w.y(), 0.02), false);
  EXPECT_EQ(same.ClassAt(w), CellClass::kSoil);
  same.AddFootprint(Square(w.x(), w.y(), 0.02), false);
  EXPECT_EQ(same.ClassAt(w), CellClass::kWeed);
  o.weed_majority_threshold = -1;
  EXPECT_THROW(TreatmentMap{o}, InvalidOptionsError);
}

TEST(TreatmentMap, ColumnSpansCountTheFootprintsCellsAnywhereAlong) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> centre(-0.5, 0.5), half(0.01, 0.12), angle(0.0, 6.3);
  for (int trial = 0; trial < 50; ++trial) {
    // A random convex quad: corners at increasing angles on an ellipse.
    const Eigen::Vector2d c(centre(rng), 1.0 + centre(rng));
    const double hx = half(rng), hy = half(rng);
    std::array<double, 4> a = {angle(rng), angle(rng), angle(rng), angle(rng)};
    std::sort(a.begin(), a.end());
    Quad q;
    for (size_t i = 0; i < 4; ++i) q[i] = c + Eigen::Vector2d(hx * std::cos(a[i]), hy * std::sin(a[i]));
    TreatmentMap by_quad(TreatmentMapOptions{}), by_spans(TreatmentMapOptions{});
    std::vector<ColumnSpan> spans;
    const double along = 0.37;  // spans measured from a plant 0.37 m along
    by_spans.AppendSpans(q, along, spans);
    const double shift = 0.0123 * trial;  // the plant moved along
    Quad moved = q;
    for (Eigen::Vector2d& p : moved) p.y() += shift;
    const int n = by_quad.AddFootprint(moved, true);
    EXPECT_EQ(by_spans.AddSpans(spans, along + shift, 1, true), n) << "trial " << trial;
    for (int row = 0; row < by_quad.rows(); ++row) {
      for (int column = 0; column < by_quad.columns(); ++column) {
        ASSERT_EQ(by_spans.Counts(column, row).crop, by_quad.Counts(column, row).crop)
            << "trial " << trial << " cell " << column << "," << row;
      }
    }
    // Taken back, nothing is left; the counters stop at zero.
    EXPECT_EQ(by_spans.AddSpans(spans, along + shift, -1, true), n);
    by_spans.AddSpans(spans, along + shift, -1, true);
    for (int row = 0; row < by_spans.rows(); ++row) {
      for (int column = 0; column < by_spans.columns(); ++column) {
        ASSERT_EQ(by_spans.Counts(column, row).crop, 0);
      }
    }
  }
}

TEST(TreatmentMap, RotatedQuadCountsCellsInside) {
  TreatmentMap map(TreatmentMapOptions{});
  // A diamond of half-diagonal 0.1 m: area 0.02 m² ≈ 112.6 cells.
  const Quad diamond = {Eigen::Vector2d(0.0, 0.9), Eigen::Vector2d(0.1, 1.0),
                        Eigen::Vector2d(0.0, 1.1), Eigen::Vector2d(-0.1, 1.0)};
  const int n = map.AddFootprint(diamond, true);
  EXPECT_NEAR(n, 0.02 / (0.01333 * 0.01333), 8.0);
}

TEST(TreatmentMap, SprayedStripsMarkExactlyTheirCellsAsTreated) {
  TreatmentMapOptions o;
  o.cell_m = 0.01;
  o.width_m = 1.0;
  o.start_y_m = 0.0;
  TreatmentMap map(o);
  // Centres of columns 49..52 (x −0.005, 0.005, 0.015, 0.025) and rows 10..11 (y 0.105, 0.115).
  map.MarkTreated(-0.006, 0.026, 0.101, 0.119);
  int treated = 0;
  for (int r = 0; r < map.rows(); ++r) {
    for (int c = 0; c < map.columns(); ++c) treated += map.Treated(c, r);
  }
  EXPECT_EQ(treated, 8);
  EXPECT_TRUE(map.Treated(49, 10));
  EXPECT_FALSE(map.Treated(48, 10));
  EXPECT_TRUE(map.Treated(52, 11));
  EXPECT_FALSE(map.Treated(53, 11));
  EXPECT_FALSE(map.Treated(50, 12));
  EXPECT_EQ(map.ClassOf(50, 10), CellClass::kSoil);  // treating does not vote
  EXPECT_FALSE(map.Observed(50, 10));                 // nor does it observe
  // The camera's view: cells whose centre is inside are observed, votes untouched.
  map.MarkObserved(Square(0.0, 0.5, 0.1));  // x, y ∈ [−0.1, 0.1] × [0.4, 0.6]
  EXPECT_TRUE(map.Observed(50, 50));
  EXPECT_TRUE(map.Observed(40, 40));   // centre (−0.095, 0.405)
  EXPECT_FALSE(map.Observed(39, 50));  // centre x −0.105
  EXPECT_FALSE(map.Observed(50, 61));  // centre y 0.615
  EXPECT_TRUE(map.Treated(50, 10));
  EXPECT_EQ(map.Counts(50, 50).crop + map.Counts(50, 50).weed, 0);
  map.Clear();
  EXPECT_FALSE(map.Treated(50, 10));
  EXPECT_FALSE(map.Observed(50, 50));
}

// A day's bed: the map keeps a window, so footprints 5 km along count as
// they did at the start, and rows let go read as unobserved soil. Without
// ForgetBefore the map stops counting after 100 000 rows (1.3 km).
TEST(TreatmentMap, ForgetsRowsBehindAndCountsKilometresAlong) {
  TreatmentMapOptions o;
  o.majority_threshold = 1;
  TreatmentMap map(o);
  const auto vote_at = [&](double y) {
    const Quad q = Square(0.0, y, 0.02);
    return map.AddFootprint(q, true);
  };
  EXPECT_GT(vote_at(1.0), 0);
  EXPECT_EQ(vote_at(1500.0), 0) << "a window of 1.3 km from the start";
  int column = 0, row = 0;
  ASSERT_TRUE(map.CellOf({0.0, 4999.0}, column, row));
  map.ForgetBefore(row - 1000);
  EXPECT_EQ(map.first_row(), row - 1000);
  EXPECT_EQ(map.ClassAt({0.0, 1.0}), CellClass::kSoil);  // let go
  EXPECT_EQ(map.rows(), row - 1000);                     // nothing held
  EXPECT_GT(vote_at(4999.0), 0);
  EXPECT_EQ(map.ClassAt({0.0, 4999.0}), CellClass::kCrop);
  EXPECT_TRUE(map.AnyIn(-0.01, 0.01, 4998.99, 4999.01, CellClass::kCrop));
  map.MarkTreated(-0.01, 0.01, 4998.99, 4999.01);
  ASSERT_TRUE(map.CellOf({0.0, 4999.0}, column, row));
  EXPECT_TRUE(map.Treated(column, row));
  // The window holds the rows from the first kept on, not the whole bed.
  EXPECT_LT(map.rows() - map.first_row(), 1100);
  // Behind the window nothing is counted, marked or grown.
  EXPECT_EQ(vote_at(10.0), 0);
  map.MarkTreated(-0.01, 0.01, 9.99, 10.01);
  ASSERT_TRUE(map.CellOf({0.0, 10.0}, column, row));
  EXPECT_FALSE(map.Treated(column, row));
}

TEST(TreatmentMap, BadOptionsAreNamed) {
  TreatmentMapOptions o;
  o.cell_m = 0.0;
  o.majority_threshold = 0;
  try {
    TreatmentMap map(o);
    FAIL();
  } catch (const InvalidOptionsError& e) {
    EXPECT_NE(std::string(e.what()).find("cell_m"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("majority_threshold"), std::string::npos);
  }
}

SchedulerOptions Bar() { return testing::TestBar(0.05); }
using testing::Healthy;

TEST(NozzleScheduler, OpensAheadByTheLatencyOverCropCells) {
  TreatmentMapOptions mo;
  mo.majority_threshold = 1;
  TreatmentMap map(mo);
  // Crop cells around bed (0.125, 1.0): under nozzle 6 (x = 0.125).
  map.AddFootprint(Square(0.125, 1.0, 0.02), true);
  std::vector<uint64_t> masks;
  NozzleScheduler scheduler(Bar(), [&](int64_t, uint64_t m) { masks.push_back(m); });
  EXPECT_NEAR(scheduler.options().bar.Nozzle(6).x(), 0.125, 1e-12);
  const double speed = 0.5;
  const double travel = speed * scheduler.options().tick_s;  // 2.5 mm a tick at 200 Hz
  // The nozzle is at bed y = s − 0.5; at the latency it will be 25 mm further.
  // Open when [s − 0.5 + 0.025, + travel] holds a crop cell centre (0.98..1.02).
  int first_open = -1;
  for (int k = 0; k < 200; ++k) {
    const double s = 1.3 + k * 0.001;
    const TickResult r = scheduler.Tick(k, Pose(0.0, 0.0, s, speed), map, Healthy(k));
    if (r.open_mask && first_open < 0) {
      first_open = k;
      EXPECT_EQ(r.open_mask, uint64_t{1} << 6);
      ASSERT_EQ(r.opened.size(), 1u);
      EXPECT_EQ(r.opened[0].nozzle, 6);
    }
  }
  // The strip [s − 0.475, s − 0.475 + travel], narrower than a cell, holds
  // the cell its middle is in: the nozzle opens as that middle enters the
  // lowest crop cell, the one whose centre is the first at or above 0.98
  // (within one 1 mm step of s).
  int column = 0, row = 0;
  ASSERT_TRUE(map.CellOf({0.125, 0.98 + 0.5 * mo.cell_m}, column, row));
  const double lowest = map.CellCentre(column, row).y();
  ASSERT_EQ(map.ClassOf(column, row), CellClass::kCrop);
  ASSERT_EQ(map.ClassOf(column, row - 1), CellClass::kSoil);
  ASSERT_GE(first_open, 0);
  const double s_open = 1.3 + first_open * 0.001;
  EXPECT_NEAR(s_open - 0.475 + 0.5 * travel, lowest - 0.5 * mo.cell_m, 0.0011);
  EXPECT_EQ(masks.size(), 200u);
}

TEST(NozzleScheduler, ATickAfterItsPoseLeadsByTheTimeSinceIt) {
  NozzleScheduler scheduler(Bar());
  BedPose pose = Pose(0.0, 0.0, 1.0, 0.7);
  pose.utime = 1'000'000;
  const double travel = 0.7 * scheduler.options().tick_s;
  const NozzleTarget at_pose = scheduler.Target(6, pose, pose.utime);
  // Nozzle at bed y 0.5, led by the 50 ms latency: 0.535.
  EXPECT_NEAR(at_pose.y0, 0.535, 1e-9);
  EXPECT_NEAR(at_pose.y1, 0.535 + travel, 1e-9);
  // The pose's third tick, 10 ms on: 7 mm further, and the ticks of one
  // pose tile the ground it drives over.
  const NozzleTarget later = scheduler.Target(6, pose, pose.utime + 10'000);
  EXPECT_NEAR(later.y0, 0.542, 1e-9);
  EXPECT_NEAR(scheduler.Target(6, pose, pose.utime + 5'000).y1, later.y0, 1e-9);
  // A tick before its pose (a runner dead-reckoning back) is not led back.
  EXPECT_NEAR(scheduler.Target(6, pose, pose.utime - 5'000).y0, 0.535, 1e-9);
}

// A nozzle opens and closes on ticks only, so each end of its spray falls
// anywhere within one tick's travel of the crop cells' edge. Driving 0.7 m/s
// over 200 crop patches at random places along the bed, poses at 50 Hz: the
// sprayed interval's centre against the crop cells' centre.
double SprayCentreRms(double tick_s) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> where(0.0, 0.05);
  SchedulerOptions o = Bar();
  o.tick_s = tick_s;
  const double speed = 0.7;
  const int64_t tick_us = std::llround(tick_s * 1e6);
  double sum2 = 0.0;
  int patches = 0;
  for (int p = 0; p < 200; ++p) {
    TreatmentMapOptions mo;
    mo.majority_threshold = 1;
    TreatmentMap map(mo);
    map.AddFootprint(Square(0.125, 1.0 + where(rng), 0.04), true);
    int column = 0, row0 = 0;
    EXPECT_TRUE(map.CellOf({0.125, 1.0}, column, row0));
    double low = 1e9, high = -1e9;  // the crop cells' extent along
    for (int row = 0; row < map.rows(); ++row) {
      if (map.ClassOf(column, row) != CellClass::kCrop) continue;
      const double y = map.CellCentre(column, row).y();
      low = std::min(low, y - 0.5 * mo.cell_m);
      high = std::max(high, y + 0.5 * mo.cell_m);
    }
    NozzleScheduler scheduler(o);
    double first = NAN, last = NAN;
    for (int64_t pose_us = 0; pose_us < 2'000'000; pose_us += 20'000) {
      // The vehicle at bed distance s: its bar at s − 0.5 (plus the lead).
      BedPose pose = Pose(0.0, 0.0, 1.2 + speed * pose_us * 1e-6, speed);
      pose.utime = pose_us;
      for (int k = 0; k < o.TicksPerPose(); ++k) {
        const int64_t now = pose_us + k * tick_us;
        const TickResult r = scheduler.Tick(now, pose, map, Healthy(now));
        if (!(r.open_mask & (uint64_t{1} << 6))) continue;
        const NozzleTarget& t = r.opened.front();
        if (std::isnan(first)) first = t.y0;
        last = t.y1;
      }
    }
    if (std::isnan(first) || high < low) continue;
    const double e = 0.5 * (first + last) - 0.5 * (low + high);
    sum2 += e * e;
    ++patches;
  }
  EXPECT_EQ(patches, 200);
  return std::sqrt(sum2 / std::max(1, patches));
}

TEST(NozzleScheduler, TicksAt200HzCentreTheSprayOnTheCropCellsCloser) {
  // Each end within the tick's travel: 14 mm at 50 Hz, 3.5 mm at 200 Hz.
  // Measured: 3.9 and 1.1 mm RMS.
  const double at_200_hz = SprayCentreRms(0.005);
  const double at_50_hz = SprayCentreRms(0.02);
  EXPECT_LT(at_200_hz, 0.0015) << at_200_hz;
  EXPECT_GT(at_50_hz, 0.003) << at_50_hz;
  EXPECT_LT(at_200_hz, 0.4 * at_50_hz);
}

TEST(NozzleScheduler, CommandsRunFourTimesPerPose) {
  SchedulerOptions o;
  EXPECT_EQ(o.TicksPerPose(), 4);
  o.tick_s = 0.02;
  EXPECT_EQ(o.TicksPerPose(), 1);
  EXPECT_TRUE(o.Validate().empty());
  o.tick_s = 0.03;  // slower than the pose: each pose would skip ground
  const OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].key, "tick_s");
}

TEST(NozzleScheduler, FailSafeClosesEveryNozzleAndSaysWhy) {
  TreatmentMapOptions mo;
  mo.majority_threshold = 1;
  TreatmentMap map(mo);
  map.AddFootprint(Square(0.0, 0.0, 1.0), true);  // crop everywhere under the bar
  uint64_t last = 0;
  NozzleScheduler scheduler(Bar(), [&](int64_t, uint64_t m) { last = m; });
  const BedPose pose = Pose(0.0, 0.0, 0.5, 0.5);
  const int64_t now = 1'000'000;
  EXPECT_EQ(scheduler.Tick(now, pose, map, Healthy(now)).open_mask, 0xFFu);
  EXPECT_EQ(last, 0xFFu);
  struct Case {
    SafetyInputs in;
    uint32_t reason;
    const char* text;
  };
  std::vector<Case> cases;
  SafetyInputs stale = Healthy(now);
  stale.pose_utime = now - 150'000;
  cases.push_back({stale, kPoseStale, "pose stale (150 ms > 100 ms)"});
  SafetyInputs camera = Healthy(now);
  camera.last_frame_utime = now - 600'000;
  cases.push_back({camera, kCameraLost, "camera lost (no frame for 600 ms > 500 ms)"});
  SafetyInputs fault = Healthy(now);
  fault.camera_ok = false;
  cases.push_back({fault, kCameraLost, "camera lost (source reports a fault)"});
  SafetyInputs odo = Healthy(now);
  odo.odometry_valid = false;
  cases.push_back({odo, kOdometryInvalid, "odometry invalid (last sample refused)"});
  SafetyInputs lost = Healthy(now);
  lost.tracking = false;
  cases.push_back({lost, kTrackerLost, "tracker has lost the grid"});
  SafetyInputs held = Healthy(now);
  held.held = true;
  cases.push_back({held, kOperatorHold, "held by the operator (paused or spraying off)"});
  for (const Case& c : cases) {
    const TickResult r = scheduler.Tick(now, pose, map, c.in);
    EXPECT_EQ(r.open_mask, 0u) << c.text;
    EXPECT_EQ(last, 0u) << c.text;
    EXPECT_EQ(r.fail_reasons, c.reason) << c.text;
    ASSERT_EQ(r.messages.size(), 1u);
    EXPECT_EQ(r.messages[0], c.text);
  }
  // A pose exactly 100 ms old is still fresh.
  SafetyInputs edge = Healthy(now);
  edge.pose_utime = now - 100'000;
  EXPECT_EQ(scheduler.Tick(now, pose, map, edge).fail_reasons, 0u);
}

TEST(NozzleScheduler, WeedModeSpraysWeedCellsOnly) {
  TreatmentMapOptions mo;
  mo.majority_threshold = 1;
  TreatmentMap map(mo);
  map.AddFootprint(Square(0.125, 0.0, 0.03), true);
  map.AddFootprint(Square(-0.125, 0.0, 0.03), false);
  SchedulerOptions o = Bar();
  o.mode = SprayMode::kWeed;
  NozzleScheduler scheduler(o);
  // Bar over bed y = 0: s = 0.5 (latency lead at speed 0 is nil).
  const TickResult r = scheduler.Tick(0, Pose(0.0, 0.0, 0.5, 0.0), map, Healthy(0));
  EXPECT_EQ(r.open_mask, uint64_t{1} << 1);  // x = −0.125
  // The station switches to the crop: the other nozzle from the next tick.
  scheduler.set_mode(SprayMode::kCrop);
  EXPECT_EQ(scheduler.Tick(1, Pose(0.0, 0.0, 0.5, 0.0), map, Healthy(1)).open_mask, uint64_t{1} << 6);  // x = +0.125
}

TEST(NozzleScheduler, BadOptionsAreNamed) {
  SchedulerOptions o;
  o.bar.nozzles = 65;
  o.fail_safe.max_pose_age_s = 0.0;
  try {
    NozzleScheduler s(o);
    FAIL();
  } catch (const InvalidOptionsError& e) {
    EXPECT_NE(std::string(e.what()).find("bar.nozzles"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fail_safe.max_pose_age_s"), std::string::npos);
  }
}

TEST(TreatmentOptions, OwnOffsetFractionsAreShares) {
  TreatmentOptions o;
  EXPECT_TRUE(o.Validate().empty());
  o.own_offset_fraction_along = 1.2;
  o.own_offset_fraction_across = -0.1;
  const OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].key, "own_offset_fraction_across");
  EXPECT_EQ(e[1].key, "own_offset_fraction_along");
  o.own_offset_fraction_along = std::nan("");
  o.own_offset_fraction_across = 0.0;
  ASSERT_EQ(o.Validate().size(), 1u);
}

TEST(SimulatedBar, ShotsLandWhereTheNozzleWasAfterTheLatency) {
  SprayBarOptions bar;
  bar.nozzles = 4;
  bar.nozzle_spacing_m = 0.1;
  bar.bar_offset_m = 0.5;
  SimulatedBar sim(bar, 0.04, 0.02);
  // Vehicle drives along field y at 1 m/s from y = 0, heading 0.
  std::vector<FieldPose> track;
  for (int k = 0; k <= 100; ++k) track.push_back({k * 10'000, 0.0, k * 0.01, 0.0});
  sim.Command(100'000, 0b0100);
  sim.Command(120'000, 0b0100);
  sim.Command(140'000, 0);
  const std::vector<Shot> shots = sim.Shots(track);
  ASSERT_EQ(shots.size(), 1u);
  EXPECT_EQ(shots[0].nozzle, 2);
  EXPECT_EQ(shots[0].open_utime, 140'000);
  EXPECT_EQ(shots[0].close_utime, 180'000);
  ASSERT_EQ(shots[0].path_field_m.size(), 3u);
  EXPECT_NEAR(shots[0].path_field_m.front().x(), 0.05, 1e-12);
  EXPECT_NEAR(shots[0].path_field_m.front().y(), 0.14 - 0.5, 1e-9);
  EXPECT_NEAR(shots[0].path_field_m.back().y(), 0.18 - 0.5, 1e-9);
  // Heading +90° (forward axis along −x): vehicle x (right) is field +y.
  const FieldPose turned{0, 1.0, 2.0, M_PI / 2};
  const Eigen::Vector2d f = VehicleToField(turned, {0.1, 0.0});
  EXPECT_NEAR(f.x(), 1.0, 1e-12);
  EXPECT_NEAR(f.y(), 2.1, 1e-12);
}

// A record beyond the map's width (a weed at the view's edge) is final once
// the bar has passed its row, like the others: waiting for a cell it will
// never have, it held every later record for the rest of the run.
TEST(PlantRegistry, RecordsOffTheMapAreLetGoWithTheirRows) {
  PlantRegistry reg;
  classify::BlobDecision weed;
  weed.area_m2 = 0.001;
  TreatmentMapOptions mo;  // 3.4 m wide: |x| < 1.7 m
  TreatmentMap map(mo);
  EXPECT_EQ(reg.Observe({2.5, 1.0}, weed), 0);  // off the map
  EXPECT_EQ(reg.Observe({0.1, 1.2}, weed), 1);
  EXPECT_EQ(reg.Observe({0.1, 9.0}, weed), 2);  // ahead
  int column = 0, row = 0;
  ASSERT_TRUE(map.CellOf({0.0, 5.0}, column, row));
  reg.TakeFinalCounts(map, row);
  reg.LetGoFinal();
  ASSERT_EQ(reg.records().size(), 1u);
  EXPECT_EQ(reg.records()[0].id, 2);
  EXPECT_EQ(reg.first_id(), 2);
}

TEST(PlantRegistry, MergesObservationsAndExplains) {
  PlantRegistry reg;
  classify::ClassifierOptions c;
  classify::BlobDecision crop;
  crop.crop = true;
  crop.area_m2 = 0.05;
  crop.gamma2 = 0.5;
  crop.distance_m = 0.012;
  classify::BlobDecision weed;
  weed.area_m2 = 0.001;
  weed.size_filter_m2 = 0.0025;  // the classifier's filter in force
  weed.gamma2 = 40.0;
  weed.distance_m = 0.2;
  EXPECT_EQ(reg.Observe({0.0, 1.0}, crop), 0);
  EXPECT_EQ(reg.Observe({0.01, 1.01}, crop), 0);
  EXPECT_EQ(reg.Observe({0.2, 1.0}, weed), 1);
  classify::BlobDecision leaf = weed;  // under the filter, a crop's cut-off leaf
  leaf.crop = leaf.fragment = true;
  EXPECT_EQ(reg.Observe({0.6, 1.0}, leaf), 2);
  classify::BlobDecision lone = weed;  // under the filter, alone in a crop's region
  lone.crop = lone.associated = lone.lone = true;
  lone.gamma2 = 1.0;
  const Eigen::Vector2d lone_grid(1.2, 1.0);
  EXPECT_EQ(reg.Observe({1.2, 1.01}, lone, lone_grid), 3);
  ASSERT_EQ(reg.records().size(), 4u);
  EXPECT_NEAR(reg.records()[0].bed_m.x(), 0.005, 1e-12);
  EXPECT_EQ(reg.records()[0].crop_votes, 2);
  reg.MarkSprayed({0, -0.01, 0.02, 0.99, 1.0});
  TreatmentMapOptions mo;
  mo.majority_threshold = 1;
  TreatmentMap map(mo);
  map.AddFootprint(Square(0.005, 1.005, 0.02), true);
  reg.Explain(map, SprayMode::kCrop, c);
  const PlantRecord& a = reg.records()[0];
  EXPECT_TRUE(a.sprayed);
  EXPECT_EQ(a.map_class, CellClass::kCrop);
  EXPECT_NE(a.why.find("crop (2 crop / 0 weed votes)"), std::string::npos) << a.why;
  EXPECT_NE(a.why.find("12 mm from the predicted crop"), std::string::npos) << a.why;
  const PlantRecord& b = reg.records()[1];
  EXPECT_FALSE(b.sprayed);
  EXPECT_NE(b.why.find("below the size filter"), std::string::npos) << b.why;
  EXPECT_NE(b.why.find("area 0.0010 m2 (filter 0.0025)"), std::string::npos) << b.why;
  EXPECT_NE(b.why.find("not sprayed"), std::string::npos) << b.why;
  const PlantRecord& l = reg.records()[2];
  EXPECT_NE(l.why.find("crop (1 crop / 0 weed votes): below the size filter, a leaf of a crop"),
            std::string::npos)
      << l.why;
  const PlantRecord& s = reg.records()[3];
  EXPECT_NE(s.why.find("crop (1 crop / 0 weed votes): below the size filter, alone in a predicted"),
            std::string::npos)
      << s.why;
  EXPECT_NE(a.why.find("crop 1 weed 0 doubt 0 -> crop"), std::string::npos) << a.why;
}

TEST(PlantRegistry, APlantIsConfirmedByBeingSeenWhereverItWasInView) {
  PlantRegistry reg;
  classify::BlobDecision weed;
  weed.area_m2 = 0.002;
  // The camera's view on the bed: 1 m square, moving 0.05 m per frame.
  const auto view = [](double y0) {
    return Quad{Eigen::Vector2d(-0.5, y0), Eigen::Vector2d(0.5, y0), Eigen::Vector2d(0.5, y0 + 1.0),
                Eigen::Vector2d(-0.5, y0 + 1.0)};
  };
  // A weed at y = 1.5 seen in every other frame of the 20 that hold it, and
  // a speck at y = 1.2 seen in 3 of them.
  for (int f = 0; f < 20; ++f) {
    if (f % 2 == 0) reg.Observe({0.1, 1.5}, weed);
    if (f == 3 || f == 4 || f == 12) reg.Observe({-0.2, 1.2}, weed);
    reg.CountView(view(0.55 + 0.05 * f));
  }
  ASSERT_EQ(reg.records().size(), 2u);
  const PlantRecord& plant = reg.records()[0];
  const PlantRecord& speck = reg.records()[1];
  EXPECT_EQ(plant.observations, 10);
  EXPECT_GE(plant.frames_in_view, 14);
  EXPECT_TRUE(plant.confirmed());
  EXPECT_EQ(speck.observations, 3);
  EXPECT_GE(speck.frames_in_view, 8);
  EXPECT_FALSE(speck.confirmed());
  // Seen twice only: never confirmed, however briefly it was in view.
  PlantRecord twice;
  twice.observations = 2;
  twice.frames_in_view = 2;
  EXPECT_FALSE(twice.confirmed());
}

TEST(PlantRegistry, LeafFragmentsOfOneGridPlantMakeOneRecord) {
  PlantRegistry reg;  // merge radius 50 mm
  classify::BlobDecision leaf;
  leaf.crop = true;
  leaf.associated = true;
  leaf.area_m2 = 0.01;
  leaf.gamma2 = 2.0;
  const Eigen::Vector2d plant(0.0, 1.0);
  // Three leaves 80 mm apart, all associated with the same predicted plant
  // (whose bed position jitters by a few mm from frame to frame).
  EXPECT_EQ(reg.Observe({-0.08, 1.0}, leaf, plant), 0);
  EXPECT_EQ(reg.Observe({0.0, 1.08}, leaf, Eigen::Vector2d(0.004, 1.003)), 0);
  EXPECT_EQ(reg.Observe({0.08, 1.0}, leaf, Eigen::Vector2d(-0.003, 0.998)), 0);
  // The next grid plant along the row is another record.
  EXPECT_EQ(reg.Observe({0.0, 1.45}, leaf, Eigen::Vector2d(0.0, 1.45)), 1);
  // Without a prediction the same fragments split by the merge radius.
  classify::BlobDecision weed;
  weed.area_m2 = 0.01;
  EXPECT_EQ(reg.Observe({-0.08, 2.0}, weed), 2);
  EXPECT_EQ(reg.Observe({0.08, 2.0}, weed), 3);
  // An unassociated blob next to a grid plant's record does not join it
  // only by the prediction: it joins by its centroid, as before.
  EXPECT_EQ(reg.Observe({0.0, 1.45}, weed), 1);
  ASSERT_EQ(reg.records().size(), 4u);
  EXPECT_EQ(reg.records()[0].crop_votes, 3);
  EXPECT_TRUE(reg.records()[0].grid_plant);
  EXPECT_NEAR(reg.records()[0].grid_bed_m.x(), (0.0 + 0.004 - 0.003) / 3.0, 1e-12);
  EXPECT_NEAR(reg.records()[0].grid_bed_m.y(), (1.0 + 1.003 + 0.998) / 3.0, 1e-12);
  EXPECT_FALSE(reg.records()[2].grid_plant);
}

// A disc of radius r seen from the camera with its outline stretched by k
// along the line of sight (a plant's height under the oblique view): the
// stretch is taken out whatever the bearing; a round plant is left as it is.
TEST(PlantRegistry, UnstretchedAreaTakesTheObliqueStretchOut) {
  const double r = 0.1, area = M_PI * r * r;
  for (const double bearing : {0.0, 0.4, -1.1}) {
    const Eigen::Vector2d along(std::sin(bearing), std::cos(bearing)), across(along.y(), -along.x());
    const double k = 1.3;
    SizeSample s;
    s.area_m2 = k * area;
    s.ground_m = 2.0 * along;
    s.covariance_m2 = 0.25 * r * r * (across * across.transpose() + k * k * along * along.transpose());
    EXPECT_NEAR(UnstretchedArea({&s, 1}), area, 1e-12) << bearing;
    s.area_m2 = area;
    s.covariance_m2 = 0.25 * r * r * Eigen::Matrix2d::Identity();
    EXPECT_NEAR(UnstretchedArea({&s, 1}), area, 1e-12) << bearing;
  }
  // Two halves of a stretched plant (its leaves cut apart) make the same
  // plant: their joint moments, not each half's.
  const double k = 1.5, h = 4.0 * r / (3.0 * M_PI);  // a half-disc's centroid from the cut
  SizeSample near, far;
  near.area_m2 = far.area_m2 = 0.5 * k * area;
  near.ground_m = {0.0, 2.0 - k * h};
  far.ground_m = {0.0, 2.0 + k * h};
  const double var_along = (0.25 - h * h / (r * r)) * r * r * k * k;
  near.covariance_m2 = far.covariance_m2 = Eigen::Vector2d(0.25 * r * r, var_along).asDiagonal();
  const SizeSample halves[] = {near, far};
  EXPECT_NEAR(UnstretchedArea(halves), area, 1e-12);
  // Widened across (a neighbour beside it): not enlarged.
  SizeSample wide;
  wide.area_m2 = area;
  wide.ground_m = {0.0, 2.0};
  wide.covariance_m2 = Eigen::Vector2d(0.5 * r * r, 0.25 * r * r).asDiagonal();
  EXPECT_DOUBLE_EQ(UnstretchedArea({&wide, 1}), area);
}

// A record's size is the median of its frames' sizes (each frame's blobs
// of it together) over the nearer half of the frames, frames where the
// border cut it left out; the largest blob still drives the size filter.
TEST(PlantRegistry, SizeIsTheMedianOverTheNearerFramesSeenWhole) {
  PlantRegistry reg;
  classify::BlobDecision leaf;
  leaf.crop = leaf.associated = true;
  leaf.gamma2 = 1.0;
  const Eigen::Vector2d plant(0.0, 1.0);
  // Per frame: the plant's distance from the camera's ground point and its
  // area, two leaves of half each; the nearest frame is cut by the border.
  const double frames[6][2] = {{3.0, 0.05}, {2.5, 0.04}, {2.0, 0.02}, {1.5, 0.03}, {1.25, 0.025}, {1.0, 0.08}};
  for (const auto& [distance, area] : frames) {
    const bool clipped = distance == 1.0;
    for (int half = 0; half < 2; ++half) {
      leaf.area_m2 = 0.5 * area;
      leaf.clipped = clipped;
      SizeSample s;
      s.area_m2 = 0.5 * area;
      s.ground_m = {0.0, distance};
      s.covariance_m2 = 0.01 * Eigen::Matrix2d::Identity();
      s.clipped = clipped;
      reg.AddSize(reg.Observe({0.0, 1.0}, leaf, plant), s);
    }
    reg.EndFrame();
  }
  ASSERT_EQ(reg.records().size(), 1u);
  const PlantRecord& r = reg.records()[0];
  EXPECT_EQ(r.sizes.size(), 5u);
  EXPECT_NEAR(r.sizes[0].distance_m, 3.0, 1e-6);
  EXPECT_NEAR(r.area_m2, 0.025, 1e-7);  // the median of 0.03, 0.025, 0.02
  EXPECT_DOUBLE_EQ(r.largest_m2, 0.025);
}

// With the crop's size spread s known (profile), a record in a crop's place
// below (1 − 3 s)² of the crops' median size is a weed where the crop is
// missing; without it (s = 0) nothing changes.
TEST(PlantRegistry, AWeedInAGapIsNotTheMissingCrop) {
  for (const double spread : {0.15, 0.0}) {
    RegistryOptions o;
    o.crop_size_sd_fraction = spread;
    PlantRegistry reg(o);
    classify::BlobDecision crop;
    crop.crop = crop.associated = true;
    crop.gamma2 = 1.0;
    for (int frame = 0; frame < 4; ++frame) {
      for (int m = 0; m < 12; ++m) {
        const Eigen::Vector2d at(0.0, 0.45 * m);
        // Plant 5 is missing: a weed of 0.012 m² stands in its region.
        const double area = m == 5 ? 0.012 : 0.05 + 0.001 * m;
        crop.area_m2 = area;
        SizeSample s;
        s.area_m2 = area;
        s.ground_m = {0.0, 2.0};
        s.covariance_m2 = 0.001 * Eigen::Matrix2d::Identity();
        reg.AddSize(reg.Observe(at, crop, at), s);
      }
      reg.EndFrame();
    }
    ASSERT_EQ(reg.records().size(), 12u);
    EXPECT_EQ(reg.records()[5].crop(), spread == 0.0) << spread;
    EXPECT_EQ(reg.records()[5].undersized, spread > 0.0) << spread;
    for (int m : {0, 4, 6, 11}) EXPECT_TRUE(reg.records()[static_cast<size_t>(m)].crop()) << m;
    // The median of the 12 crop-voted records (the upper one of an even count).
    EXPECT_NEAR(reg.crop_median_m2(), spread > 0.0 ? 0.056 : 0.0, 1e-7);
  }
}

// The run ends with plant lines far in the view: their records have been
// seen only far away. FlushInView judges the records inside the last view
// on the frames they had: a predicted crop's record seen in 3 of 12 frames
// is confirmed; a predicted crop with no crop record within reach takes the
// more seen of two crop-sized records held weeds near it; a crop-sized
// record near a predicted crop that has its record, or beyond reach of
// every prediction, or outside the view, stays as it was.
TEST(PlantRegistry, TheLastViewIsJudgedOnTheFramesItHad) {
  RegistryOptions o;
  o.crop_size_sd_fraction = 0.15;  // crops >= 0.3025 of the median are crop-sized
  PlantRegistry reg(o);
  classify::BlobDecision crop, weed;
  crop.crop = crop.associated = true;
  crop.gamma2 = 1.0;
  const auto sample = [](double area) {
    SizeSample s;
    s.area_m2 = area;
    s.ground_m = {0.0, 2.0};
    s.covariance_m2 = 0.001 * Eigen::Matrix2d::Identity();
    return s;
  };
  // Twelve crops along x = 0 at 0.45 m (median size 0.05 m²), seen in all 12 frames.
  const Quad view{Eigen::Vector2d(-1.0, 4.4), Eigen::Vector2d(1.0, 4.4), Eigen::Vector2d(1.0, 8.0),
                  Eigen::Vector2d(-1.0, 8.0)};
  int late = -1, big = -1, twin = -1, beside = -1, outside = -1;
  for (int frame = 0; frame < 12; ++frame) {
    for (int m = 0; m < 12; ++m) {
      const Eigen::Vector2d at(0.0, 0.45 * m);
      reg.AddSize(reg.Observe(at, crop, at), sample(0.05));
    }
    if (frame % 4 == 0) {  // seen in 3 of the 12 frames
      const Eigen::Vector2d at(0.45, 6.0);
      late = reg.Observe(at, crop, at);
      reg.AddSize(late, sample(0.045));
      big = reg.Observe({-0.45, 6.3}, weed);  // as large as a crop, not associated
      reg.AddSize(big, sample(0.04));
      outside = reg.Observe({-0.45, 3.0}, weed);  // the same, behind the last view
      reg.AddSize(outside, sample(0.04));
    }
    if (frame % 3 == 0) {  // seen in 4 of the 12 frames: the more seen of the two
      twin = reg.Observe({-0.45, 6.4}, weed);
      reg.AddSize(twin, sample(0.04));
      beside = reg.Observe({0.1, 5.1}, weed);  // 0.18 m from the crop at y = 4.95
      reg.AddSize(beside, sample(0.05));
    }
    reg.CountView(Quad{Eigen::Vector2d(-1.0, 0.0), Eigen::Vector2d(1.0, 0.0), Eigen::Vector2d(1.0, 8.0),
                       Eigen::Vector2d(-1.0, 8.0)});
    reg.EndFrame();
  }
  EXPECT_NEAR(reg.crop_median_m2(), 0.05, 1e-9);
  const auto rec = [&](int id) { return *reg.Find(id); };
  EXPECT_FALSE(rec(late).confirmed());  // 3 of 12 frames
  EXPECT_FALSE(rec(twin).crop());
  const std::vector<Eigen::Vector2d> predicted{{0.0, 4.5},  {0.0, 4.95}, {0.45, 6.0},
                                               {-0.45, 6.35}, {0.0, 5.4}, {-0.45, 3.0}};
  const std::vector<int> changed = reg.FlushInView(view, predicted, 0.225);
  EXPECT_TRUE(rec(late).judged_at_end);
  EXPECT_TRUE(rec(late).confirmed());
  EXPECT_TRUE(rec(late).crop());
  EXPECT_TRUE(rec(twin).crop_at_end);  // 4 sightings beat 3
  EXPECT_TRUE(rec(twin).crop());
  EXPECT_TRUE(rec(twin).confirmed());
  EXPECT_FALSE(rec(big).crop());  // the less seen at the same prediction
  EXPECT_FALSE(rec(beside).crop());  // 0.18 m from a crop that has its record, 0.32 m from one that has none
  EXPECT_FALSE(rec(outside).judged_at_end);
  EXPECT_FALSE(rec(outside).crop());
  EXPECT_EQ(changed, (std::vector<int>{late, twin}));
  EXPECT_TRUE(reg.records()[11].judged_at_end);  // the crop at 4.95 m, still confirmed
  EXPECT_TRUE(reg.records()[11].confirmed());
}

// Spray-weed mode's segmentation joins no blobs by soil growth, so that a
// weed against a crop's rim keeps its own blob; the rest of the options is
// the caller's.
TEST(SegmenterForMode, SprayWeedModeJoinsNoBlobsBySoilGrowth) {
  vision::SegmenterOptions base;
  base.soil_growth.z = 2.5;
  base.hull_gain = 1.7;
  const vision::SegmenterOptions crop = SegmenterOptionsFor(SprayMode::kCrop, base);
  const vision::SegmenterOptions weed = SegmenterOptionsFor(SprayMode::kWeed, base);
  EXPECT_EQ(crop.soil_growth.join_min_area_px, 0);
  EXPECT_EQ(weed.soil_growth.join_min_area_px, std::numeric_limits<int>::max());
  EXPECT_DOUBLE_EQ(weed.soil_growth.z, 2.5);
  EXPECT_DOUBLE_EQ(weed.hull_gain, 1.7);
  EXPECT_TRUE(weed.Validate().empty());
}

}  // namespace
}  // namespace plantscale::treatment
