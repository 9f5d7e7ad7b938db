#include "app/commands.h"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <numbers>

#include "app/config_loader.h"
#include "app/sim_output.h"

namespace plantscale::app {
namespace {

void AddSimulateOptions(CLI::App* cmd, auto& a) {
  cmd->add_option("--preset", a.preset, "preset name (config/presets) or YAML file")
      ->capture_default_str();
  cmd->add_option("--length-m", a.length_m, "distance to drive, metres (default: the preset's)");
  cmd->add_option("--seed", a.seed, "random seed (default: the preset's)");
  cmd->add_option("--every", a.every, "write images of every k-th frame (truth for all)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--image", a.image, "image kind: nir or rgb (default: the preset's)")
      ->check(CLI::IsMember({"nir", "rgb"}));
  cmd->add_flag("--quiet", a.quiet, "no progress bar");
}

template <typename Args>
SimulateRequest MakeRequest(const Args& a, const std::string& config_dir) {
  SimulateRequest r;
  const std::filesystem::path dir =
      config_dir.empty() ? DefaultConfigDir() : std::filesystem::path(config_dir);
  r.options = LoadSimulatorPreset(a.preset, dir);
  if (a.length_m) r.options.length_m = *a.length_m;
  if (a.seed) {
    if (*a.seed < 0) throw ConfigError("--seed", "seed", "must be >= 0");
    r.options.seed = static_cast<uint64_t>(*a.seed);
  }
  if (a.image == "rgb") r.options.render.kind = sim::ImageKind::kRgb;
  if (a.image == "nir") r.options.render.kind = sim::ImageKind::kNir;
  ThrowIfInvalid("command line (--length-m, --seed) with preset '" + a.preset + "'",
                 r.options.Validate());
  r.out = a.out;
  r.image_every = a.every;
  r.progress = !a.quiet;
  return r;
}

void PrintSummary(const char* command, const SimulateRequest& r, const SimulateSummary& s) {
  const double deg = 180.0 / std::numbers::pi;
  std::cout << std::fixed << std::setprecision(2) << "plantscale " << command << ": preset "
            << r.options.preset << ", seed " << r.options.seed << "\n  driven            "
            << s.distance_m << " m in " << s.frames << " frames (" << s.dropped
            << " dropped), odometry says " << s.odometry_distance_m << " m"
            << "\n  field             " << s.crops_in_field << " crops, " << s.weeds_in_field
            << " weeds; " << s.plants_seen << " plants seen, " << std::setprecision(0)
            << s.mean_plant_pixels << " px per plant per frame" << std::setprecision(1)
            << "\n  vehicle vs rows   RMS offset " << 1000.0 * s.rms_offset_m << " mm, max "
            << 1000.0 * s.max_abs_offset_m << " mm, max bearing " << std::setprecision(2)
            << deg * s.max_abs_bearing_rad << " deg" << std::setprecision(1)
            << "\n  speed             "
            << (s.simulate_seconds > 0 ? s.frames / s.simulate_seconds : 0.0)
            << " frames/s simulated, " << s.wall_seconds << " s in all with disk writes"
            << "\n  wrote             " << r.out.string() << "/ (" << s.images_written
            << " frames with labels and instances in frames/, labels/, instances/;"
            << "\n                    truth/frames.csv, truth/visible_plants.csv, truth/plants.csv,"
            << "\n                    truth/lines.csv, truth/odometry.csv, run.json)\n";
}

}  // namespace

CommandLine::CommandLine(CLI::App& cli) {
  cli.add_option("--config-dir", config_dir_,
                 "folder with cameras/ and presets/ (default: built-in)");
  simulate_ =
      cli.add_subcommand("simulate", "drive the field simulator and write frames and ground truth");
  AddSimulateOptions(simulate_, sim_);
  simulate_->add_option("--out", sim_.out, "output folder")->required();

  demo_ = cli.add_subcommand("demo", "a simulated 40 m pass written to out/demo with a summary");
  demo_args_.out = "out/demo";
  demo_args_.every = 25;
  AddSimulateOptions(demo_, demo_args_);
  demo_->add_option("--out", demo_args_.out, "output folder")->capture_default_str();

  presets_ = cli.add_subcommand("presets", "list the simulator presets and cameras");
}

int CommandLine::Run() const {
  if (simulate_->parsed()) return Simulate();
  if (demo_->parsed()) return Demo();
  if (presets_->parsed()) return Presets();
  return 2;
}

int CommandLine::Simulate() const {
  const SimulateRequest request = MakeRequest(sim_, config_dir_);
  const SimulateSummary summary = RunSimulation(request, std::cerr);
  PrintSummary("simulate", request, summary);
  return 0;
}

int CommandLine::Demo() const {
  SimulateArgs args = demo_args_;
  if (!args.length_m) args.length_m = 40.0;
  const SimulateRequest request = MakeRequest(args, config_dir_);
  const SimulateSummary summary = RunSimulation(request, std::cerr);
  PrintSummary("demo", request, summary);
  return 0;
}

int CommandLine::Presets() const {
  const std::filesystem::path dir =
      config_dir_.empty() ? DefaultConfigDir() : std::filesystem::path(config_dir_);
  for (const char* kind : {"presets", "cameras"}) {
    std::cout << kind << " (" << (dir / kind).string() << "):\n";
    for (const std::string& n : ListConfigNames(dir / kind)) std::cout << "  " << n << '\n';
  }
  return 0;
}

}  // namespace plantscale::app
