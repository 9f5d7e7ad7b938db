#include "app/config/profiles.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "app/config/config_loader.h"
#include "evaluation/tracking_eval.h"
#include "evaluation/treatment_eval.h"

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;

constexpr double kDeg = std::numbers::pi / 180.0;

fs::path Write(const std::string& name, const std::string& text) {
  const fs::path p =
      fs::temp_directory_path() / ("plantscale_profiles_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p) << text;
  return p;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Profiles, EveryShippedProfileLoads) {
  for (const std::string& name : ListConfigNames(DefaultConfigDir() / "crops")) {
    EXPECT_NO_THROW(LoadCropProfile(name, DefaultConfigDir())) << name;
  }
  for (const std::string& name : ListConfigNames(DefaultConfigDir() / "vehicles")) {
    EXPECT_NO_THROW(LoadVehicleProfile(name, DefaultConfigDir())) << name;
  }
  EXPECT_GE(ListConfigNames(DefaultConfigDir() / "crops").size(), 3u);
}

TEST(Profiles, FieldPresetDefaultsAreTheNominalCropByName) {
  const Profiles p = LoadProfiles("", "", "field", DefaultConfigDir());
  EXPECT_EQ(p.crop.name, "cauliflower-6-week");
  EXPECT_EQ(p.vehicle.name, "silsoe");
  EXPECT_DOUBLE_EQ(p.crop.plant_spacing_m, 0.45);  // the planter's setting, not the planted 0.467
  EXPECT_DOUBLE_EQ(p.vehicle.camera.height_m, 1.5);
  EXPECT_DOUBLE_EQ(EngineCamera(p).virtual_plane_height_m, 0.1);
  const pipeline::PipelineOptions o = ProductPipelineOptions(p);
  EXPECT_EQ(o.tracker.rows_each_side, 1);
  EXPECT_DOUBLE_EQ(o.tracker.crop_radius_m, 0.14);
  EXPECT_DOUBLE_EQ(o.tracker.crop_height_m, 0.112);
  // The profile leaves the bounce and the spreads to a grower's defaults
  // (docs/profiles.md), not the simulator's field values.
  EXPECT_NEAR(o.tracker.camera_pitch_sd_rad, 0.5 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(p.crop.planter_sd_m, kGrowerPlanterSdM);
  EXPECT_DOUBLE_EQ(p.crop.leaf_radius_sd_fraction, kGrowerLeafRadiusSdFraction);
  EXPECT_DOUBLE_EQ(o.tracker.plant_offset_sd_m, 0.02);
  EXPECT_DOUBLE_EQ(o.treatment.scheduler.bar.valve_latency_s, 0.04);
  EXPECT_EQ(o.treatment.scheduler.bar.nozzles, 64);
  // A preset without a nominal crop needs --crop and --vehicle.
  EXPECT_NE(ErrorOf([] { DefaultProfileNames("my-own"); }).find("give both"), std::string::npos);
}

// A bed wider than the spray bar is said, naming both files and the rows;
// every shipped pairing of a preset's crop and vehicle says nothing.
TEST(Profiles, RowsBeyondOrNearTheSprayBarsEndAreSaid) {
  for (const char* preset : {"A", "B", "C", "D", "field", "long", "treatment", "testbed", "sanchiz_pla",
                             "lettuce-fast", "cabbage-wide"}) {
    EXPECT_TRUE(ProfileWarnings(LoadProfiles("", "", preset, DefaultConfigDir())).empty()) << preset;
  }
  Profiles p = LoadProfiles("", "", "field", DefaultConfigDir());  // silsoe: 64 × 22.5 mm, ±0.72 m
  p.crop.file = "five-rows.yaml";
  p.crop.rows = 5;
  p.crop.row_spacing_m = 0.5;
  p.crop.planter_sd_m = 0.016;
  std::vector<std::string> w = ProfileWarnings(p);
  ASSERT_EQ(w.size(), 1u);  // the rows at ±0.5 m are 0.22 m inside the bar's ends
  EXPECT_NE(w[0].find("five-rows.yaml: the rows at -100.0 cm and +100.0 cm of the 5-row bed lie beyond"),
            std::string::npos)
      << w[0];
  EXPECT_NE(w[0].find("silsoe.yaml (64 nozzles of 22.5 mm, from -72.0 cm to 72.0 cm across the vehicle)"),
            std::string::npos)
      << w[0];
  EXPECT_NE(w[0].find("will not be treated"), std::string::npos);
  // Three rows 0.7 m apart: the outer lines 2 cm inside the ends, planter sd 2 cm.
  p.crop.rows = 3;
  p.crop.row_spacing_m = 0.7;
  p.crop.planter_sd_m = 0.02;
  w = ProfileWarnings(p);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("the rows at -70.0 cm and +70.0 cm stand within two planter sd (4.0 cm) of the end"),
            std::string::npos)
      << w[0];
  p.crop.planter_sd_m = 0.009;  // 1.8 cm: clear of the ends
  EXPECT_TRUE(ProfileWarnings(p).empty());
  // A bar moved 0.3 m to the right: only the left row is past its end.
  p.vehicle.bar.centre_x_m = 0.3;
  w = ProfileWarnings(p);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("the row at -70.0 cm of the 3-row bed lies beyond"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("from -42.0 cm to 102.0 cm"), std::string::npos) << w[0];
}

TEST(Profiles, AnUnknownVehicleGetsDefaultSuspension) {
  const VehicleProfile v = LoadVehicleProfile("sanchiz-pla-66", DefaultConfigDir());
  EXPECT_FALSE(v.suspension_given);
  EXPECT_NEAR(v.pitch_sd_rad, 0.5 * kDeg, 1e-12);
  EXPECT_NEAR(v.roll_sd_rad, 0.3 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(v.height_sd_m, 0.005);
  // No shipped profile copies the simulator's spreads: every crop and
  // vehicle leaves them to the defaults.
  for (const std::string& name : ListConfigNames(DefaultConfigDir() / "vehicles")) {
    EXPECT_FALSE(LoadVehicleProfile(name, DefaultConfigDir()).suspension_given) << name;
  }
  for (const std::string& name : ListConfigNames(DefaultConfigDir() / "crops")) {
    const CropProfile c = LoadCropProfile(name, DefaultConfigDir());
    EXPECT_DOUBLE_EQ(c.planter_sd_m, 0.02) << name;
    EXPECT_DOUBLE_EQ(c.leaf_radius_sd_fraction, 0.2) << name;
  }
}

// How well the camera was calibrated: the roll's sd becomes the tracker's
// calibration state; absent, a field calibration's figures; all 0, none.
TEST(Profiles, CalibrationUncertaintyReachesTheTrackersRollState) {
  const fs::path dir = DefaultConfigDir();
  const VehicleProfile unknown = LoadVehicleProfile("sanchiz-pla-66", dir);
  EXPECT_NEAR(unknown.calibration_roll_sd_rad, 0.3 * kDeg, 1e-12);
  EXPECT_NEAR(unknown.calibration_tilt_sd_rad, 0.5 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(unknown.calibration_height_sd_m, 0.01);
  EXPECT_DOUBLE_EQ(unknown.calibration_focal_sd, 0.01);
  const Profiles field = LoadProfiles("", "", "field", dir);
  const tracking::TrackerOptions o = ProductTrackerOptions(field);
  EXPECT_NEAR(o.calibration_roll_sd_rad, 0.3 * kDeg, 1e-12);
  EXPECT_TRUE(o.CalibrationStates());
  EXPECT_EQ(o.calibration_pitch_sd_rad, 0.0);
  EXPECT_EQ(o.calibration_height_sd_m, 0.0);
  EXPECT_EQ(o.calibration_focal_sd, 0.0);
  const Profiles trusted = LoadProfiles("", "silsoe-trusted-calibration", "field", dir);
  EXPECT_FALSE(ProductTrackerOptions(trusted).CalibrationStates());
  const fs::path bad = Write("calsd.yaml",
                             "track_width_m: 1.5\ncamera: {calibration: thesis, image_width_px: 640, "
                             "image_height_px: 480}\nvalve_latency_s: 0.04\nnozzles: {count: 64, "
                             "spacing_m: 0.0225, bar_offset_m: 0.6}\ncalibration_sd: {tilt_deg: 0.5, "
                             "roll_deg: 30, height_m: 0.01, focal: 0.01}\n");
  EXPECT_NE(ErrorOf([&] { LoadVehicleProfile(bad.string(), dir); })
                .find(bad.string() + ": calibration_sd.roll_deg: is 30, expected 0 to 5 deg"),
            std::string::npos)
      << ErrorOf([&] { LoadVehicleProfile(bad.string(), dir); });
}

// The contract: the engine's options are built from the profiles
// only, so they do not move when the simulator's hidden parameters do.
TEST(Profiles, EngineOptionsDoNotChangeWithTheSimulatorsHiddenParameters) {
  TrackingEvalOptions t;
  t.sim = LoadSimulatorPreset("field", DefaultConfigDir());
  t.profiles = LoadProfiles("", "", "field", DefaultConfigDir());
  t.calibration_error = {0.01, 0.5, 0.3, 0.01};
  TreatmentEvalOptions r;
  r.sim = t.sim;
  r.profiles = t.profiles;
  r.calibration_error = t.calibration_error;
  const TrackingEngine before = TrackingEngineOf(t, 1000);
  const geometry::CameraOptions treatment_before = TreatmentEngineCamera(r, 1000);

  sim::SimulatorOptions& s = t.sim;
  s.field.row_spacing_m = 0.5;
  s.field.plant_spacing_m = 0.41;
  s.field.nominal_plant_spacing_m = 0.40;
  s.field.crop_radius_m = 0.2;
  s.field.crop_height_ratio = 0.5;
  s.field.crop_radius_sd_fraction = 0.3;
  s.field.planting_jitter_m = 0.03;
  s.field.crop_lean_sd_m = 0.02;
  s.field.rows = 5;
  s.vehicle.track_width_m = 1.8;
  s.vehicle.bump_pitch_sd_rad = 0.02;
  s.vehicle.bump_roll_sd_rad = 0.02;
  s.vehicle.bump_height_sd_m = 0.01;
  s.vehicle.bump_correlation_s = 1.0;
  s.camera.height_m = 1.3;
  s.camera.tilt_rad += 0.1;
  s.camera.focal_length_m *= 1.1;
  s.camera.virtual_plane_height_m = 0.0;
  r.sim = s;
  const TrackingEngine after = TrackingEngineOf(t, 1000);
  const geometry::CameraOptions treatment_after = TreatmentEngineCamera(r, 1000);

  for (const auto& [a, b] : {std::pair{before.camera, after.camera},
                             std::pair{treatment_before, treatment_after},
                             std::pair{before.camera, treatment_before}}) {
    EXPECT_EQ(a.height_m, b.height_m);
    EXPECT_EQ(a.tilt_rad, b.tilt_rad);
    EXPECT_EQ(a.roll_rad, b.roll_rad);
    EXPECT_EQ(a.focal_length_m, b.focal_length_m);
    EXPECT_EQ(a.virtual_plane_height_m, b.virtual_plane_height_m);
  }
  for (const auto& [a, b] : {std::pair{before.ours, after.ours}, std::pair{before.thesis, after.thesis}}) {
    EXPECT_EQ(a.rows_each_side, b.rows_each_side);
    EXPECT_EQ(a.row_spacing_m, b.row_spacing_m);
    EXPECT_EQ(a.plant_spacing_m, b.plant_spacing_m);
    EXPECT_EQ(a.track_width_m, b.track_width_m);
    EXPECT_EQ(a.crop_radius_m, b.crop_radius_m);
    EXPECT_EQ(a.crop_height_m, b.crop_height_m);
    EXPECT_EQ(a.plant_height_sd_m, b.plant_height_sd_m);
    EXPECT_EQ(a.plant_offset_sd_m, b.plant_offset_sd_m);
    EXPECT_EQ(a.plant_offset_walk_across_sd_per_sqrt_m, b.plant_offset_walk_across_sd_per_sqrt_m);
    EXPECT_EQ(a.camera_pitch_sd_rad, b.camera_pitch_sd_rad);
    EXPECT_EQ(a.camera_roll_sd_rad, b.camera_roll_sd_rad);
    EXPECT_EQ(a.camera_height_sd_m, b.camera_height_sd_m);
    EXPECT_EQ(a.camera_bounce_correlation_s, b.camera_bounce_correlation_s);
  }
  // ... and they are the profile's.
  EXPECT_EQ(after.ours.plant_spacing_m, 0.45);
  EXPECT_EQ(after.ours.crop_radius_m, 0.14);
  EXPECT_EQ(after.ours.rows_each_side, 1);
}

TEST(Profiles, CalibrationErrorIsDrawnPerSeedWithTheGivenSds) {
  const CalibrationError a = ParseCalibrationError(
      "height_m=0.01,tilt_deg=0.5,roll_deg=0.3,focal=0.01", "--calibration-error");
  EXPECT_DOUBLE_EQ(a.height_m, 0.01);
  EXPECT_DOUBLE_EQ(a.tilt_deg, 0.5);
  EXPECT_DOUBLE_EQ(a.roll_deg, 0.3);
  EXPECT_DOUBLE_EQ(a.focal, 0.01);
  const geometry::CameraOptions c = LoadCamera("thesis", DefaultConfigDir());
  // 400 seeds: the sample sd of each parameter within 10 % of the given sd
  // (the sd of a sample sd of 400 normals is about 3.5 %), the mean within
  // 0.15 sd, and draws beyond 2 sd occur (about 4.6 % of them, 18 expected).
  constexpr int kSeeds = 400;
  double h2 = 0.0, t2 = 0.0, r2 = 0.0, f2 = 0.0, h1 = 0.0, t1 = 0.0;
  int beyond_two_sd = 0;
  for (uint64_t seed = 0; seed < kSeeds; ++seed) {
    const CalibrationError e = DrawnCalibrationError(a, seed);
    const CalibrationError again = DrawnCalibrationError(a, seed);
    EXPECT_EQ(e.height_m, again.height_m);  // the same seed, the same draw
    EXPECT_EQ(e.focal, again.focal);
    const geometry::CameraOptions off = ApplyCalibrationError(c, e);
    EXPECT_NEAR(off.height_m - c.height_m, e.height_m, 1e-12);
    EXPECT_NEAR(off.tilt_rad - c.tilt_rad, e.tilt_deg * kDeg, 1e-12);
    EXPECT_NEAR(off.roll_rad - c.roll_rad, e.roll_deg * kDeg, 1e-12);
    EXPECT_NEAR(off.focal_length_m / c.focal_length_m - 1.0, e.focal, 1e-12);
    h2 += e.height_m * e.height_m;
    t2 += e.tilt_deg * e.tilt_deg;
    r2 += e.roll_deg * e.roll_deg;
    f2 += e.focal * e.focal;
    h1 += e.height_m;
    t1 += e.tilt_deg;
    beyond_two_sd += std::abs(e.tilt_deg) > 2.0 * a.tilt_deg;
  }
  EXPECT_NEAR(std::sqrt(h2 / kSeeds), 0.01, 0.1 * 0.01);
  EXPECT_NEAR(std::sqrt(t2 / kSeeds), 0.5, 0.1 * 0.5);
  EXPECT_NEAR(std::sqrt(r2 / kSeeds), 0.3, 0.1 * 0.3);
  EXPECT_NEAR(std::sqrt(f2 / kSeeds), 0.01, 0.1 * 0.01);
  EXPECT_NEAR(h1 / kSeeds, 0.0, 0.15 * 0.01);
  EXPECT_NEAR(t1 / kSeeds, 0.0, 0.15 * 0.5);
  EXPECT_GE(beyond_two_sd, 6);
  EXPECT_LE(beyond_two_sd, 35);
  // Seeds next to each other draw independently: not the same tilt.
  EXPECT_NE(DrawnCalibrationError(a, 7).tilt_deg, DrawnCalibrationError(a, 8).tilt_deg);
  // No sd, no error.
  const CalibrationError none = DrawnCalibrationError(CalibrationError{}, 3);
  EXPECT_FALSE(none.any());
  EXPECT_NE(ErrorOf([] { ParseCalibrationError("tilt=0.5", "--calibration-error"); })
                .find("--calibration-error: tilt: unknown key"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseCalibrationError("focal=-0.01", "--calibration-error"); })
                .find("expected 0 to 0.2"),
            std::string::npos);
}

constexpr const char* kCrop =
    "rows: 3\nrow_spacing_m: 0.475\nplant_spacing_m: 0.45\nleaf_radius_m: 0.14\n"
    "leaf_radius_sd_fraction: 0.15\nleaf_height_m: 0.112\nplanter_sd_m: 0.016\n";

TEST(Profiles, BadInputNamesFileKeyAndRange) {
  const fs::path dir = DefaultConfigDir();
  const fs::path missing = Write("missing.yaml", "rows: 3\nrow_spacing_m: 0.475\n");
  EXPECT_NE(ErrorOf([&] { LoadCropProfile(missing.string(), dir); })
                .find(missing.string() + ": plant_spacing_m: missing (expected 0.02 to 2 m)"),
            std::string::npos);
  std::string unit = kCrop;
  unit.replace(unit.find("plant_spacing_m: 0.45"), 21, "plant_spacing_m: 450");
  const fs::path mm = Write("mm.yaml", unit);
  EXPECT_NE(ErrorOf([&] { LoadCropProfile(mm.string(), dir); })
                .find(mm.string() + ": plant_spacing_m: is 450, expected 0.02 to 2 m"),
            std::string::npos);
  const fs::path typo = Write("typo.yaml", std::string(kCrop) + "leaf_hieght_m: 0.1\n");
  EXPECT_NE(ErrorOf([&] { LoadCropProfile(typo.string(), dir); }).find("leaf_hieght_m: unknown key"),
            std::string::npos);
  const std::string vehicle =
      "track_width_m: 1.5\ncamera: {calibration: thesis, image_width_px: 640, "
      "image_height_px: 480}\nvalve_latency_s: 0.04\nnozzles: {count: 64, spacing_m: 0.0225, "
      "bar_offset_m: 0.6}\n";
  EXPECT_NO_THROW(LoadVehicleProfile(Write("good.yaml", vehicle).string(), dir));
  std::string neg = vehicle;
  neg.replace(neg.find("valve_latency_s: 0.04"), 21, "valve_latency_s: -0.04");
  const fs::path negative = Write("neg.yaml", neg);
  EXPECT_NE(ErrorOf([&] { LoadVehicleProfile(negative.string(), dir); })
                .find(negative.string() + ": valve_latency_s: is -0.04, expected 0 to 0.5 s"),
            std::string::npos);
  std::string size = vehicle;
  size.replace(size.find("calibration: thesis"), 19, "calibration: sanchiz_pla_66");
  const fs::path other = Write("size.yaml", size);
  EXPECT_NE(ErrorOf([&] { LoadVehicleProfile(other.string(), dir); })
                .find(other.string() + ": camera.calibration: "),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { LoadVehicleProfile(other.string(), dir); })
                .find("is for 768x576 px images, expected 640x480 px"),
            std::string::npos);
  // A vehicle whose camera is not the simulator's size.
  const VehicleProfile sanchiz = LoadVehicleProfile("sanchiz-pla-66", dir);
  EXPECT_NE(ErrorOf([&] { RequireImageSize(sanchiz, 640, 480); }).find("the camera's are 640x480 px"),
            std::string::npos);
  for (const fs::path& p : {missing, mm, typo, negative, other}) fs::remove(p);
  fs::remove(Write("good.yaml", ""));
}

// `segmenter: {model, min_confidence}`: a name in config/models or a path
// beside the profile; the pipeline's learned options carry the model's
// bytes and card, or, for a model that cannot be read, the reason.
TEST(Profiles, SegmenterModelKeyNamesTheGrowersModel) {
  const fs::path dir = DefaultConfigDir();
  const fs::path named = Write("named.yaml", std::string(kCrop) + "segmenter: {model: peanut, min_confidence: 0.75}\n");
  const CropProfile c = LoadCropProfile(named.string(), dir);
  EXPECT_EQ(fs::path(c.segmenter_model), dir / "models" / "peanut.onnx");
  EXPECT_DOUBLE_EQ(c.segmenter_min_confidence, 0.75);
  const pipeline::LearnedOptions l = LearnedPipelineOptions(c);
  ASSERT_TRUE(l.enabled());
  ASSERT_TRUE(l.onnx);
  EXPECT_EQ(l.onnx->size(), fs::file_size(dir / "models" / "peanut.onnx"));
  EXPECT_EQ(l.spec.channels, 3);
  EXPECT_TRUE(l.unreadable.empty());
  Profiles p{c, LoadVehicleProfile("silsoe", dir)};
  EXPECT_DOUBLE_EQ(ProductPipelineOptions(p).treatment.classifier.learned_min_confidence, 0.75);
  EXPECT_TRUE(ProductPipelineOptions(p).learned.enabled());
  // None named: off.
  EXPECT_FALSE(LearnedPipelineOptions(LoadCropProfile("cauliflower-6-week", dir)).enabled());
  // A model that is not there: refused naming the file, the key and the path.
  const fs::path gone = Write("gone.yaml", std::string(kCrop) + "segmenter: {model: no-such-model}\n");
  EXPECT_NE(ErrorOf([&] { LoadCropProfile(gone.string(), dir); })
                .find(gone.string() + ": segmenter.model: no model " + (dir / "models" / "no-such-model.onnx").string()),
            std::string::npos);
  const fs::path typo = Write("segtypo.yaml", std::string(kCrop) + "segmenter: {model: peanut, confidence: 0.7}\n");
  EXPECT_NE(ErrorOf([&] { LoadCropProfile(typo.string(), dir); }).find("segmenter.confidence: unknown key"),
            std::string::npos);
  // A model file whose card is missing: read as unreadable, not thrown.
  const fs::path bare = fs::temp_directory_path() / ("plantscale_profiles_" + std::to_string(::getpid()) + "_bare.onnx");
  std::ofstream(bare) << "not a graph";
  CropProfile b = c;
  b.segmenter_model = bare.string();
  const pipeline::LearnedOptions u = LearnedPipelineOptions(b);
  EXPECT_TRUE(u.enabled());
  EXPECT_FALSE(u.onnx);
  EXPECT_NE(u.unreadable.find("_bare.json"), std::string::npos) << u.unreadable;
  for (const fs::path& f : {named, gone, typo, bare}) fs::remove(f);
}

}  // namespace
}  // namespace plantscale::app
