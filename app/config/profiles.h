#pragma once
// Crop and vehicle profiles (issue 33): what a grower and a machine builder
// know, written in YAML (config/crops/*.yaml, config/vehicles/*.yaml), and
// the only source of the vehicle pipeline's options. The simulator keeps its
// own preset; nothing here reads a simulator parameter. docs/profiles.md
// describes every key.
//
// Every problem with a profile is a ConfigError naming the file, the key and
// the expected range (a missing key, a value out of range such as a spacing
// of 450 written for 0.45 m, a negative latency, a calibration file for
// another image size).

#include <cstdint>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "engine/geometry/camera_model.h"
#include "engine/pipeline/pipeline.h"
#include "engine/tracking/grid_tracker.h"
#include "engine/treatment/treatment_system.h"

namespace plantscale::app {

// A crop at a growth stage, as planted.
struct CropProfile {
  std::string name;  // file stem
  std::string file;
  int rows = 3;                         // rows per bed (odd: a central row)
  double row_spacing_m = 0.0;           // as the drill was set
  double row_spacing_sd_m = 0.0;        // how precisely it is known (sd; default kGrowerRowSpacingSdM)
  double plant_spacing_m = 0.0;         // as the planter was set
  double leaf_radius_m = 0.0;           // mean leaf-tip radius at the growth stage
  double leaf_radius_sd_fraction = 0.0; // plant-to-plant size spread (sd / mean)
  double leaf_height_m = 0.0;           // height of the leaf tips above the soil
  double planter_sd_m = 0.0;            // each plant's position about its grid place (sd, with lean)
  double virtual_plane_height_m = 0.0;  // the camera's virtual ground plane (thesis §2.3.8)
  // The grower's learned crop/weed model for this crop (`segmenter: {model:
  // FILE, min_confidence: C}`; learned_model.h): a resolved path, empty for
  // none. FILE is a name in config/models (`field-grey`) or a path relative
  // to the profile's folder.
  std::string segmenter_model;
  double segmenter_min_confidence = 0.6;  // ClassifierOptions::learned_min_confidence
};

// The spreads a grower seldom measures, when the crop profile leaves them
// out: a transplanter's plants within 2 cm of their place (lean included),
// sizes within 20 % of the mean. Generous on purpose: a filter that
// believes a tighter spread than the field has is overconfident.
inline constexpr double kGrowerPlanterSdM = 0.02;
inline constexpr double kGrowerLeafRadiusSdFraction = 0.2;
// A drill's row spacing is a machine setting: within 5 mm of what it was set
// to unless the profile says otherwise. The tracker's prior on r̄, and what
// its check of the bed against the profile allows (spacing_check.h).
inline constexpr double kGrowerRowSpacingSdM = 0.005;

// A vehicle: its wheels, camera, bar and suspension.
struct VehicleProfile {
  std::string name;
  std::string file;
  double track_width_m = 0.0;
  std::string calibration_file;        // resolved path of the camera calibration
  geometry::CameraOptions camera;      // as calibrated (virtual plane from the crop)
  double valve_latency_s = 0.0;
  treatment::SprayBarOptions bar;      // nozzle layout and latency
  // Camera bounce (suspension); an unknown vehicle's defaults when absent:
  // a slow vehicle on a tilled bed, generous rather than tight (a grower
  // seldom measures them).
  double pitch_sd_rad = 0.5 * 3.14159265358979323846 / 180.0;
  double roll_sd_rad = 0.3 * 3.14159265358979323846 / 180.0;
  double height_sd_m = 0.005;
  double bounce_correlation_s = 0.25;
  bool suspension_given = false;       // false: the defaults above
  // How far the camera's calibration may be off (sd): what a field
  // calibration leaves (1 cm, 0.5°, 0.3°, 1 %) unless the profile says.
  double calibration_tilt_sd_rad = 0.5 * 3.14159265358979323846 / 180.0;
  double calibration_roll_sd_rad = 0.3 * 3.14159265358979323846 / 180.0;
  double calibration_height_sd_m = 0.01;
  double calibration_focal_sd = 0.01;
};

struct Profiles {
  CropProfile crop;
  VehicleProfile vehicle;
};

// `name_or_path`: a name in config/crops (config/vehicles) or a YAML file.
CropProfile LoadCropProfile(const std::string& name_or_path,
                            const std::filesystem::path& config_dir);
VehicleProfile LoadVehicleProfile(const std::string& name_or_path,
                                  const std::filesystem::path& config_dir);

// The profiles a simulator preset's nominal crop and vehicle are written
// in, chosen by the preset's name (a table, not its parameters): field ->
// cauliflower-6-week on silsoe, ... Throws ConfigError for a preset without
// one (give --crop and --vehicle).
struct ProfileNames {
  std::string crop, vehicle;
};
ProfileNames DefaultProfileNames(const std::string& preset_name);
// --crop / --vehicle when given (non-empty), else the preset's defaults.
Profiles LoadProfiles(const std::string& crop, const std::string& vehicle,
                      const std::string& preset_name, const std::filesystem::path& config_dir);

// What the two profiles cannot do together, as sentences naming both
// files (empty: nothing). The bed is centred on the vehicle; a row whose
// line lies beyond the spray bar's end (its outer nozzle's covered edge)
// is never treated, and one whose line lies within two planter sd of it
// loses the plants planted off the line towards the end (more when the
// vehicle wanders across the bed). Neither is an error: a grower may treat
// only the central rows of a wide bed.
std::vector<std::string> ProfileWarnings(const Profiles& profiles);
// Each of them on `err` as "plantscale: warning: ...".
void PrintProfileWarnings(const Profiles& profiles, std::ostream& err);

// A calibration a field calibration leaves: the engine's camera is off from
// the true one. Given as standard deviations (`--calibration-error`), drawn
// per seed from a normal distribution (DrawnCalibrationError); the drawn
// values use the same type.
struct CalibrationError {
  double height_m = 0.0;
  double tilt_deg = 0.0;
  double roll_deg = 0.0;
  double focal = 0.0;  // fraction of the focal length
  bool any() const { return height_m != 0.0 || tilt_deg != 0.0 || roll_deg != 0.0 || focal != 0.0; }
};
// "height_m=0.01,tilt_deg=0.5,roll_deg=0.3,focal=0.01" (any subset; sds
// >= 0). Throws ConfigError naming `where` (the option) and the key.
CalibrationError ParseCalibrationError(const std::string& text, const std::string& where);
// The error of run `seed`: each parameter drawn from N(0, sd²) with a stream
// of its own derived from the seed (the same seed, the same error, on every
// platform). A fixed ±1 sd would flatter the consistency figures: a field
// calibration is sometimes off by two sd.
CalibrationError DrawnCalibrationError(const CalibrationError& sds, uint64_t seed);
geometry::CameraOptions ApplyCalibrationError(geometry::CameraOptions camera,
                                              const CalibrationError& signed_error);

// A calibration given for this run (`run --calibration FILE`) in place of
// the vehicle profile's own must be of the same camera: the same image
// size and a focal length in pixels within 20 % (a recalibration moves it
// by a few per cent; another lens or sensor by more). Throws ConfigError
// naming both files and both values.
void RequireSameCamera(const VehicleProfile& vehicle, const geometry::CameraOptions& calibration,
                       const std::string& calibration_file);

// The engine's camera: the vehicle's calibration with the crop's virtual
// ground plane.
geometry::CameraOptions EngineCamera(const Profiles& profiles);
// Throws ConfigError naming the vehicle file when its calibration is for
// another image size than the camera's images (width x height).
void RequireImageSize(const VehicleProfile& vehicle, int width_px, int height_px);

// The product's options, from the two profiles only.
tracking::TrackerOptions ProductTrackerOptions(const Profiles& profiles);
treatment::TreatmentOptions ProductTreatmentOptions(const Profiles& profiles);
// The camera's motion as the pipeline's second motion source
// (pipeline/motion_fusion.h), its features on the crop's leaf-tip plane;
// enabled.
pipeline::MotionFusionOptions VisualMotionOptions(const Profiles& p);
pipeline::PipelineOptions ProductPipelineOptions(const Profiles& profiles);
// The learned model the crop profile names, read from disk (none: disabled
// options). A model that cannot be read is not an error here: the options
// carry the reason (LearnedOptions::unreadable) and the pipeline runs on
// the grid's rule, saying so in every frame's faults.
pipeline::LearnedOptions LearnedPipelineOptions(const CropProfile& crop);
// `model`: a name in config/models or a path (relative to `base`); the
// resolved path. Throws ConfigError naming `file` and `key` when neither exists.
std::string ResolveModelPath(const std::string& model, const std::filesystem::path& base,
                             const std::filesystem::path& config_dir, const std::string& file,
                             const std::string& key);
// The thesis's tracker (§4.6, ch. 8) with its noise settings, on the same
// profiles (rows, nominal spacings, track width).
tracking::TrackerOptions ThesisTrackerOptions(const Profiles& profiles);

}  // namespace plantscale::app
