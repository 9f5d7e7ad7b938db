#include "app/config/profiles.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/config/config_loader.h"
#include "app/config/learned_model.h"
#include "engine/common/rng.h"

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

YAML::Node ParseProfile(const fs::path& file) {
  std::ifstream in(file);
  if (!in) {
    throw ConfigError(file.string(), "(file)",
                      "cannot be read: " + std::string(std::strerror(errno)));
  }
  try {
    YAML::Node root = YAML::Load(in);
    if (!root || root.IsNull()) throw ConfigError(file.string(), "(file)", "is empty");
    if (!root.IsMap()) throw ConfigError(file.string(), "(top level)", "expected a mapping");
    return root;
  } catch (const YAML::ParserException& e) {
    throw ConfigError(file.string(), "(file)",
                      "malformed YAML at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

// Keys of one mapping read one by one: every value is required unless read
// with a default, in its range, and unknown keys are errors.
class Keys {
 public:
  Keys(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {
    if (!node_.IsMap()) throw ConfigError(file_, path_.empty() ? "(top level)" : path_, "expected a mapping");
  }
  std::string Key(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  bool Has(const std::string& key) const { return static_cast<bool>(node_[key]); }
  YAML::Node Node(const std::string& key) {
    used_.insert(key);
    return node_[key];
  }
  // A number in [low, high] with its unit; required.
  double Number(const std::string& key, double low, double high, const char* unit) {
    const std::string range = "expected " + app::Number(low) + " to " + app::Number(high) +
                              (unit[0] ? std::string(" ") + unit : std::string());
    if (!Has(key)) throw ConfigError(file_, Key(key), "missing (" + range + ")");
    const YAML::Node n = Node(key);
    const std::string line = " (line " + std::to_string(n.Mark().line + 1) + ")";
    double v = 0.0;
    try {
      if (!n.IsScalar()) throw YAML::BadConversion(n.Mark());
      v = n.as<double>();
    } catch (const YAML::BadConversion&) {
      throw ConfigError(file_, Key(key), "expected a number, " + range + line);
    }
    if (!std::isfinite(v) || v < low || v > high) {
      throw ConfigError(file_, Key(key), "is " + app::Number(v) + ", " + range + line);
    }
    return v;
  }
  double Number(const std::string& key, double low, double high, const char* unit,
                double default_value) {
    return Has(key) ? Number(key, low, high, unit) : default_value;
  }
  std::string String(const std::string& key) {
    if (!Has(key)) throw ConfigError(file_, Key(key), "missing");
    const YAML::Node n = Node(key);
    if (!n.IsScalar()) throw ConfigError(file_, Key(key), "expected a single value");
    return n.Scalar();
  }
  void Finish() const {
    for (const auto& item : node_) {
      const std::string key = item.first.IsScalar() ? item.first.Scalar() : "(not a name)";
      if (used_.count(key) == 0) {
        throw ConfigError(file_, Key(key),
                          "unknown key (line " + std::to_string(item.first.Mark().line + 1) + ")");
      }
    }
  }

 private:
  YAML::Node node_;
  std::string file_;
  std::string path_;
  std::set<std::string> used_;
};

}  // namespace

CropProfile LoadCropProfile(const std::string& name_or_path, const fs::path& config_dir) {
  const fs::path file = ResolveConfigFile(name_or_path, config_dir / "crops", "crop profile");
  Keys k(ParseProfile(file), file.string(), "");
  CropProfile c;
  c.name = file.stem().string();
  c.file = file.string();
  if (k.Has("description")) k.Node("description");
  const double rows = k.Number("rows", 1, 15, "rows");
  if (rows != std::floor(rows) || static_cast<int>(rows) % 2 == 0) {
    throw ConfigError(c.file, "rows", "is " + Number(rows) + ", expected an odd whole number 1 to 15");
  }
  c.rows = static_cast<int>(rows);
  c.row_spacing_m = k.Number("row_spacing_m", 0.1, 2.0, "m");
  c.row_spacing_sd_m = k.Number("row_spacing_sd_m", 0.0005, 0.1, "m", kGrowerRowSpacingSdM);
  c.plant_spacing_m = k.Number("plant_spacing_m", 0.02, 2.0, "m");
  c.leaf_radius_m = k.Number("leaf_radius_m", 0.005, 0.5, "m");
  c.leaf_radius_sd_fraction =
      k.Number("leaf_radius_sd_fraction", 0.0, 0.5, "", kGrowerLeafRadiusSdFraction);
  c.leaf_height_m = k.Number("leaf_height_m", 0.0, 1.0, "m");
  c.planter_sd_m = k.Number("planter_sd_m", 0.0, 0.1, "m", kGrowerPlanterSdM);
  c.virtual_plane_height_m =
      k.Number("virtual_plane_height_m", 0.0, 1.0, "m", 0.9 * c.leaf_height_m);
  if (k.Has("segmenter")) {
    Keys m(k.Node("segmenter"), c.file, "segmenter");
    c.segmenter_model = ResolveModelPath(m.String("model"), file.parent_path(), config_dir, c.file,
                                         "segmenter.model");
    c.segmenter_min_confidence = m.Number("min_confidence", 0.0, 2.0, "", c.segmenter_min_confidence);
    m.Finish();
  }
  k.Finish();
  return c;
}

VehicleProfile LoadVehicleProfile(const std::string& name_or_path, const fs::path& config_dir) {
  const fs::path file = ResolveConfigFile(name_or_path, config_dir / "vehicles", "vehicle profile");
  Keys k(ParseProfile(file), file.string(), "");
  VehicleProfile v;
  v.name = file.stem().string();
  v.file = file.string();
  if (k.Has("description")) k.Node("description");
  v.track_width_m = k.Number("track_width_m", 0.5, 5.0, "m");
  if (!k.Has("camera")) throw ConfigError(v.file, "camera", "missing (calibration, image_width_px, image_height_px)");
  {
    Keys c(k.Node("camera"), v.file, "camera");
    const std::string calibration = c.String("calibration");
    const int width = static_cast<int>(c.Number("image_width_px", 16, 20000, "px"));
    const int height = static_cast<int>(c.Number("image_height_px", 16, 20000, "px"));
    c.Finish();
    // A name is a camera in config/cameras; a relative path is relative to
    // the profile's folder.
    fs::path cal(calibration);
    const bool is_path = cal.extension() == ".yaml" || cal.extension() == ".yml" ||
                         calibration.find('/') != std::string::npos;
    if (is_path && cal.is_relative()) cal = file.parent_path() / cal;
    const fs::path resolved =
        is_path ? cal : ResolveConfigFile(calibration, config_dir / "cameras", "camera");
    v.calibration_file = resolved.string();
    try {
      v.camera = LoadCamera(resolved.string(), config_dir);
    } catch (const ConfigError& e) {
      throw ConfigError(v.file, "camera.calibration", e.what());
    }
    if (v.camera.image_width_px != width || v.camera.image_height_px != height) {
      throw ConfigError(v.file, "camera.calibration",
                        v.calibration_file + " is for " + std::to_string(v.camera.image_width_px) +
                            "x" + std::to_string(v.camera.image_height_px) +
                            " px images, expected " + std::to_string(width) + "x" +
                            std::to_string(height) + " px (camera.image_width_px x image_height_px)");
    }
  }
  v.valve_latency_s = k.Number("valve_latency_s", 0.0, 0.5, "s");
  v.bar.valve_latency_s = v.valve_latency_s;
  if (!k.Has("nozzles")) throw ConfigError(v.file, "nozzles", "missing (count, spacing_m, bar_offset_m)");
  {
    Keys n(k.Node("nozzles"), v.file, "nozzles");
    const double count = n.Number("count", 1, 64, "nozzles");
    if (count != std::floor(count)) throw ConfigError(v.file, "nozzles.count", "expected a whole number 1 to 64");
    v.bar.nozzles = static_cast<int>(count);
    v.bar.nozzle_spacing_m = n.Number("spacing_m", 0.005, 0.5, "m");
    v.bar.bar_offset_m = n.Number("bar_offset_m", 0.0, 5.0, "m behind the camera's ground point");
    v.bar.centre_x_m = n.Number("centre_x_m", -2.0, 2.0, "m", 0.0);
    n.Finish();
  }
  if (k.Has("suspension")) {
    Keys s(k.Node("suspension"), v.file, "suspension");
    v.pitch_sd_rad = s.Number("pitch_sd_deg", 0.0, 5.0, "deg") * kDeg;
    v.roll_sd_rad = s.Number("roll_sd_deg", 0.0, 5.0, "deg") * kDeg;
    v.height_sd_m = s.Number("height_sd_m", 0.0, 0.05, "m");
    v.bounce_correlation_s = s.Number("correlation_s", 0.0, 10.0, "s");
    s.Finish();
    v.suspension_given = true;
  }
  if (k.Has("calibration_sd")) {
    Keys c(k.Node("calibration_sd"), v.file, "calibration_sd");
    v.calibration_tilt_sd_rad = c.Number("tilt_deg", 0.0, 5.0, "deg") * kDeg;
    v.calibration_roll_sd_rad = c.Number("roll_deg", 0.0, 5.0, "deg") * kDeg;
    v.calibration_height_sd_m = c.Number("height_m", 0.0, 0.1, "m");
    v.calibration_focal_sd = c.Number("focal", 0.0, 0.1, "(fraction of the focal length)");
    c.Finish();
  }
  k.Finish();
  const OptionErrors bar_errors = v.bar.Validate();
  if (!bar_errors.empty()) throw ConfigError(v.file, "nozzles." + bar_errors[0].key, bar_errors[0].reason);
  return v;
}

ProfileNames DefaultProfileNames(const std::string& preset) {
  static const std::map<std::string, ProfileNames> kTable = {
      {"A", {"cauliflower-8-week", "silsoe"}},
      {"B", {"cauliflower-3-week", "silsoe"}},
      {"C", {"cauliflower-6-week", "silsoe"}},
      {"D", {"cauliflower-3-week", "silsoe"}},
      {"field", {"cauliflower-6-week", "silsoe"}},
      {"long", {"cauliflower-6-week", "silsoe"}},
      {"treatment", {"cauliflower-9-week", "silsoe"}},
      {"testbed", {"testbed-plants", "silsoe-testbed"}},
      {"sanchiz_pla", {"lettuce", "sanchiz-pla-66"}},
      {"lettuce-fast", {"lettuce", "silsoe"}},
      {"cabbage-wide", {"cabbage-wide", "silsoe"}},
  };
  const auto it = kTable.find(preset);
  if (it == kTable.end()) {
    throw ConfigError("command line", "--crop/--vehicle",
                      "preset '" + preset + "' has no default crop and vehicle profile: give both");
  }
  return it->second;
}

Profiles LoadProfiles(const std::string& crop, const std::string& vehicle,
                      const std::string& preset_name, const fs::path& config_dir) {
  Profiles p;
  if (crop.empty() || vehicle.empty()) {
    const ProfileNames names = DefaultProfileNames(preset_name);
    p.crop = LoadCropProfile(crop.empty() ? names.crop : crop, config_dir);
    p.vehicle = LoadVehicleProfile(vehicle.empty() ? names.vehicle : vehicle, config_dir);
  } else {
    p.crop = LoadCropProfile(crop, config_dir);
    p.vehicle = LoadVehicleProfile(vehicle, config_dir);
  }
  return p;
}

std::vector<std::string> ProfileWarnings(const Profiles& p) {
  const CropProfile& c = p.crop;
  const treatment::SprayBarOptions& bar = p.vehicle.bar;
  const double half = 0.5 * bar.nozzles * bar.nozzle_spacing_m;
  const double margin = 2.0 * c.planter_sd_m;
  const auto cm = [](double m, bool sign = false) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(1) << (sign ? std::showpos : std::noshowpos) << m * 100.0 << " cm";
    return o.str();
  };
  const auto mm = [](double m) {
    std::ostringstream o;
    o << std::setprecision(3) << m * 1000.0 << " mm";
    return o.str();
  };
  std::vector<int> beyond, near_end;
  for (int i = 0; i < c.rows; ++i) {
    const int n = i - (c.rows - 1) / 2;  // 0: the central row
    const double x = n * c.row_spacing_m;
    const double past_end = std::max(x - (bar.centre_x_m + half), (bar.centre_x_m - half) - x);
    if (past_end > 0.0) {
      beyond.push_back(n);
    } else if (past_end + margin > 0.0) {
      near_end.push_back(n);
    }
  }
  const auto names = [&](const std::vector<int>& rows) {
    std::ostringstream o;
    for (size_t i = 0; i < rows.size(); ++i) {
      o << (i == 0 ? "" : i + 1 == rows.size() ? " and " : ", ") << cm(rows[i] * c.row_spacing_m, true);
    }
    return o.str();
  };
  const std::string bar_text = "the spray bar of " + p.vehicle.file + " (" + std::to_string(bar.nozzles) +
                               " nozzles of " + mm(bar.nozzle_spacing_m) + ", from " +
                               cm(bar.centre_x_m - half) + " to " + cm(bar.centre_x_m + half) +
                               " across the vehicle)";
  // "FILE: the rows at A and B", and the verb's ending for them.
  const auto subject = [&](const std::vector<int>& rows) {
    return c.file + ": the row" + (rows.size() > 1 ? "s at " : " at ") + names(rows);
  };
  const auto verb_s = [](const std::vector<int>& rows) { return std::string(rows.size() > 1 ? "" : "s"); };
  std::vector<std::string> out;
  if (!beyond.empty()) {
    out.push_back(subject(beyond) + " of the " + std::to_string(c.rows) + "-row bed lie" + verb_s(beyond) +
                  " beyond " + bar_text + ": " + (beyond.size() > 1 ? "their" : "its") +
                  " plants will not be treated");
  }
  if (!near_end.empty()) {
    out.push_back(subject(near_end) + " stand" + verb_s(near_end) + " within two planter sd (" + cm(margin) +
                  ") of the end of " + bar_text +
                  ": plants off the line towards the end, or the vehicle wandering, will be missed");
  }
  return out;
}

void PrintProfileWarnings(const Profiles& profiles, std::ostream& err) {
  for (const std::string& w : ProfileWarnings(profiles)) err << "plantscale: warning: " << w << '\n';
}

CalibrationError ParseCalibrationError(const std::string& text, const std::string& where) {
  CalibrationError e;
  if (text.empty()) return e;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) {
      throw ConfigError(where, item, "expected key=value (height_m, tilt_deg, roll_deg, focal)");
    }
    const std::string key = item.substr(0, eq);
    const std::string value = item.substr(eq + 1);
    double v = 0.0;
    try {
      size_t used = 0;
      v = std::stod(value, &used);
      if (used != value.size()) throw std::invalid_argument(value);
    } catch (const std::exception&) {
      throw ConfigError(where, key, "expected a number, got '" + value + "'");
    }
    const auto check = [&](double high, const char* unit) {
      if (!std::isfinite(v) || v < 0.0 || v > high) {
        throw ConfigError(where, key,
                          "is " + value + ", expected 0 to " + Number(high) + " " + unit +
                              " (a standard deviation: the error is drawn per seed)");
      }
      return v;
    };
    if (key == "height_m") {
      e.height_m = check(0.2, "m");
    } else if (key == "tilt_deg") {
      e.tilt_deg = check(10.0, "deg");
    } else if (key == "roll_deg") {
      e.roll_deg = check(10.0, "deg");
    } else if (key == "focal") {
      e.focal = check(0.2, "(fraction of the focal length)");
    } else {
      throw ConfigError(where, key, "unknown key (height_m, tilt_deg, roll_deg, focal)");
    }
  }
  return e;
}

CalibrationError DrawnCalibrationError(const CalibrationError& sds, uint64_t seed) {
  // The stream label spells "calib" so no other seeded draw shares it.
  Rng rng = Rng::Derived(seed, 0x63616C6962ULL);
  CalibrationError e;
  e.height_m = rng.Normal(0.0, sds.height_m);
  e.tilt_deg = rng.Normal(0.0, sds.tilt_deg);
  e.roll_deg = rng.Normal(0.0, sds.roll_deg);
  e.focal = rng.Normal(0.0, sds.focal);
  return e;
}

geometry::CameraOptions ApplyCalibrationError(geometry::CameraOptions c, const CalibrationError& e) {
  c.height_m += e.height_m;
  c.tilt_rad += e.tilt_deg * kDeg;
  c.roll_rad += e.roll_deg * kDeg;
  c.focal_length_m *= 1.0 + e.focal;
  return c;
}

void RequireSameCamera(const VehicleProfile& v, const geometry::CameraOptions& c,
                       const std::string& file) {
  const geometry::CameraOptions& own = v.camera;
  const auto size = [](const geometry::CameraOptions& o) {
    return std::to_string(o.image_width_px) + "x" + std::to_string(o.image_height_px) + " px";
  };
  if (own.image_width_px != c.image_width_px || own.image_height_px != c.image_height_px) {
    throw ConfigError(file, "image size",
                      "is " + size(c) + ", the camera of " + v.file + " (" + v.calibration_file +
                          ") takes " + size(own) + ": a calibration of another camera");
  }
  const double f_own = own.focal_length_m / own.pixel_width_m;
  const double f_new = c.focal_length_m / c.pixel_width_m;
  if (std::abs(f_new / f_own - 1.0) > 0.2) {
    std::ostringstream why;
    why << "focal length " << std::fixed << std::setprecision(0) << f_new << " px, the camera of "
        << v.file << " (" << v.calibration_file << ") " << f_own
        << " px: more than 20 % apart, a calibration of another camera";
    throw ConfigError(file, "focal_length_m", why.str());
  }
}

geometry::CameraOptions EngineCamera(const Profiles& p) {
  geometry::CameraOptions c = p.vehicle.camera;
  c.virtual_plane_height_m = p.crop.virtual_plane_height_m;
  return c;
}

void RequireImageSize(const VehicleProfile& v, int width_px, int height_px) {
  if (v.camera.image_width_px == width_px && v.camera.image_height_px == height_px) return;
  throw ConfigError(v.file, "camera.calibration",
                    v.calibration_file + " is for " + std::to_string(v.camera.image_width_px) + "x" +
                        std::to_string(v.camera.image_height_px) + " px images, the camera's are " +
                        std::to_string(width_px) + "x" + std::to_string(height_px) + " px");
}

tracking::TrackerOptions ProductTrackerOptions(const Profiles& p) {
  const CropProfile& c = p.crop;
  const VehicleProfile& v = p.vehicle;
  tracking::TrackerOptions o;
  o.rows_each_side = (c.rows - 1) / 2;
  o.row_spacing_m = c.row_spacing_m;
  o.plant_spacing_m = c.plant_spacing_m;
  // How precisely the drill's spacing is known: the prior on r̄, and what
  // the check of the bed against the profile allows.
  o.row_spacing_sd_m = c.row_spacing_sd_m;
  // A camera off its calibration by the vehicle's calibration_sd scales
  // the rows' spacing as the camera sees it: at the centre of the view a
  // height error by δH/(H − h), a tilt error by δθ/tan θ (θ below the
  // horizontal), a focal error by its fraction. The check of the spacing
  // against the profile allows that (spacing_check.h).
  {
    const geometry::CameraOptions& cam = v.camera;
    const double above = std::max(0.1, cam.height_m - c.virtual_plane_height_m);
    const double h = v.calibration_height_sd_m / above;
    const double t = v.calibration_tilt_sd_rad / std::tan(cam.tilt_rad);
    o.spacing_check_scale_sd = std::min(0.5, std::sqrt(h * h + t * t + std::pow(v.calibration_focal_sd, 2)));
  }
  o.track_width_m = v.track_width_m;
  // The crop as a grower knows it: mean leaf-tip radius and height, how
  // much plants vary in size (their centroid heights scale with them), and
  // how precisely the planter places them (with their lean).
  o.crop_radius_m = c.leaf_radius_m;
  o.crop_height_m = c.leaf_height_m;
  o.plant_height_sd_m = std::max(0.002, c.leaf_radius_sd_fraction * o.crop_height_m);
  o.plant_offset_sd_m = std::max(0.002, c.planter_sd_m);
  // A centroid's wander as the view changes is the parallax of the plant's
  // leaves: it scales with the crop's height from where it was measured.
  const double wander = o.crop_height_m / tracking::TrackerOptions::kOffsetWalkCropHeightM;
  o.plant_offset_walk_across_sd_per_sqrt_m *= wander;
  o.plant_offset_walk_along_sd_per_sqrt_m *= wander;
  // The vehicle's camera bounce as its suspension was measured (or an
  // unknown vehicle's defaults): size and how long it lasts.
  o.camera_pitch_sd_rad = std::max(1e-4, v.pitch_sd_rad);
  o.camera_roll_sd_rad = std::max(1e-4, v.roll_sd_rad);
  o.camera_height_sd_m = std::max(1e-4, v.height_sd_m);
  o.camera_bounce_correlation_s = v.bounce_correlation_s;
  // And how well its camera's roll was calibrated: a calibration state,
  // estimated. Tilt, height and focal are not carried: estimated, they cost
  // placement along the rows; as consider states
  // (TrackerOptions::calibration_scale_consider) they make the NEES honest
  // but lost the grid's lateral on some lettuce-fast runs
  // (docs/results/2026-11-27-calibration.md).
  o.calibration_roll_sd_rad = v.calibration_roll_sd_rad;
  return o;
}

treatment::TreatmentOptions ProductTreatmentOptions(const Profiles& p) {
  treatment::TreatmentOptions o;
  o.scheduler.bar = p.vehicle.bar;
  // A record far smaller than the crops in a crop's place is a weed in a
  // gap: how much smaller the crop's own spread of sizes says.
  o.registry.crop_size_sd_fraction = p.crop.leaf_radius_sd_fraction;
  // Plant sizes are measured at the leaf tips, where the outline is.
  o.outline_height_m = p.crop.leaf_height_m;
  o.classifier.learned_min_confidence = p.crop.segmenter_min_confidence;
  return o;
}

std::string ResolveModelPath(const std::string& model, const fs::path& base,
                             const fs::path& config_dir, const std::string& file,
                             const std::string& key) {
  fs::path path(model);
  const bool is_path = path.extension() == ".onnx" || model.find('/') != std::string::npos;
  if (!is_path) path = config_dir / "models" / (model + ".onnx");
  else if (path.is_relative() && !base.empty()) path = base / path;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw ConfigError(file, key,
                      "no model " + path.string() +
                          (is_path ? "" : " (a name is a model in config/models; a path ends in .onnx)"));
  }
  return path.string();
}

pipeline::LearnedOptions LearnedPipelineOptions(const CropProfile& crop) {
  pipeline::LearnedOptions o;
  if (crop.segmenter_model.empty()) return o;
  o.source = crop.segmenter_model;
  try {
    LearnedModel m = ReadLearnedModel(crop.segmenter_model);
    o.spec = m.spec;
    o.onnx = std::make_shared<const std::vector<uint8_t>>(std::move(m.onnx));
  } catch (const std::exception& e) {
    o.unreadable = e.what();
  }
  return o;
}

pipeline::PipelineOptions ProductPipelineOptions(const Profiles& p) {
  pipeline::PipelineOptions o;
  o.learned = LearnedPipelineOptions(p.crop);
  o.treatment = ProductTreatmentOptions(p);
  o.segmenter = treatment::SegmenterOptionsFor(o.treatment.scheduler.mode);
  o.tracker = ProductTrackerOptions(p);
  return o;
}

pipeline::MotionFusionOptions VisualMotionOptions(const Profiles& p) {
  pipeline::MotionFusionOptions o;
  o.enabled = true;
  o.visual = motion::VisualOdometryFor(p.crop.leaf_radius_m, p.crop.leaf_height_m);
  o.wheel_sd_fraction = ProductTrackerOptions(p).wheel_sd_fraction;
  return o;
}

tracking::TrackerOptions ThesisTrackerOptions(const Profiles& p) {
  tracking::TrackerOptions o;
  o.estimate_spacing = false;
  o.estimate_odometry_scale = false;
  o.slip_guard.enabled = false;
  o.plant_offsets = false;
  o.model_bounce = false;
  o.skip_merged_features = false;  // every feature in the gate (§6.2)
  o.space = tracking::ObservationSpace::kImage;
  o.rows_each_side = (p.crop.rows - 1) / 2;
  o.row_spacing_m = p.crop.row_spacing_m;
  o.plant_spacing_m = p.crop.plant_spacing_m;
  o.track_width_m = p.vehicle.track_width_m;
  o.feature_sd_m = 0.01;
  o.pixel_sd_px = 0.0;
  o.forward_sd_per_sqrt_m = 0.0;
  o.lateral_sd_per_sqrt_m = 0.0;
  o.bearing_sd_per_sqrt_m = 0.0;
  o.frame_offset_sd_m = 0.002;
  o.frame_forward_sd_m = 0.004;
  o.frame_bearing_sd_rad = 0.002;
  o.edge_margin_px = 0.0;
  return o;
}

}  // namespace plantscale::app
