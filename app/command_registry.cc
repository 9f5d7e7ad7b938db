#include "app/command_registry.h"

#include <cstdio>

#include "app/config/config_loader.h"

namespace plantscale::app {

std::filesystem::path GlobalOptions::ConfigDir() const {
  return config_dir.empty() ? DefaultConfigDir() : std::filesystem::path(config_dir);
}

CommandRegistry::CommandRegistry(CLI::App& cli)
    : cli_(cli), global_(std::make_shared<GlobalOptions>()) {
  cli_.add_option("--config-dir", global_->config_dir,
                  "folder with cameras/ and presets/ (default: built-in)");
}

CLI::App* CommandRegistry::Add(const std::string& name, const std::string& description,
                               std::function<int()> run, CLI::App* parent) {
  CLI::App* command = (parent ? parent : &cli_)->add_subcommand(name, description);
  entries_.push_back({command, std::move(run)});
  return command;
}

int CommandRegistry::Run() const {
  // Deepest parsed command wins: `evaluate segmentation` before `evaluate`.
  for (auto it = entries_.rbegin(); it != entries_.rend(); ++it) {
    if (it->command->parsed() && it->run) return it->run();
  }
  return 2;
}

void AddRunOptions(CLI::App* cmd, std::string& preset, int& seeds, std::optional<int64_t>& seed,
                   std::optional<double>* length_m, const std::string& seeds_help) {
  cmd->add_option("--preset", preset, "preset name or YAML file")->capture_default_str();
  cmd->add_option("--seeds", seeds, seeds_help)->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--seed", seed, "first seed (default: the preset's)")->check(CLI::NonNegativeNumber);
  if (length_m != nullptr) {
    cmd->add_option("--length-m", *length_m, "distance driven per run (default: the preset's)")
        ->check(CLI::PositiveNumber);
  }
}

void AddProfileOptions(CLI::App* cmd, ProfileArgs& a, bool calibration_error) {
  cmd->add_option("--crop", a.crop,
                  "crop profile the engine is configured from (config/crops name or YAML file, "
                  "docs/profiles.md; default: the preset's nominal crop, by name)");
  cmd->add_option("--vehicle", a.vehicle,
                  "vehicle profile the engine is configured from (config/vehicles name or YAML "
                  "file; default: the preset's vehicle, by name)");
  cmd->add_option("--segmenter-model", a.segmenter_model,
                  "the grower's learned crop/weed model (config/models name or .onnx file, "
                  "docs/learned-segmentation.md) instead of the crop profile's segmenter.model; "
                  "\"none\": the grid's rule alone");
  if (calibration_error) {
    cmd->add_option("--calibration-error", a.calibration_error,
                    "the engine's camera is off from the simulator's by an error drawn per seed "
                    "from a normal distribution with these standard deviations: "
                    "height_m=H,tilt_deg=T,roll_deg=R,focal=F (focal: a fraction); e.g. "
                    "height_m=0.01,tilt_deg=0.5,roll_deg=0.3,focal=0.01 (the JSON lists each "
                    "seed's draw)");
  }
}

void ApplySegmenterModelArg(const ProfileArgs& a, const std::filesystem::path& config_dir,
                            Profiles& profiles) {
  if (a.segmenter_model.empty()) return;
  if (a.segmenter_model == "none") {
    profiles.crop.segmenter_model.clear();
    return;
  }
  profiles.crop.segmenter_model = ResolveModelPath(a.segmenter_model, std::filesystem::current_path(),
                                                   config_dir, "--segmenter-model", a.segmenter_model);
}

std::string HelpNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

}  // namespace plantscale::app
