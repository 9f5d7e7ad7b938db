#include "app/simulate_commands.h"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <optional>

#include "app/config/config_loader.h"
#include "app/sim_output.h"
#include "app/telemetry_commands.h"

namespace plantscale::app {
namespace {

struct SimulateArgs {
  std::string preset = "field";
  std::optional<double> length_m;
  std::optional<int64_t> seed;
  std::string out;
  int every = 1;
  std::string image;
  bool quiet = false;
  std::string crop, vehicle;  // profiles of the vehicle pipeline (--publish)
  std::string segmenter_model;  // --segmenter-model (overrides the crop profile's)
  PublishArgs publish;  // simulate only: --publish, --fast, --lcm-url, --log
};


void AddSimulateOptions(CLI::App* cmd, SimulateArgs& a) {
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

SimulateRequest MakeRequest(const SimulateArgs& a, const GlobalOptions& global) {
  SimulateRequest r;
  r.options = LoadSimulatorPreset(a.preset, global.ConfigDir());
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


int Simulate(const SimulateArgs& args, const GlobalOptions& global, const char* name) {
  if (args.out.empty() && !args.publish.publish) {
    throw ConfigError("command line", "--out", "required (or --publish to stream telemetry)");
  }
  const PublishArgs& p = args.publish;
  if (!p.publish && (p.fast || !p.lcm_url.empty() || !p.log.empty() || !p.can.empty())) {
    throw ConfigError("command line", "--fast/--lcm-url/--log/--can", "only with --publish");
  }
  if (!p.publish && !p.gateway.listen.empty()) {
    throw ConfigError("command line", "--gateway", "only with --publish");
  }
  const SimulateRequest request = MakeRequest(args, global);
  if (args.publish.publish) {
    Profiles profiles =
        LoadProfiles(args.crop, args.vehicle, request.options.preset, global.ConfigDir());
    ProfileArgs model;
    model.segmenter_model = args.segmenter_model;
    ApplySegmenterModelArg(model, global.ConfigDir(), profiles);
    PrintProfileWarnings(profiles, std::cerr);
    SimRunConfig run = SimRunConfigOf(args.preset, global.ConfigDir(), request.options);
    run.crop = std::filesystem::absolute(profiles.crop.file).lexically_normal().string();
    run.vehicle = std::filesystem::absolute(profiles.vehicle.file).lexically_normal().string();
    return SimulateAndPublish(request.options, profiles, args.publish, run);
  }
  if (!args.crop.empty() || !args.vehicle.empty()) {
    throw ConfigError("command line", "--crop/--vehicle", "only with --publish");
  }
  const SimulateSummary summary = RunSimulation(request, std::cerr);
  PrintSummary(name, request, summary);
  return 0;
}

int Presets(const GlobalOptions& global) {
  const std::filesystem::path dir = global.ConfigDir();
  for (const char* kind : {"presets", "cameras", "crops", "vehicles"}) {
    std::cout << kind << " (" << (dir / kind).string() << "):\n";
    for (const std::string& n : ListConfigNames(dir / kind)) std::cout << "  " << n << '\n';
  }
  return 0;
}

}  // namespace

void AddSimulateCommands(CommandRegistry& registry) {
  const GlobalOptions& global = registry.global();

  SimulateArgs& sim = registry.Keep(SimulateArgs{});
  CLI::App* simulate = registry.Add(
      "simulate", "drive the field simulator and write frames and ground truth",
      [&sim, &global] { return Simulate(sim, global, "simulate"); });
  AddSimulateOptions(simulate, sim);
  CLI::Option* out = simulate->add_option("--out", sim.out, "output folder (unless --publish)");
  AddPublishOptions(simulate, sim.publish);
  out->excludes("--publish");
  simulate->add_option("--crop", sim.crop,
                       "with --publish: the vehicle pipeline's crop profile (config/crops name "
                       "or YAML file; default: the preset's nominal crop by name)");
  simulate->add_option("--vehicle", sim.vehicle,
                       "with --publish: the vehicle pipeline's vehicle profile (config/vehicles "
                       "name or YAML file; default: the preset's vehicle by name)");
  simulate->add_option("--segmenter-model", sim.segmenter_model,
                       "with --publish: the grower's learned crop/weed model (config/models name "
                       "or .onnx file) instead of the crop profile's; \"none\": the grid's rule alone");

  registry.Add("presets", "list the simulator presets, cameras, crop profiles and vehicle profiles",
               [&global] { return Presets(global); });
}

}  // namespace plantscale::app
