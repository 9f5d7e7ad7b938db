#pragma once
// Reads YAML presets into the engine's option structs (docs/design.md §6: only
// app/ reads files). Every problem is reported with the file, the key and
// the reason; unknown keys are errors so that typos never pass silently.
// Angles are written in degrees (`tilt_deg`) or radians (`tilt_rad`) and
// converted here, at the edge.

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/sim/simulator.h"

namespace plantscale::app {

class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& file, const std::string& key, const std::string& reason);
};

// Where presets live: $PLANTSCALE_CONFIG_DIR, else the source tree's config/.
std::filesystem::path DefaultConfigDir();

// Names (file stems) of the .yaml files in `dir`, sorted; empty if unreadable.
std::vector<std::string> ListConfigNames(const std::filesystem::path& dir);

// `name_or_path` is a preset name (config/presets/<name>.yaml) or a path to
// a YAML file. Throws ConfigError for an unknown preset, unreadable or
// malformed YAML, unknown keys, wrong types and invalid values.
sim::SimulatorOptions LoadSimulatorPreset(const std::string& name_or_path,
                                          const std::filesystem::path& config_dir);
// The preset's field, vehicle, grid and render settings around the camera
// of `calibration` (a camera name or file, as LoadCamera) instead of the
// preset's own: `run --calibration`, until crop profiles hold the crop and
// vehicle settings. The preset's camera_overrides still apply and may set
// only virtual_plane_height_m (the crop's height, a crop setting); any other
// override is a ConfigError. Camera errors name the calibration file.
sim::SimulatorOptions LoadSimulatorPresetWithCalibration(const std::string& name_or_path,
                                                         const std::string& calibration,
                                                         const std::filesystem::path& config_dir);
// The file of `name_or_path` in `dir` (a name: dir/<name>.yaml; a path as
// given); throws ConfigError listing the known names for an unknown name.
std::filesystem::path ResolveConfigFile(const std::string& name_or_path,
                                        const std::filesystem::path& dir, const char* what);
geometry::CameraOptions LoadCamera(const std::string& name_or_path,
                                   const std::filesystem::path& config_dir);

}  // namespace plantscale::app
