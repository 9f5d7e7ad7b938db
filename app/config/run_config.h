#pragma once
// What a simulated vehicle run was made from, recorded in its log so that
// the run can be scored long after (`plantscale evaluate log`): the
// simulator is deterministic in its options, so the preset (as given on the
// command line), the folder it was read from and what the command line
// changed (seed, length, image kind) rebuild the same field, plant for plant.
// `simulate --publish` sends it once, as the JSON text of a "run_config"
// event on PLANTSCALE_EVENTS right after "run_started".

#include <cstdint>
#include <filesystem>
#include <string>

#include "engine/sim/simulator.h"

namespace plantscale::app {

struct SimRunConfig {
  std::string preset;  // preset name or YAML file, as given
  uint64_t seed = 1;
  double length_m = 40.0;
  std::string image = "nir";  // "nir" or "rgb"
  std::string config_dir;     // the folder presets were read from (absolute)
  // The profiles the vehicle pipeline was configured from (files, absolute;
  // empty in logs from before profiles: the preset's defaults).
  std::string crop;
  std::string vehicle;
};

// The run of `options`, loaded from `preset` in `config_dir`.
SimRunConfig SimRunConfigOf(const std::string& preset, const std::filesystem::path& config_dir,
                            const sim::SimulatorOptions& options);

// One JSON object: {"preset", "seed", "length_m", "image", "config_dir",
// "crop", "vehicle"}.
std::string RunConfigJson(const SimRunConfig& run);
// Throws ConfigError naming `where` (the log) and the key when the text is
// not such an object.
SimRunConfig ParseRunConfig(const std::string& json, const std::string& where);

// The simulator options of the run: its preset from `config_dir`, with the
// run's seed, length and image kind. Throws ConfigError as
// LoadSimulatorPreset does.
sim::SimulatorOptions SimulatorOptionsOf(const SimRunConfig& run,
                                         const std::filesystem::path& config_dir);

}  // namespace plantscale::app
