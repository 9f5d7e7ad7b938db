#include "app/tracking_commands.h"

#include <fstream>
#include <iostream>
#include <optional>
#include <string>

#include "app/config/config_loader.h"
#include "app/odometry_fault_options.h"
#include "app/segment_commands.h"
#include "evaluation/tracking_eval.h"
#include "evaluation/tracking_writer.h"
#include "evaluation/writer.h"

namespace plantscale::app {
namespace {

struct TrackingArgs {
  std::string preset = "long";
  int seeds = 10;
  std::optional<int64_t> seed;
  std::optional<double> length_m;
  double spacing_offset_mm = 0.0;
  ProfileArgs profiles;
  std::string baseline;
  bool virtual_plane = false;
  bool scale_consider = false;
  std::string trace_csv;
  bool json = false;
  std::string reference = "grid";  // or "plant-lines" (thesis §8.1)
  OdometryFaultArgs fault;
};

TrackingEvalOptions TrackingOptionsOf(const TrackingArgs& a, const GlobalOptions& global) {
  TrackingEvalOptions o;
  o.sim = LoadSimulatorPreset(a.preset, global.ConfigDir());
  if (a.seed) o.sim.seed = static_cast<uint64_t>(*a.seed);
  if (a.length_m) o.sim.length_m = *a.length_m;
  o.profiles = LoadProfiles(a.profiles.crop, a.profiles.vehicle, o.sim.preset, global.ConfigDir());
  o.calibration_error = ParseCalibrationError(a.profiles.calibration_error, "--calibration-error");
  o.seeds = a.seeds;
  o.spacing_offset_m = a.spacing_offset_mm / 1000.0;
  o.baseline_thesis = a.baseline == "thesis";
  o.centroids_on_virtual_plane = a.virtual_plane;
  o.calibration_scale_consider = a.scale_consider;
  o.odometry_fault = ToOdometryFault(a.fault);
  o.visual_motion = a.fault.visual_motion;
  o.reference = a.reference == "plant-lines" ? TrackingReference::kPlantLines : TrackingReference::kGrid;
  o.calibration_error_text = a.profiles.calibration_error;
  return o;
}

int EvaluateTrackingCommand(const TrackingArgs& a, const GlobalOptions& global) {
  TrackingEvalOptions o = TrackingOptionsOf(a, global);
  std::ofstream trace;
  if (!a.trace_csv.empty()) {
    trace.open(a.trace_csv);
    if (!trace) {
      std::cerr << "evaluate tracking: cannot write " << a.trace_csv << '\n';
      return 1;
    }
    o.trace = &trace;
  }
  WriteEvaluation(EvaluateTracking(o), a.json, std::cout);
  return 0;
}

}  // namespace

void AddTrackingCommands(CommandRegistry& registry) {
  const GlobalOptions& global = registry.global();
  TrackingArgs& args = registry.Keep(TrackingArgs{});
  CLI::App* cmd = registry.Add(
      "tracking", "crop-grid tracker accuracy, consistency and initialisation against truth",
      [&args, &global] { return EvaluateTrackingCommand(args, global); },
      EvaluateCommand(registry));
  AddRunOptions(cmd, args.preset, args.seeds, args.seed, &args.length_m);
  AddProfileOptions(cmd, args.profiles, true);
  cmd->add_option("--spacing-offset-mm", args.spacing_offset_mm,
                  "start our estimated spacings this far off the crop profile's")
      ->capture_default_str();
  cmd->add_option("--baseline", args.baseline, "also run the thesis's tracker")
      ->check(CLI::IsMember({"thesis"}));
  cmd->add_flag("--virtual-plane", args.virtual_plane,
                "locate our blob centroids on the preset's virtual plane (thesis §2.3.8) instead of "
                "at the crop's centroid heights");
  cmd->add_flag("--scale-consider", args.scale_consider,
                "carry the camera's tilt, height and focal length (the vehicle profile's "
                "calibration_sd) in our tracker as consider states, as well as the roll "
                "(TrackerOptions::calibration_scale_consider; off in the product: "
                "docs/results/2026-11-27-calibration.md)");
  cmd->add_option("--trace-csv", args.trace_csv,
                  "write our per-frame errors, σ, spacings and wheel scale to this CSV");
  cmd->add_option("--reference", args.reference,
                  "what lateral errors are scored against: grid (the planted grid, every frame) "
                  "or plant-lines (thesis §8.1: at each line of plants, against the mean root "
                  "position of that line's plants)")
      ->check(CLI::IsMember({"grid", "plant-lines"}))
      ->capture_default_str();
  AddOdometryFaultOptions(cmd, args.fault);
  cmd->add_flag("--json", args.json, "print one JSON object");
}

}  // namespace plantscale::app
