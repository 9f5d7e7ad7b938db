#include "evaluation/log_writer.h"

#include <cstdio>
#include <string>

#include "evaluation/tracking_writer.h"
#include "evaluation/treatment_writer.h"

namespace plantscale::app {

nlohmann::json ToJson(const LogEvaluation& e) {
  nlohmann::json treatment = MetricsJson(e.treatment);
  for (const std::string& key : TreatmentKeysNotInLogs()) treatment[key] = nullptr;
  const LogMessages& n = e.messages;
  nlohmann::json spacing = nlohmann::json::array();
  for (const LogEvaluation::Said& said : e.row_spacing_events) {
    spacing.push_back({{"utime", said.utime}, {"text", said.text}});
  }
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
          {"row_spacing_events", spacing},
          {"problems", e.problems}};
}

void WriteTable(const LogEvaluation& e, std::ostream& out) {
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
  for (const LogEvaluation::Said& said : e.row_spacing_events) out << "  the vehicle said: " << said.text << '\n';
}

}  // namespace plantscale::app
