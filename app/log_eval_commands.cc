#include "app/log_eval_commands.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "app/log_eval.h"
#include "app/segment_commands.h"
#include "app/tracking_commands.h"
#include "app/treatment_commands.h"

namespace plantscale::app {
namespace {

struct LogEvalArgs {
  std::string log;
  std::string config_dir;
  bool json = false;
};

nlohmann::json Json(const LogEvaluation& e) {
  nlohmann::json treatment = MetricsJson(e.treatment);
  for (const std::string& key : TreatmentKeysNotInLogs()) treatment[key] = nullptr;
  const LogMessages& n = e.messages;
  return {{"log", e.log},
          {"preset", e.run.preset},
          {"seed", e.run.seed},
          {"length_m", e.run.length_m},
          {"config_dir", e.config_dir.string()},
          {"distance_m", e.distance_m},
          {"treatment", treatment},
          {"tracking", MetricsJson(e.tracking)},
          {"messages",
           {{"events", n.events},
            {"grid", n.grid},
            {"truth", n.truth},
            {"truth_pose", n.truth_pose},
            {"nozzles", n.nozzles},
            {"shots", n.shots},
            {"grid_without_truth", n.grid_without_truth},
            {"undecodable", n.undecodable}}},
          {"problems", e.problems}};
}

void PrintTable(const LogEvaluation& e, std::ostream& out) {
  char line[256];
  const auto row = [&](const char* name, double value, const char* unit) {
    std::snprintf(line, sizeof line, "  %-30s %9.3f %s\n", name, value, unit);
    out << line;
  };
  out << "evaluate log: " << e.log << ": preset " << e.run.preset << ", seed " << e.run.seed << ", "
      << e.distance_m << " m driven\n";
  const TreatmentMetrics& t = e.treatment;
  row("crop hit rate", 100 * t.crop_hit_rate, "%");
  row("weed hit rate", 100 * t.weed_hit_rate, "%");
  row("weed hit rate, clear of crop", 100 * t.weed_hit_rate_clear, "%");
  row("placement bias along (y_w)", 1000 * t.placement_bias_along_m, "mm");
  row("placement bias across (x_w)", 1000 * t.placement_bias_across_m, "mm");
  row("placement RMS along", 1000 * t.placement_rms_along_m, "mm");
  row("placement RMS across", 1000 * t.placement_rms_across_m, "mm");
  row("treated area of the bed", 100 * t.treated_area_fraction, "%");
  out << "  crop plants " << t.crop_plants << ", weeds " << t.weeds << ", shots " << t.shots
      << ", frames classified " << t.frames_classified << '\n';
  const TrackingMetrics& k = e.tracking;
  row("lateral RMSE", 1000 * k.lateral_rmse_m, "mm");
  row("filter sigma(t_x), mean", 1000 * k.lateral_sd_mean_m, "mm");
  row("bearing RMSE", k.bearing_rmse_deg, "deg");
  row("forward drift", k.forward_drift_cm_per_m, "cm/m");
  row("NEES in 95 % bounds", k.nees_in_bounds_fraction, "");
  out << "  frames scored " << k.frames << " of " << k.frames_tracking << " tracked, losses "
      << k.losses << ", initialised on the right grid: " << (k.init_success_rate > 0 ? "yes" : "no")
      << '\n';
}

int EvaluateLogCommand(const LogEvalArgs& a, const GlobalOptions& global) {
  LogEvalOptions o;
  o.log = a.log;
  // --config-dir here, else the global one when given, else the log's own.
  o.config_dir = !a.config_dir.empty() ? a.config_dir : global.config_dir;
  const LogEvaluation e = EvaluateLog(o);
  for (const std::string& p : e.problems) std::cerr << "evaluate log: warning: " << p << '\n';
  if (a.json) {
    std::cout << Json(e).dump(2) << '\n';
  } else {
    PrintTable(e, std::cout);
  }
  return 0;
}

}  // namespace

void AddLogEvalCommands(CommandRegistry& registry) {
  const GlobalOptions& global = registry.global();
  LogEvalArgs& args = registry.Keep(LogEvalArgs{});
  CLI::App* cmd = registry.Add(
      "log",
      "a simulated run's vehicle log (simulate --publish --log) against the truth in it: "
      "treatment and tracking as evaluate treatment and evaluate tracking score them",
      [&args, &global] { return EvaluateLogCommand(args, global); }, EvaluateCommand(registry));
  cmd->add_option("LOG", args.log, "LCM log of plantscale simulate --publish --log")->required();
  cmd->add_option("--config-dir", args.config_dir,
                  "folder with presets/ to rebuild the run from (default: the log's, else "
                  "built-in)");
  cmd->add_flag("--json", args.json, "print one JSON object");
}

}  // namespace plantscale::app
