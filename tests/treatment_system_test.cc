// Crop/weed classification, the treatment map and spraying on the
// calibrated presets (issue 6), with the thesis's chain (its tracker,
// adaptive threshold, whole bounding boxes, table 7.2's classifier) on the
// same frames. Fixed seeds. The bounds guard the figures reached now (see
// docs/results/); where they fall short of the targets the comment says so.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <utility>

#include "app/config/config_loader.h"
#include "evaluation/treatment_eval.h"

namespace plantscale::app {
namespace {

TreatmentEvaluation Evaluate(const char* preset, int seeds, double length_m, bool thesis) {
  TreatmentEvalOptions o;
  o.sim = LoadSimulatorPreset(preset, DefaultConfigDir());
  if (length_m > 0) o.sim.length_m = length_m;
  o.seeds = seeds;
  o.profiles = LoadProfiles("", "", o.sim.preset, DefaultConfigDir());
  o.treatment = ProductTreatmentOptions(*o.profiles);
  o.baseline_thesis = thesis;
  return EvaluateTreatment(o);
}

// One seed of `preset` with the product's options (after `setup`), then
// again with the evaluation's options changed.
std::pair<TreatmentEvaluation, TreatmentEvaluation> OneSeedAndChangedEvaluation(
    const char* preset, const std::function<void(TreatmentEvalOptions&)>& change,
    const std::function<void(TreatmentEvalOptions&)>& setup = {}) {
  TreatmentEvalOptions o;
  o.sim = LoadSimulatorPreset(preset, DefaultConfigDir());
  o.seeds = 1;
  o.profiles = LoadProfiles("", "", o.sim.preset, DefaultConfigDir());
  o.treatment = ProductTreatmentOptions(*o.profiles);
  if (setup) setup(o);
  TreatmentEvaluation product = EvaluateTreatment(o);
  change(o);
  return {std::move(product), EvaluateTreatment(o)};
}

// The same with the treatment options changed.
std::pair<TreatmentEvaluation, TreatmentEvaluation> OneSeedAndChanged(
    const char* preset, const std::function<void(treatment::TreatmentOptions&)>& change,
    const std::function<void(TreatmentEvalOptions&)>& setup = {}) {
  return OneSeedAndChangedEvaluation(
      preset, [&](TreatmentEvalOptions& o) { change(o.treatment); }, setup);
}

// A grower who measured the field's spreads (the values the shipped
// profiles held before they left them to the grower's defaults, issue 59):
// planter 16 mm, size 0.15, bounce 0.3° / 0.2° / 4 mm. The options below
// were designed for a known crop; with the defaults (planter 20 mm, size
// 0.2, bounce 0.5° / 0.3° / 5 mm) seed 1's along RMS is 10.06 mm, the slip
// guard gains 0.16 mm and height from size costs 0.34 mm (docs/results/figures.md).
void WithMeasuredSpreads(TreatmentEvalOptions& o) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  o.profiles->crop.planter_sd_m = 0.016;
  o.profiles->crop.leaf_radius_sd_fraction = 0.15;
  o.profiles->vehicle.pitch_sd_rad = 0.3 * kDeg;
  o.profiles->vehicle.roll_sd_rad = 0.2 * kDeg;
  o.profiles->vehicle.height_sd_m = 0.004;
  o.profiles->vehicle.suspension_given = true;
  o.treatment = ProductTreatmentOptions(*o.profiles);
}

// `better` hits every crop `worse` hits, its placement RMS along is at
// least `along_gain_m` lower, across at most `across_slack_m` higher, on the
// same share of the bed (within 0.3 %), over more than 200 crops.
void ExpectCloserAlongOnTheSameBed(const TreatmentEvaluation& better,
                                   const TreatmentEvaluation& worse, double along_gain_m,
                                   double across_slack_m) {
  ASSERT_GT(better.ours.crop_plants, 200);
  EXPECT_GE(better.ours.crop_hit_rate, worse.ours.crop_hit_rate);
  EXPECT_LT(better.ours.placement_rms_along_m, worse.ours.placement_rms_along_m - along_gain_m);
  EXPECT_LT(better.ours.placement_rms_across_m,
            worse.ours.placement_rms_across_m + across_slack_m);
  EXPECT_NEAR(better.ours.treated_area_fraction, worse.ours.treated_area_fraction, 0.003);
}

TEST(TreatmentSystem, FieldSprayCrop) {
  const TreatmentEvaluation e = Evaluate("field", 5, 0.0, true);
  ASSERT_TRUE(e.thesis);
  const TreatmentMetrics& m = e.ours;
  ASSERT_GE(m.crop_plants, 1000);  // issue: ≥ 1000 crop plants over the seeds
  EXPECT_EQ(e.mode, "crop");
  // Issue target 99.5 %: met, 100 % (1103 of 1103; 99.91 % with footprints
  // on each frame's centroid, 99.27 % before merged blobs were split).
  EXPECT_GE(m.crop_hit_rate, 0.995);
  EXPECT_LE(e.missed_crops.size(), 2u);
  for (const MissedCrop& c : e.missed_crops) EXPECT_GE(c.nearest_spray_m, 0.0);
  // Issue: |bias| ≤ 3 mm on both axes (thesis 9.7 / −23.1 mm): met,
  // +0.8 / −0.7 mm.
  EXPECT_LE(std::abs(m.placement_bias_along_m), 0.003);
  EXPECT_LE(std::abs(m.placement_bias_across_m), 0.003);
  // Issue target RMS ≤ 10 mm (to the root, as the thesis's fig. 8.3):
  // met, 9.39 mm along and 9.64 mm across (9.50 / 9.83 before soil
  // growth, vision/soil_growth.h), with the bar commanded at
  // 200 Hz and the tracker's slip guard (10.3 / 9.8 mm at 50 Hz without
  // it), each plant's
  // centroid height read from its blob's size (10.8 / 9.6 mm without),
  // footprints at the
  // grid node plus 0.7 of each plant's own offset along and the tracker's
  // offsets walking 6 mm/√m along (11.9 / 9.8 mm before both; 11.5 / 9.7
  // with the walk alone), each plant's footprints following it along to
  // where the tracker last holds it, the tracker taking no merged or
  // weed-sized blob for a plant, and merged blobs' boxes casting doubt on
  // the crops' plane rather than weed votes on the weeds' (12.7 / 9.8 mm
  // with those; 16.5 / 10.0 mm before following; 27.0 / 12.2 on each
  // frame's centroid; 28.5 / 12.4 with one virtual plane); thesis 34.4 /
  // 33.6 mm. The plants' lean (10 mm sd of the rim from the root, hidden
  // under the canopy the camera sees) puts about 6 mm along: 10.0 mm with
  // no lean.
  EXPECT_LE(m.placement_rms_along_m, 0.010);
  EXPECT_LE(m.placement_rms_across_m, 0.0105);
  EXPECT_LE(m.centre_rms_across_m, 0.0115);
  // Issue target ≤ 15 % of the bed: met, 7.5 % (6.8 % before soil growth
  // took the plants' shaded rims) with 0.30 footprints (6.9 % before
  // merged blobs cast doubt; 7.3 % before footprints followed
  // their plants; thesis 33 %).
  EXPECT_LE(m.treated_area_fraction, 0.15);
  EXPECT_GE(m.treated_area_fraction, 0.04);  // a real spray pattern, not nothing
  // Weeds clear of the crop's leaves are hardly sprayed (3 of 1115 with
  // soil growth, 0 before: the thesis's count, which saw weeds on
  // photographs; 2.2 % on each frame's centroid); weeds under a crop's
  // leaves share its spray (14.0 % of all weeds with soil growth; 12.1 % of all
  // weeds hit with 0.30 footprints, 18.5 % with 0.40; 12.35 % with
  // footprints at 0.7 of the plant's own offset along; 12.9 % with the bar
  // at 200 Hz and the slip guard). 36 % of the weeds stand under a crop's
  // leaves, so the "weeds hit ≤ 0.5 %" is read as the thesis's
  // count, the weeds clear of crop (docs/results/, treatment).
  EXPECT_LE(m.weed_hit_rate_clear, 0.005);
  EXPECT_LE(m.weed_hit_rate, 0.145);
  // Crop pixels labelled crop 98.7 %: issue target 95 % met on the field
  // (96.8 % before soil growth, 96.7 % before leaf fragments, 93.6 % before the plants beyond the
  // view's border were predicted, 91.5 % before the hull growth, 85.0 %
  // before segmentation filled holes and closed notches). Of the crop pixels segmented as plant 99.8 % are
  // labelled crop (thesis table 7.9: 93.1–96.4 %).
  EXPECT_GE(m.crop_pixel_rate, 0.95);
  EXPECT_GE(m.crop_pixel_rate_of_plant, 0.98);
  EXPECT_NEAR(m.crop_pixel_rate_of_plant, m.crop_as_crop / (m.crop_as_crop + m.crop_as_weed),
              1e-12);
  // Leaf fragments of one grid plant make one record (15818 before; 11900
  // before soil growth joined the halves of plants split by shade, 8324
  // before session 27). Weeds merged with a crop's blob are recorded since
  // (TreatmentOptions::outline_weed_votes, ClassifierOptions::
  // outline_limit_sd): 11557 now, the 3,233 more mostly weed parts seen in
  // one or two frames, never confirmed; the confirmed ones are held below.
  EXPECT_LT(m.plants_recorded, 12500);
  // Of those records, the plants (seen in ≥ 3 frames and ≥ 40 % of those
  // that looked at them, PlantRecord::confirmed) number about the plants
  // there are: 620 for 222 crops and 352 weeds on seed 1 (2692 records).
  EXPECT_NEAR(m.plants_confirmed, m.crop_plants + m.weeds, 0.2 * (m.crop_plants + m.weeds));
  // Never sprayed while the fail-safe holds the bar closed: at most the
  // initialisation frames.
  EXPECT_LT(m.ticks_fail_safe, m.ticks / 50);
  // Against the thesis's chain on the same frames: far less of the bed and
  // of the weeds sprayed.
  EXPECT_LT(m.treated_area_fraction, 0.5 * e.thesis->treated_area_fraction);
  EXPECT_LT(m.weed_hit_rate, 0.6 * e.thesis->weed_hit_rate);
  EXPECT_GT(m.crop_pixel_rate, e.thesis->crop_pixel_rate);
  EXPECT_LT(m.placement_rms_along_m, e.thesis->placement_rms_along_m);
}

// A plant's footprints from its far views carry the parallax of its own
// height: moved along to its latest (nearest) estimate, the spray lands
// closer to the root. Field, seed 1 (222 crops): along RMS 12.9 mm against
// 15.5 mm with each footprint left where its frame put it (across 9.8 and
// 9.5 mm).
TEST(TreatmentSystem, FootprintsFollowingTheirPlantSprayCloserAlong) {
  const auto [follow, stay] = OneSeedAndChanged(
      "field", [](treatment::TreatmentOptions& t) { t.crop_footprint_follows_plant = false; });
  ASSERT_GT(follow.ours.crop_plants, 200);
  EXPECT_GE(follow.ours.crop_hit_rate, stay.ours.crop_hit_rate);
  EXPECT_LT(follow.ours.placement_rms_along_m, stay.ours.placement_rms_along_m - 0.002);
  EXPECT_LT(follow.ours.placement_rms_across_m, stay.ours.placement_rms_across_m + 0.001);
  EXPECT_LE(follow.ours.treated_area_fraction, stay.ours.treated_area_fraction);
}

// The root hides under the canopy: what the tracker holds as a plant's own
// offset along the rows is partly its lean and the parallax of its own
// height, which its grid node does not share. Footprints at the node plus
// 0.7 of that offset land nearer the root. Field, seed 1 (222 crops, all
// hit either way): along RMS 11.1 mm against 12.5 mm at the whole offset,
// across 9.5 against 9.8 mm, 6.65 % of the bed both.
TEST(TreatmentSystem, FootprintsAtPartOfThePlantsOwnOffsetSprayCloserToTheRoot) {
  const auto [part, whole] = OneSeedAndChanged(
      "field", [](treatment::TreatmentOptions& t) { t.own_offset_fraction_along = 1.0; });
  ExpectCloserAlongOnTheSameBed(part, whole, 0.001, 0.0005);
}

// A plant's size sets its centroid's height, whose parallax moves its
// located centroid along the rows as it crosses the view: with each blob's
// size read as a pseudo-observation of the plant's height
// (TrackerOptions::height_from_size), the tracker holds it nearer its root.
// Field, seed 1 (222 crops, all hit either way): along RMS 10.25 mm against
// 11.10 mm without, across 9.94 against 9.53 mm, 6.65 % of the bed both.
TEST(TreatmentSystem, HeightsReadFromBlobSizesSprayCloserAlong) {
  const auto [sized, unsized] = OneSeedAndChangedEvaluation(
      "field",
      [](TreatmentEvalOptions& o) {
        o.adjust_tracker = [](tracking::TrackerOptions& t) { t.height_from_size = false; };
      },
      WithMeasuredSpreads);
  ExpectCloserAlongOnTheSameBed(sized, unsized, 0.0005, 0.0007);
}

// A wheel spinning 15 % long runs the dead-reckoned grid ahead of the
// plants between frames, and the nozzles fire late; the tracker's slip
// guard holds the ground speed from before the jump. Field, seed 1 (222
// crops, all hit either way): along RMS 9.44 mm against 10.61 mm without,
// across 10.25 against 10.17 mm.
TEST(TreatmentSystem, TheSlipGuardSpraysCloserAlong) {
  const auto [guarded, unguarded] = OneSeedAndChangedEvaluation(
      "field",
      [](TreatmentEvalOptions& o) {
        o.adjust_tracker = [](tracking::TrackerOptions& t) { t.slip_guard.enabled = false; };
      },
      WithMeasuredSpreads);
  ExpectCloserAlongOnTheSameBed(guarded, unguarded, 0.0006, 0.0005);
}

// No odometry for 10 m (issue 38's stop). Wheels alone, the bar stays
// closed while they are silent; with the camera's motion standing in (its
// search centred on the grid's own motion, its distance scale learnt
// against the wheels before, the bar ticked from each frame until the next)
// it sprays on. Field, tuning seed 1: 61 of 61 crops in the stretch hit,
// placement RMS 14.2 mm (issue: ≤ 15 mm); wheels alone 0 of 61.
TEST(TreatmentSystem, TheCameraStandsInForOdometryThatStops) {
  const auto [wheels, camera] = OneSeedAndChangedEvaluation(
      "field", [](TreatmentEvalOptions& o) { o.visual_motion = true; },
      [](TreatmentEvalOptions& o) { o.odometry_fault = DefaultOdometryFault(OdometryFaultKind::kStop); });
  ASSERT_TRUE(wheels.fault_stretch && camera.fault_stretch);
  ASSERT_GT(camera.fault_stretch->crop_plants, 50);
  EXPECT_EQ(wheels.fault_stretch->crop_hits, 0);
  EXPECT_GE(camera.fault_stretch->crop_hit_rate, 0.97);
  EXPECT_LT(camera.fault_stretch->placement_rms_m, 0.017);
  EXPECT_GE(camera.ours.crop_hit_rate, 0.97);
}

// A 3-week crop's scaled box is some ±15 mm, under 2σ of the placement:
// stretched to ±25 mm it covers the root. D, seed 1 (229 crops): 100 %
// hit on 2.0 % of the bed against 98.7 % on 1.5 % unstretched (98.7 and
// 94.8 % before the bar ran at 200 Hz and the tracker guarded against
// slip; 97.4 and 92.6 % before lone small crops were crop).
TEST(TreatmentSystem, SmallCropsFootprintsStretchedToCoverThePlacementError) {
  const auto [stretched, scaled] = OneSeedAndChanged(
      "D", [](treatment::TreatmentOptions& t) {
        t.crop_footprint_min_half_m = 0.0;
        // The fail-safe's margin is derived from the stretch; without it
        // the comparison is of the footprints alone.
        t.close_on_uncertainty = false;
      });
  ASSERT_GT(stretched.ours.crop_plants, 200);
  EXPECT_GE(stretched.ours.crop_hit_rate, 0.99);
  EXPECT_GT(stretched.ours.crop_hit_rate, scaled.ours.crop_hit_rate + 0.008);
  EXPECT_LE(stretched.ours.treated_area_fraction, 0.025);
}

// Spray-weed mode, field, 20 m of seed 1 (158 weeds, 106 clear of the
// crop's leaves; 96 crops).
TEST(TreatmentSystem, FieldSprayWeedSparesTheCrop) {
  const auto [product, whole_box] = OneSeedAndChanged(
      "field", [](treatment::TreatmentOptions& t) { t.merged_weed_parts_only = false; },
      [](TreatmentEvalOptions& o) {
        o.sim.length_m = 20.0;
        o.treatment.scheduler.mode = treatment::SprayMode::kWeed;
      });
  const TreatmentMetrics& m = product.ours;
  EXPECT_EQ(product.mode, "weed");
  ASSERT_GT(m.weeds, 50);
  // 73.6 % of the weeds clear of the crop are sprayed on 4.7 % of the bed.
  // Weed blobs are located at the weeds' own height (31 % when they stood
  // on the crop's 0.1 m plane, 20 cm beyond where they are 3 m ahead) and
  // one vote makes a weed cell (TreatmentMapOptions::weed_majority_threshold).
  // The weeds missed are mostly small ones lost to segmentation (≈ 30 % of
  // weed pixels labelled soil) and weeds just beyond a crop, which its
  // canopy hides or joins in every view. The crop is spared: none of 96 hit.
  EXPECT_GT(m.weed_hit_rate_clear, 0.68);
  EXPECT_LT(m.crop_hit_rate, 0.03);
  EXPECT_LT(m.treated_area_fraction, 0.07);
  // Merged blobs voting weed with their whole box, as wide as two crops and
  // on the weeds' low plane, sprayed a third of the bed (34.9 %) to reach
  // 93.4 % of these weeds: blanket spraying beside every crop.
  EXPECT_LT(m.treated_area_fraction, 0.25 * whole_box.ours.treated_area_fraction);
}

// Crop pixels labelled crop (thesis tables 7.5–7.8: 95.1, 78.9, 81.7, 55.0 %
// on A–D). Issue target ≥ 95 % on every preset: met over 5 seeds (A 97.2,
// B 97.9, C 99.0, D 95.2 %) since soil growth (engine/vision/soil_growth.h)
// took back shaded leaf at the plants' rims; before it B and D were 91.9
// and 91.5 %, segmentation losing 7.4–7.7 % of their crop pixels to soil.
// Blobs that miss every association region are split among the predicted
// crops, which lifts A (touching plants merged) from 48 %. On 10 m, 1 seed:
// 94.8 / 97.0 / 98.7 / 93.9 % (93.8 / 91.2 / 96.6 / 90.2 % without soil
// growth; 85.6 / 85.0 / 90.6 / 84.1 % before the hull growth and the plants
// beyond the view's border); bounds 2–2.5 points below.
struct PixelCase {
  const char* preset;
  double at_least;
};

class TreatmentPixels : public ::testing::TestWithParam<PixelCase> {};

TEST_P(TreatmentPixels, CropPixelsLabelledCrop) {
  const PixelCase c = GetParam();
  const TreatmentEvaluation e = Evaluate(c.preset, 1, 10.0, false);
  ASSERT_GT(e.ours.frames_classified, 50);
  EXPECT_GE(e.ours.crop_pixel_rate, c.at_least) << c.preset;
}

INSTANTIATE_TEST_SUITE_P(Presets, TreatmentPixels,
                         ::testing::Values(PixelCase{"A", 0.925}, PixelCase{"B", 0.95},
                                           PixelCase{"C", 0.965}, PixelCase{"D", 0.915}),
                         [](const auto& test_param) { return std::string(test_param.param.preset); });

}  // namespace
}  // namespace plantscale::app
