#include "app/command_registry.h"

#include "app/config_loader.h"

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

}  // namespace plantscale::app
