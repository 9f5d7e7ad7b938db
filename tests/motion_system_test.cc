// Sanchiz & Pla (1999) on the simulator, at fixed seeds (issue 7): the
// paper's method on their two set-ups, and ours beside it. Published: > 95 %
// correct correspondences over 30 images; row-fit RMS 32.7 / 27.2 / 8.6 mm,
// angle 0.42 / 0.54°, spacing 413.2 / 408.3 mm for 400 mm real.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "app/config/config_loader.h"
#include "evaluation/motion_eval.h"

namespace plantscale::app {
namespace {

MotionEvalOptions Sequences(int seeds, int frames, const std::string& preset = "sanchiz_pla") {
  MotionEvalOptions o;
  o.sim = LoadSimulatorPreset(preset, DefaultConfigDir());
  o.seeds = seeds;
  o.frames = frames;
  o.paper = PaperMethod();
  o.ours = OursMethod(o.sim);
  return o;
}

// Tuning seeds 1–2 of `field`, 30 frames each, ours searching around `prior`.
MotionEvalOptions FieldSequences(MotionPrior prior) {
  MotionEvalOptions o = Sequences(2, 30, "field");
  o.sim.seed = 1;
  o.prior = prior;
  return o;
}

// First set-up (v = 1.2 m, φ = 66°, f = 40 mm, 1.25 m/s, 200 ms): 30-image
// sequences whose consecutive frames share only about 0.1 m of ground.
TEST(MotionSystem, FirstSetUpCorrespondencesAndDrift) {
  const MotionEvaluation e = EvaluateMotion(Sequences(8, 30));
  ASSERT_EQ(e.frames, 30);
  // Ours: the 99 % (measured 99.2 % of 127 matches).
  EXPECT_GE(e.ours.correct_correspondence_rate, 0.99);
  // The paper's method on this overlap: 89.6 % (it claims > 95 % on wider views).
  EXPECT_GT(e.paper.correct_correspondence_rate, 0.85);
  // Without odometry the heading is barely observable here: ours 2.2 cm/m,
  // the paper's method 35 cm/m (its rotation RMSE is 3.6° per frame).
  EXPECT_LT(e.ours.drift_cm_per_m, 2.6);
  EXPECT_LT(e.ours.drift_cm_per_m, 0.2 * e.paper.drift_cm_per_m);
  // Its signed parts (measured: along −0.71, across +1.72 cm/m, a
  // systematic lateral part): means of the components of the error vectors
  // whose mean length is the drift, so their norm cannot exceed it.
  EXPECT_LE(std::hypot(e.ours.drift_along_cm_per_m, e.ours.drift_across_cm_per_m),
            e.ours.drift_cm_per_m + 1e-9);
  EXPECT_LT(e.ours.rotation_rmse_deg, 0.25);
  EXPECT_LT(e.ours.rotation_rmse_deg, e.paper.rotation_rmse_deg);
  EXPECT_LT(e.ours.translation_rmse_m, 0.01);
}

// The same set-up with the soil's shift as the prior (evaluate motion's
// default): its view is 0.32 m along and the vehicle moves 0.25 m a frame,
// so no shift may be taken (before the peak-ratio and step checks, held-out
// seeds 1000–1001 took one on 49 of 58 pairs: no match correct, 106 cm/m).
// Measured on the preset's seeds 1–2: no shift taken, 56 of 56 matches
// correct, 1.28 cm/m.
TEST(MotionSystem, FirstSetUpTakesNoGroundShiftItsViewCannotMeasure) {
  MotionEvalOptions o = Sequences(2, 30);
  o.prior = MotionPrior::kImage;
  const MotionEvaluation e = EvaluateMotion(o);
  EXPECT_EQ(e.ours.prior_valid_pairs, 0);
  EXPECT_GE(e.ours.correct_correspondence_rate, 0.97);
  EXPECT_GE(e.ours.matches, 30);
  EXPECT_LT(e.ours.drift_cm_per_m, 2.6);
}

// Second set-up (vertical camera at 1.77 m, f = 28 mm, 0.25 m/s, 140 ms),
// driven 0.2 m beside the central row so that two rows are whole in view;
// 200 frames (7 m, the length of the paper's map), 9 seeds.
TEST(MotionSystem, SecondSetUpMosaicRowFit) {
  MotionEvalOptions o = Sequences(9, 200);
  o.sim.camera = LoadCamera("sanchiz_pla_90", DefaultConfigDir());
  o.sim.vehicle.speed_m_s = 0.25;
  o.sim.vehicle.frame_rate_hz = 1.0 / 0.14;
  o.sim.vehicle.start_offset_m = 0.2;
  o.ours = OursMethod(o.sim);
  const MotionEvaluation e = EvaluateMotion(o);
  EXPECT_GE(e.paper.correct_correspondence_rate, 0.98);
  EXPECT_GE(e.ours.correct_correspondence_rate, 0.98);
  ASSERT_GE(e.paper.rows_fitted, 6);
  ASSERT_GE(e.ours.rows_fitted, 6);
  // The paper's method places the plants on the ground: the rows come out
  // too far apart, as published (413.2 / 408.3 mm): measured 406 mm.
  EXPECT_GT(e.paper.row_spacing_m, 0.402);
  EXPECT_LT(e.paper.row_spacing_m, 0.415);
  // Ours: spacing within 3 mm (published errors 13.2 / 8.3 mm), row RMS
  // below two of the three published rows (mean 22.8 mm), angle below 0.42°.
  EXPECT_NEAR(e.ours.row_spacing_m, e.true_row_spacing_m, 0.003);
  EXPECT_LT(e.ours.row_fit_rms_m, 0.0228);
  EXPECT_LT(e.ours.row_angle_deg, 0.42);
  // Drift without odometry: ours 0.70 cm/m, the paper's method 3.04 cm/m;
  // 0.82 when the rotation prior returned to the first frame's heading
  // instead of the rows' fitted on the map (row_heading.h).
  EXPECT_LT(e.ours.drift_cm_per_m, 0.78);
  EXPECT_LT(e.ours.drift_cm_per_m, 0.3 * e.paper.drift_cm_per_m);
}

// The vehicle's own camera searching around the wheels (issue 38), its
// features placed with the camera's pitch the soil reads: tuning seeds 1–2,
// 49 of 58 pairs locked, 96.4 % of 1,110 matches right (session 34); with
// the nominal camera 35 locked, 94.5 % of 667 (the bounce moves the
// features beyond the 6 mm gate around the wheels). 28 matches have a
// feature on no plant (a stone or clod segmented as plant matter), scored
// by its ground point.
TEST(MotionSystem, FieldWithTheWheelsPriorMatchesThePlantsAndTheStones) {
  MotionEvalOptions o = FieldSequences(MotionPrior::kWheels);
  const MotionEvaluation e = EvaluateMotion(o);
  ASSERT_EQ(e.ours.pairs, 58);
  EXPECT_TRUE(e.camera_pitch);
  EXPECT_GE(e.ours.locked_pairs, 45);
  EXPECT_GE(e.ours.matches, 900);
  EXPECT_GT(e.ours.correct_correspondence_rate, 0.955);
  EXPECT_GT(e.ours.matches_on_ground, 0);
  EXPECT_LT(e.ours.matches_on_ground, e.ours.matches / 10);
  o.camera_pitch = false;
  const MotionEvaluation nominal = EvaluateMotion(o);
  EXPECT_FALSE(nominal.camera_pitch);
  EXPECT_LT(nominal.ours.locked_pairs, 40);
  EXPECT_GT(nominal.ours.correct_correspondence_rate, 0.93);
}

// The vehicle's own camera with no odometry at all (issue 38): ours
// searches around the ground's shift, the soil's texture on the ground
// (motion/ground_shift.h), with the camera's pitch from frame to frame
// taken out of it and put into the features' placing, and the features'
// translation is scaled by the soil's distance over theirs. Tuning seeds
// 1–2, measured (session 34): 58 of 58 pairs locked, 98.4 % correct, the
// prior's error 7.9 mm a frame, drift 1.68 cm/m, along +1.04. Without the
// pitch (session 33): 55 of 58, 96.9 % correct (72.5 % while the truth was
// placed with the camera's nominal pose), 13.0 mm, drift 2.34, along +0.52
// (−0.43 without the soil's scale). The plant masks on the feature plane
// instead: along −1.75, their matter's height not the plane's; the
// smoothed previous motion alone locks 1 of 58 pairs.
TEST(MotionSystem, FieldWithoutOdometryLocksOnTheGroundShift) {
  MotionEvalOptions o = FieldSequences(MotionPrior::kImage);
  const MotionEvaluation e = EvaluateMotion(o);
  ASSERT_EQ(e.ours.pairs, 58);
  EXPECT_EQ(e.ours.prior_valid_pairs, 58);
  // The ground shift's error per frame: the camera's bounce (0.004 rad of
  // pitch moves the view by about a centimetre), most of it taken out.
  EXPECT_LT(e.ours.prior_translation_rmse_m, 0.010);
  EXPECT_GE(e.ours.locked_pairs, 55);
  EXPECT_GT(e.ours.correct_correspondence_rate, 0.97);
  EXPECT_LT(e.ours.drift_cm_per_m, 2.0);
  // The scale over-corrects on these two seeds (docs/results, session 34).
  EXPECT_LT(std::abs(e.ours.drift_along_cm_per_m), 1.3);
  // The contour features on the profile's plane read short against the
  // soil on the ground (measured 1.26 %).
  EXPECT_GT(e.ours.soil_scale, 1.0);
  EXPECT_LT(e.ours.soil_scale, 1.03);
  // The soil's turn (near and far halves of the view) on nearly every pair,
  // to 0.088° a frame; the locked rotation 0.100° (0.19° searched around
  // no turn, session 32).
  EXPECT_GE(e.ours.prior_turn_pairs, 54);
  EXPECT_LT(e.ours.prior_rotation_rmse_deg, 0.12);
  EXPECT_LT(e.ours.rotation_rmse_deg, 0.13);
  o.ground_shift = motion::GroundShiftOptions{};  // the plant masks: no turn, no scale
  const MotionEvaluation masks = EvaluateMotion(o);
  EXPECT_EQ(masks.ours.soil_scale, 1.0);
  EXPECT_LT(masks.ours.drift_along_cm_per_m, -1.0);
  EXPECT_EQ(masks.ours.prior_turn_pairs, 0);
  EXPECT_GT(masks.ours.rotation_rmse_deg, 0.15);
}

}  // namespace
}  // namespace plantscale::app
