#pragma once
// A small registry of plantscale subcommands. Each command family lives in its
// own file (simulate_commands.cc, segment_commands.cc, ...) and adds itself
// with one Add*Commands(CommandRegistry&) call in commands.cc, so that
// families never edit each other's code.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/config/profiles.h"

namespace plantscale::app {

// Options that every subcommand may read (set before the subcommand).
struct GlobalOptions {
  std::string config_dir;  // --config-dir; empty: DefaultConfigDir()
  std::filesystem::path ConfigDir() const;
};

class CommandRegistry {
 public:
  explicit CommandRegistry(CLI::App& cli);

  // Adds `name` (a subcommand of `parent`, or of the top level when null) run
  // by `run` when parsed. Returns the CLI11 subcommand for adding options.
  CLI::App* Add(const std::string& name, const std::string& description,
                std::function<int()> run, CLI::App* parent = nullptr);

  // Keeps `value` alive for as long as the registry (option storage).
  template <typename T>
  T& Keep(T value) {
    auto holder = std::make_shared<T>(std::move(value));
    kept_.push_back(holder);
    return *holder;
  }

  // Runs the parsed subcommand; returns its exit code (2 when none parsed).
  int Run() const;

  CLI::App& cli() { return cli_; }
  const GlobalOptions& global() const { return *global_; }

 private:
  struct Entry {
    CLI::App* command;
    std::function<int()> run;
  };
  CLI::App& cli_;
  std::shared_ptr<GlobalOptions> global_;
  std::vector<Entry> entries_;
  std::vector<std::shared_ptr<void>> kept_;
};

// The simulator-run options every `evaluate` command shares: --preset,
// --seeds (`seeds_help`), --seed and, when given, --length-m.
void AddRunOptions(CLI::App* cmd, std::string& preset, int& seeds, std::optional<int64_t>& seed,
                   std::optional<double>* length_m = nullptr,
                   const std::string& seeds_help = "number of seeds");

// The profiles an `evaluate` configures its engines from (issue 33):
// --crop FILE, --vehicle FILE (default: those named for the preset's
// nominal crop and vehicle) and, with `calibration_error`,
// --calibration-error height_m=H,tilt_deg=T,roll_deg=R,focal=F.
struct ProfileArgs {
  std::string crop;
  std::string vehicle;
  std::string calibration_error;
  std::string segmenter_model;  // overrides the crop profile's `segmenter: {model}`
};
void AddProfileOptions(CLI::App* cmd, ProfileArgs& args, bool calibration_error);
// The crop profile's learned model replaced by --segmenter-model (when
// given: a name in config/models or a .onnx path). Throws ConfigError when
// it names no model.
void ApplySegmenterModelArg(const ProfileArgs& args, const std::filesystem::path& config_dir,
                            Profiles& profiles);

// A default for a --help text, printed from the code's own value ("%g").
std::string HelpNumber(double value);

}  // namespace plantscale::app
