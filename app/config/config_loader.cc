#include "app/config/config_loader.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>
#include <vector>

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

std::string Join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

// A YAML mapping whose keys are read one by one; Finish() rejects the rest.
class MapReader {
 public:
  MapReader(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {
    if (!node_.IsMap())
      throw ConfigError(file_, path_.empty() ? "(top level)" : path_, "expected a mapping");
  }

  bool Has(const std::string& key) const { return static_cast<bool>(node_[key]); }
  YAML::Node Node(const std::string& key) {
    used_.insert(key);
    return node_[key];
  }

  template <typename T>
  void Get(const std::string& key, T& out) {
    const YAML::Node n = Node(key);
    if (!n) return;
    out = As<T>(n, key);
  }
  void Get(const std::string& key, std::optional<double>& out) {
    const YAML::Node n = Node(key);
    if (n) out = As<double>(n, key);
  }
  // `stem_rad` or `stem_deg`.
  void Angle(const std::string& stem, double& out_rad) {
    const std::string rad = stem + "_rad";
    const std::string deg = stem + "_deg";
    if (Has(rad) && Has(deg))
      throw ConfigError(file_, Join(path_, stem), "give _rad or _deg, not both");
    Get(rad, out_rad);
    if (Has(deg)) out_rad = As<double>(Node(deg), deg) * std::numbers::pi / 180.0;
  }
  void Finish() const {
    for (const auto& item : node_) {
      if (!item.first.IsScalar()) {  // `? [a, b]: 1` or a null key (found by fuzzing)
        throw ConfigError(file_, path_.empty() ? "(top level)" : path_,
                          "a key that is not a name (line " +
                              std::to_string(item.first.Mark().line + 1) + ")");
      }
      const std::string& key = item.first.Scalar();
      if (used_.count(key) == 0) {
        throw ConfigError(file_, Join(path_, key),
                          "unknown key (line " + std::to_string(item.first.Mark().line + 1) + ")");
      }
    }
  }
  const std::string& file() const { return file_; }

 private:
  template <typename T>
  T As(const YAML::Node& n, const std::string& key) const {
    const std::string where = Join(path_, key);
    const std::string line = " (line " + std::to_string(n.Mark().line + 1) + ")";
    if (!n.IsScalar()) throw ConfigError(file_, where, "expected a single value" + line);
    try {
      T value = n.as<T>();
      if constexpr (std::is_floating_point_v<T>) {
        if (!std::isfinite(value))
          throw ConfigError(file_, where, "must be a finite number" + line);
      }
      return value;
    } catch (const YAML::BadConversion&) {
      const char* type = std::is_same_v<T, bool>       ? "true or false"
                         : std::is_integral_v<T>       ? "an integer"
                         : std::is_floating_point_v<T> ? "a number"
                                                       : "a string";
      throw ConfigError(file_, where,
                        std::string("expected ") + type + ", got '" + n.Scalar() + "'" + line);
    }
  }

  YAML::Node node_;
  std::string file_;
  std::string path_;
  std::set<std::string> used_;
};

YAML::Node ParseFile(const fs::path& file) {
  std::ifstream in(file);
  if (!in)
    throw ConfigError(file.string(), "(file)",
                      "cannot be read: " + std::string(std::strerror(errno)));
  try {
    YAML::Node root = YAML::Load(in);
    if (!root || root.IsNull()) throw ConfigError(file.string(), "(file)", "is empty");
    return root;
  } catch (const YAML::ParserException& e) {
    throw ConfigError(file.string(), "(file)",
                      "malformed YAML at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

fs::path Resolve(const std::string& name_or_path, const fs::path& dir, const char* what) {
  const fs::path as_path(name_or_path);
  if (as_path.extension() == ".yaml" || as_path.extension() == ".yml" ||
      name_or_path.find('/') != std::string::npos) {
    return as_path;
  }
  const fs::path file = dir / (name_or_path + ".yaml");
  std::error_code ec;  // a name too long for a file name is an unknown preset, not an I/O error
  if (fs::exists(file, ec)) return file;
  std::string known;
  for (const std::string& n : ListConfigNames(dir)) known += (known.empty() ? "" : ", ") + n;
  throw ConfigError(
      dir.string(), name_or_path,
      std::string("unknown ") + what + " (known: " + (known.empty() ? "none" : known) + ")");
}

void ReadCamera(MapReader& r, geometry::CameraOptions& o) {
  std::string ignored;
  r.Get("description", ignored);
  r.Get("height_m", o.height_m);
  r.Angle("tilt", o.tilt_rad);
  r.Angle("roll", o.roll_rad);
  r.Get("focal_length_m", o.focal_length_m);
  r.Get("pixel_width_m", o.pixel_width_m);
  r.Get("pixel_height_m", o.pixel_height_m);
  r.Get("image_width_px", o.image_width_px);
  r.Get("image_height_px", o.image_height_px);
  r.Get("principal_point_u_px", o.principal_point_u_px);
  r.Get("principal_point_v_px", o.principal_point_v_px);
  r.Get("virtual_plane_height_m", o.virtual_plane_height_m);
  r.Finish();
}

void ReadGrid(MapReader& r, geometry::GridModelOptions& o) {
  r.Get("rows_each_side", o.rows_each_side);
  r.Get("max_range_m", o.max_range_m);
  r.Get("in_view_margin_px", o.in_view_margin_px);
  r.Finish();
}

void ReadField(MapReader& r, sim::FieldOptions& o) {
  r.Get("rows", o.rows);
  r.Get("row_spacing_m", o.row_spacing_m);
  r.Get("plant_spacing_m", o.plant_spacing_m);
  r.Get("nominal_row_spacing_m", o.nominal_row_spacing_m);
  r.Get("nominal_plant_spacing_m", o.nominal_plant_spacing_m);
  r.Get("spacing_drift_fraction", o.spacing_drift_fraction);
  r.Get("spacing_drift_wavelength_m", o.spacing_drift_wavelength_m);
  r.Get("planting_jitter_m", o.planting_jitter_m);
  r.Get("missing_plant_fraction", o.missing_plant_fraction);
  r.Get("crop_radius_m", o.crop_radius_m);
  r.Get("crop_radius_sd_fraction", o.crop_radius_sd_fraction);
  r.Get("crop_height_ratio", o.crop_height_ratio);
  r.Get("crop_lean_sd_m", o.crop_lean_sd_m);
  r.Get("crop_lobes", o.crop_lobes);
  r.Get("crop_lobe_depth", o.crop_lobe_depth);
  r.Get("fractured_fraction", o.fractured_fraction);
  r.Get("weed_density_per_m2", o.weed_density_per_m2);
  r.Get("weed_radius_median_m", o.weed_radius_median_m);
  r.Get("weed_radius_log_sd", o.weed_radius_log_sd);
  r.Get("weed_max_radius_m", o.weed_max_radius_m);
  r.Get("weed_in_row_fraction", o.weed_in_row_fraction);
  r.Get("weed_height_ratio", o.weed_height_ratio);
  r.Get("stone_density_per_m2", o.stone_density_per_m2);
  r.Get("stone_size_median_m", o.stone_size_median_m);
  r.Get("plant_brightness_sd", o.plant_brightness_sd);
  r.Get("bed_margin_m", o.bed_margin_m);
  r.Finish();
}

void ReadVehicle(MapReader& r, sim::VehicleOptions& o) {
  r.Get("speed_m_s", o.speed_m_s);
  r.Get("track_width_m", o.track_width_m);
  r.Get("start_offset_m", o.start_offset_m);
  r.Angle("start_heading", o.start_heading_rad);
  r.Get("zigzag_amplitude_m", o.zigzag_amplitude_m);
  r.Get("zigzag_wavelength_m", o.zigzag_wavelength_m);
  r.Angle("heading_wander_sd", o.heading_wander_sd_rad);
  r.Get("odometry_rate_hz", o.odometry_rate_hz);
  r.Get("odometry_noise_fraction", o.odometry_noise_fraction);
  r.Get("odometry_scale_error", o.odometry_scale_error);
  r.Get("wheel_scale_difference", o.wheel_scale_difference);
  r.Get("slip_bursts_per_100m", o.slip_bursts_per_100m);
  r.Get("slip_burst_length_m", o.slip_burst_length_m);
  r.Get("slip_fraction", o.slip_fraction);
  r.Angle("bump_pitch_sd", o.bump_pitch_sd_rad);
  r.Angle("bump_roll_sd", o.bump_roll_sd_rad);
  r.Get("bump_height_sd_m", o.bump_height_sd_m);
  r.Get("bump_correlation_s", o.bump_correlation_s);
  r.Get("frame_rate_hz", o.frame_rate_hz);
  r.Get("frame_jitter_s", o.frame_jitter_s);
  r.Get("dropped_frame_fraction", o.dropped_frame_fraction);
  r.Get("exposure_s", o.exposure_s);
  r.Finish();
}

void ReadRender(MapReader& r, sim::RenderOptions& o) {
  std::string kind = o.kind == sim::ImageKind::kRgb ? "rgb" : "nir";
  r.Get("image", kind);
  if (kind == "nir") {
    o.kind = sim::ImageKind::kNir;
  } else if (kind == "rgb") {
    o.kind = sim::ImageKind::kRgb;
  } else {
    throw ConfigError(r.file(), "render.image", "must be 'nir' or 'rgb' (got '" + kind + "')");
  }
  r.Get("exposure", o.exposure);
  r.Get("soil_reflectance", o.soil_reflectance);
  r.Get("crop_reflectance", o.crop_reflectance);
  r.Get("weed_reflectance", o.weed_reflectance);
  r.Get("stone_reflectance", o.stone_reflectance);
  r.Get("soil_texture_contrast", o.soil_texture_contrast);
  r.Get("leaf_texture_contrast", o.leaf_texture_contrast);
  r.Get("illumination_gradient", o.illumination_gradient);
  r.Get("vehicle_shadow_depth", o.vehicle_shadow_depth);
  r.Get("vehicle_shadow_edge_m", o.vehicle_shadow_edge_m);
  r.Get("vehicle_shadow_slope", o.vehicle_shadow_slope);
  r.Get("plant_shadow_depth", o.plant_shadow_depth);
  r.Angle("sun_azimuth", o.sun_azimuth_rad);
  r.Angle("sun_elevation", o.sun_elevation_rad);
  r.Get("specular_fraction", o.specular_fraction);
  r.Get("specular_gain", o.specular_gain);
  r.Get("leaf_shadow_fraction", o.leaf_shadow_fraction);
  r.Get("leaf_shadow_depth", o.leaf_shadow_depth);
  r.Get("optical_blur_px", o.optical_blur_px);
  r.Get("sensor_noise", o.sensor_noise);
  r.Get("max_range_m", o.max_range_m);
  r.Get("ray_samples", o.ray_samples);
  r.Get("threads", o.threads);
  r.Finish();
}

template <typename Fn>
void Section(MapReader& top, const std::string& key, Fn&& read) {
  if (!top.Has(key)) return;
  MapReader r(top.Node(key), top.file(), key);
  read(r);
}

}  // namespace

ConfigError::ConfigError(const std::string& file, const std::string& key, const std::string& reason)
    : std::runtime_error(file + ": " + key + ": " + reason) {}

std::vector<std::string> ListConfigNames(const fs::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

fs::path DefaultConfigDir() {
  if (const char* env = std::getenv("PLANTSCALE_CONFIG_DIR"); env != nullptr && *env != '\0') {
    return env;
  }
  return PLANTSCALE_SOURCE_CONFIG_DIR;
}

fs::path ResolveConfigFile(const std::string& name_or_path, const fs::path& dir,
                           const char* what) {
  return Resolve(name_or_path, dir, what);
}

geometry::CameraOptions LoadCamera(const std::string& name_or_path, const fs::path& config_dir) {
  const fs::path file = Resolve(name_or_path, config_dir / "cameras", "camera");
  MapReader r(ParseFile(file), file.string(), "");
  geometry::CameraOptions o;
  ReadCamera(r, o);
  const OptionErrors errors = o.Validate();
  if (!errors.empty()) throw ConfigError(file.string(), errors[0].key, errors[0].reason);
  return o;
}

namespace {

// The preset, with the camera of `calibration` instead of its own when given.
sim::SimulatorOptions LoadPreset(const std::string& name_or_path, const fs::path& config_dir,
                                 const std::string* calibration) {
  const fs::path file = Resolve(name_or_path, config_dir / "presets", "preset");
  MapReader top(ParseFile(file), file.string(), "");
  sim::SimulatorOptions o;
  o.preset = file.stem().string();
  std::string ignored;
  top.Get("description", ignored);
  std::string camera_source = file.string();
  if (top.Has("camera")) {
    const YAML::Node camera = top.Node("camera");
    if (camera.IsScalar()) {  // a camera preset by name, with optional overrides
      camera_source = Resolve(camera.Scalar(), config_dir / "cameras", "camera").string();
      o.camera = LoadCamera(camera.Scalar(), config_dir);
    } else {
      MapReader r(camera, file.string(), "camera");
      ReadCamera(r, o.camera);
    }
  }
  if (calibration != nullptr) {
    camera_source = Resolve(*calibration, config_dir / "cameras", "camera").string();
    o.camera = LoadCamera(*calibration, config_dir);
    if (top.Has("camera_overrides") && top.Node("camera_overrides").IsMap()) {
      for (const auto& item : top.Node("camera_overrides")) {
        const auto key = item.first.as<std::string>();
        if (key != "virtual_plane_height_m") {
          throw ConfigError(file.string(), "camera_overrides." + key,
                            "would change the calibration " + camera_source +
                                "; with a calibration a preset may override only "
                                "virtual_plane_height_m (the crop's height)");
        }
      }
    }
  }
  Section(top, "camera_overrides", [&](MapReader& r) { ReadCamera(r, o.camera); });
  Section(top, "grid", [&](MapReader& r) { ReadGrid(r, o.grid); });
  Section(top, "field", [&](MapReader& r) { ReadField(r, o.field); });
  Section(top, "vehicle", [&](MapReader& r) { ReadVehicle(r, o.vehicle); });
  Section(top, "render", [&](MapReader& r) { ReadRender(r, o.render); });
  top.Get("length_m", o.length_m);
  int seed = 1;
  top.Get("seed", seed);
  o.seed = static_cast<uint64_t>(seed);
  top.Finish();
  const OptionErrors errors = o.Validate();
  if (!errors.empty()) {
    const bool from_camera_file =
        errors[0].key.rfind("camera.", 0) == 0 && camera_source != file.string();
    throw ConfigError(from_camera_file ? camera_source : file.string(), errors[0].key,
                      errors[0].reason);
  }
  return o;
}

}  // namespace

sim::SimulatorOptions LoadSimulatorPreset(const std::string& name_or_path,
                                          const fs::path& config_dir) {
  return LoadPreset(name_or_path, config_dir, nullptr);
}

sim::SimulatorOptions LoadSimulatorPresetWithCalibration(const std::string& name_or_path,
                                                         const std::string& calibration,
                                                         const fs::path& config_dir) {
  return LoadPreset(name_or_path, config_dir, &calibration);
}

}  // namespace plantscale::app
