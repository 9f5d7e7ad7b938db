#include "app/config/config_loader.h"

#include <gtest/gtest.h>

#include <fstream>
#include <numbers>

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;

// A config folder in a temporary directory with a camera and presets.
class ConfigLoaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("plantscale_config_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "cameras");
    fs::create_directories(dir_ / "presets");
    Write("cameras/cam.yaml", "height_m: 1.5\ntilt_deg: 45\nfocal_length_m: 0.0048\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  std::string ErrorOf(const std::string& preset) {
    try {
      LoadSimulatorPreset(preset, dir_);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(ConfigLoaderTest, LoadsCameraByNameWithOverridesAndDegrees) {
  Write("presets/p.yaml",
        "camera: cam\ncamera_overrides: {virtual_plane_height_m: 0.1}\n"
        "field: {rows: 5, weed_density_per_m2: 2.5}\nvehicle: {start_heading_deg: 2}\n"
        "length_m: 12\nseed: 9\n");
  const sim::SimulatorOptions o = LoadSimulatorPreset("p", dir_);
  EXPECT_EQ(o.preset, "p");
  EXPECT_DOUBLE_EQ(o.camera.height_m, 1.5);
  EXPECT_NEAR(o.camera.tilt_rad, std::numbers::pi / 4.0, 1e-12);
  EXPECT_DOUBLE_EQ(o.camera.virtual_plane_height_m, 0.1);
  EXPECT_EQ(o.field.rows, 5);
  EXPECT_DOUBLE_EQ(o.field.weed_density_per_m2, 2.5);
  EXPECT_NEAR(o.vehicle.start_heading_rad, 2.0 * std::numbers::pi / 180.0, 1e-12);
  EXPECT_DOUBLE_EQ(o.length_m, 12.0);
  EXPECT_EQ(o.seed, 9U);
}

TEST_F(ConfigLoaderTest, UnknownPresetListsTheKnownOnes) {
  Write("presets/alpha.yaml", "length_m: 5\n");
  const std::string error = ErrorOf("nope");
  EXPECT_NE(error.find("nope"), std::string::npos) << error;
  EXPECT_NE(error.find("unknown preset"), std::string::npos) << error;
  EXPECT_NE(error.find("alpha"), std::string::npos) << error;
}

// Found by tests/fuzz/config_fuzz: a camera name longer than a file name
// made std::filesystem::exists throw filesystem_error (exit 1, "filesystem
// error") instead of the unknown-camera ConfigError.
TEST_F(ConfigLoaderTest, OverlongCameraNameIsAnUnknownCamera) {
  Write("presets/long.yaml", "camera: " + std::string(300, 'c') + "\n");
  const std::string error = ErrorOf("long");
  EXPECT_NE(error.find("unknown camera"), std::string::npos) << error;
}

// Found by tests/fuzz/config_fuzz: a key that is not a scalar threw
// YAML::TypedBadConversion out of the loader.
TEST_F(ConfigLoaderTest, KeyThatIsNotANameIsAConfigError) {
  Write("presets/complex.yaml", "length_m: 5\n? [a, b]\n: 1\n");
  EXPECT_NE(ErrorOf("complex").find("a key that is not a name (line 2)"), std::string::npos)
      << ErrorOf("complex");
  Write("presets/null.yaml", "field:\n  ? \n  : 1\n");
  EXPECT_NE(ErrorOf("null").find("field: a key that is not a name"), std::string::npos)
      << ErrorOf("null");
}

TEST_F(ConfigLoaderTest, MalformedYamlNamesFileAndLine) {
  Write("presets/bad.yaml", "field:\n  rows: [3\nlength_m: 4\n");
  const std::string error = ErrorOf("bad");
  EXPECT_NE(error.find("bad.yaml"), std::string::npos) << error;
  EXPECT_NE(error.find("malformed YAML at line"), std::string::npos) << error;
}

TEST_F(ConfigLoaderTest, UnknownKeyIsAnErrorWithItsLine) {
  Write("presets/typo.yaml", "field:\n  rows: 3\n  weed_densty: 4\n");
  const std::string error = ErrorOf("typo");
  EXPECT_NE(error.find("field.weed_densty: unknown key (line 3)"), std::string::npos) << error;
}

TEST_F(ConfigLoaderTest, WrongTypeNamesKeyAndValue) {
  Write("presets/type.yaml", "vehicle: {speed_m_s: fast}\n");
  const std::string error = ErrorOf("type");
  EXPECT_NE(error.find("vehicle.speed_m_s: expected a number, got 'fast'"), std::string::npos)
      << error;
}

TEST_F(ConfigLoaderTest, InvalidValuesNameFileKeyAndReason) {
  Write("presets/neg.yaml", "camera: {height_m: -1.5}\n");
  std::string error = ErrorOf("neg");
  EXPECT_NE(error.find("neg.yaml: camera.height_m: must be > 0 (got -1.5)"), std::string::npos)
      << error;
  Write("cameras/steep.yaml", "tilt_deg: 95\n");
  Write("presets/steep.yaml", "camera: steep\n");
  error = ErrorOf("steep");
  EXPECT_NE(error.find("steep.yaml: tilt_rad: must be in (0, 1.5708]"), std::string::npos) << error;
  Write("presets/zero.yaml", "camera: {image_width_px: 0}\n");
  error = ErrorOf("zero");
  EXPECT_NE(error.find("camera.image_width_px: must be > 0"), std::string::npos) << error;
}

TEST_F(ConfigLoaderTest, UnreadableFileIsReported) {
  const std::string error = [&] {
    try {
      LoadSimulatorPreset((dir_ / "presets" / "missing.yaml").string(), dir_);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  }();
  EXPECT_NE(error.find("missing.yaml: (file): cannot be read"), std::string::npos) << error;
}

TEST_F(ConfigLoaderTest, CalibrationReplacesThePresetsCameraKeepingTheCropsPlane) {
  Write("cameras/calib.yaml",
        "height_m: 1.2\ntilt_deg: 60\nfocal_length_m: 0.006\n"
        "virtual_plane_height_m: 0.0\n");
  Write("presets/p.yaml",
        "camera: cam\ncamera_overrides: {virtual_plane_height_m: 0.1}\nfield: {rows: 5}\n");
  const sim::SimulatorOptions o =
      LoadSimulatorPresetWithCalibration("p", (dir_ / "cameras" / "calib.yaml").string(), dir_);
  EXPECT_DOUBLE_EQ(o.camera.height_m, 1.2);
  EXPECT_NEAR(o.camera.tilt_rad, std::numbers::pi / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(o.camera.focal_length_m, 0.006);
  EXPECT_DOUBLE_EQ(o.camera.virtual_plane_height_m, 0.1);  // the crop's height: the preset's
  EXPECT_EQ(o.field.rows, 5);
}

TEST_F(ConfigLoaderTest, CalibrationErrorsNameTheCalibrationOrTheOverride) {
  Write("presets/p.yaml", "camera: cam\ncamera_overrides: {height_m: 1.4}\n");
  const auto error_of = [&](const std::string& preset, const std::string& calibration) {
    try {
      LoadSimulatorPresetWithCalibration(preset, calibration, dir_);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string error = error_of("p", "cam");
  EXPECT_NE(error.find("p.yaml: camera_overrides.height_m: would change the calibration"),
            std::string::npos)
      << error;
  Write("presets/q.yaml", "camera: cam\n");
  Write("cameras/bad.yaml", "height_m: [1\n");
  error = error_of("q", (dir_ / "cameras" / "bad.yaml").string());
  EXPECT_NE(error.find("bad.yaml: (file): malformed YAML at line"), std::string::npos) << error;
  Write("cameras/typo.yaml", "height_m: 1.5\nfocal_length: 0.004\n");
  error = error_of("q", (dir_ / "cameras" / "typo.yaml").string());
  EXPECT_NE(error.find("typo.yaml: focal_length: unknown key (line 2)"), std::string::npos)
      << error;
  error = error_of("q", (dir_ / "absent.yaml").string());
  EXPECT_NE(error.find("absent.yaml: (file): cannot be read"), std::string::npos) << error;
  error = error_of("q", "nosuchcamera");
  EXPECT_NE(error.find("nosuchcamera: unknown camera"), std::string::npos) << error;
}

TEST(ShippedPresets, EveryPresetAndCameraLoadsAndValidates) {
  const fs::path dir = DefaultConfigDir();
  int presets = 0;
  for (const auto& entry : fs::directory_iterator(dir / "presets")) {
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(LoadSimulatorPreset(entry.path().stem().string(), dir));
    ++presets;
  }
  for (const char* name : {"A", "B", "C", "D", "testbed", "field", "treatment", "long"}) {
    EXPECT_TRUE(fs::exists(dir / "presets" / (std::string(name) + ".yaml"))) << name;
  }
  EXPECT_GE(presets, 8);
  EXPECT_GE(LoadSimulatorPreset("long", dir).length_m, 100.0);
  for (const char* camera : {"thesis", "sanchiz_pla_66", "sanchiz_pla_90"}) {
    EXPECT_NO_THROW(LoadCamera(camera, dir)) << camera;
  }
  const geometry::CameraOptions sp = LoadCamera("sanchiz_pla_90", dir);
  EXPECT_DOUBLE_EQ(sp.height_m, 1.77);
  EXPECT_NEAR(sp.tilt_rad, std::numbers::pi / 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(sp.focal_length_m, 0.028);
}

}  // namespace
}  // namespace plantscale::app
