#include "evaluation/treatment_writer.h"

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "evaluation/seeds.h"
#include "evaluation/writer.h"

namespace plantscale::app {

nlohmann::json MetricsJson(const TreatmentMetrics& m) {
  return {
      {"crop_plants", m.crop_plants},
      {"crop_hits", m.crop_hits},
      {"crop_hit_rate", m.crop_hit_rate},
      {"weeds", m.weeds},
      {"weed_hits", m.weed_hits},
      {"weed_hit_rate", m.weed_hit_rate},
      {"weeds_clear_of_crop", m.weeds_clear},
      {"weed_hit_rate_clear_of_crop", m.weed_hit_rate_clear},
      {"weeds_touching_crop", m.weeds_touching},
      {"weed_hit_rate_touching_crop", m.weed_hit_rate_touching},
      {"weed_hit_rate_touching_crop_dry", m.weed_hit_rate_touching_crop_dry},
      {"placement_bias_along_m", m.placement_bias_along_m},
      {"placement_bias_across_m", m.placement_bias_across_m},
      {"placement_rms_along_m", m.placement_rms_along_m},
      {"placement_rms_across_m", m.placement_rms_across_m},
      {"placement_rms_m", m.placement_rms_m},
      {"centre_bias_along_m", m.centre_bias_along_m},
      {"centre_bias_across_m", m.centre_bias_across_m},
      {"centre_rms_along_m", m.centre_rms_along_m},
      {"centre_rms_across_m", m.centre_rms_across_m},
      {"treated_area_fraction", m.treated_area_fraction},
      {"crop_pixel_rate", m.crop_pixel_rate},
      {"crop_pixel_rate_of_plant", m.crop_pixel_rate_of_plant},
      {"weed_pixel_fpr_of_plant", m.weed_pixel_fpr_of_plant},
      {"pixels", {{"crop_as_crop", m.crop_as_crop}, {"crop_as_weed", m.crop_as_weed},
                  {"crop_as_soil", m.crop_as_soil}, {"weed_as_crop", m.weed_as_crop},
                  {"weed_as_weed", m.weed_as_weed}, {"weed_as_soil", m.weed_as_soil},
                  {"crop_as_weed_by",
                   {{"no_decision", m.crop_as_weed_no_decision},
                    {"small", m.crop_as_weed_small},
                    {"unassociated", m.crop_as_weed_unassociated},
                    {"other", m.crop_as_weed_other},
                    {"split_part", m.crop_as_weed_split_part},
                    {"split_clipped", m.crop_as_weed_split_clipped}}}}},
      {"frames_classified", m.frames_classified},
      {"ticks", m.ticks},
      {"ticks_fail_safe", m.ticks_fail_safe},
      {"shots", m.shots},
      {"map_resets", m.map_resets},
      {"plants_recorded", m.plants_recorded},
      {"plants_confirmed", m.plants_confirmed},
  };
}

namespace {

nlohmann::json PointJson(const classify::MrrocPoint& p) {
  return {{"min_crop_area_m2", std::isfinite(p.min_crop_area_m2) ? p.min_crop_area_m2 : -1.0},
          {"assoc_chi2", std::isfinite(p.assoc_chi2) ? p.assoc_chi2 : -1.0},
          {"tpr", p.tpr},
          {"fpr", p.fpr}};
}

void PrintFigures(const TreatmentEvaluation& e, std::ostream& out) {
  out << "evaluate treatment: preset " << e.preset << ", " << e.seeds << " seed(s), "
      << e.distance_m << " m per run, spray-" << e.mode << " mode\n";
  const auto row = [&](const char* name, double ours, std::optional<double> thesis_here,
                       double scale, const char* unit, const char* thesis) {
    char buffer[256];
    std::snprintf(buffer, sizeof buffer, "  %-28s %9.3f %-3s", name, ours * scale, unit);
    out << buffer;
    if (thesis_here) {
      std::snprintf(buffer, sizeof buffer, " | thesis chain here %9.3f", *thesis_here * scale);
      out << buffer;
    }
    if (*thesis) out << " | thesis: " << thesis;
    out << '\n';
  };
  const auto t = [&](double TreatmentMetrics::*field) -> std::optional<double> {
    if (!e.thesis) return std::nullopt;
    return (*e.thesis).*field;
  };
  using M = TreatmentMetrics;
  row("crop hit rate", e.ours.crop_hit_rate, t(&M::crop_hit_rate), 100, "%", "all crops treated (§8.2.1)");
  row("weed hit rate", e.ours.weed_hit_rate, t(&M::weed_hit_rate), 100, "%", "none of the weeds (§8.2.1)");
  row("weed hit rate, clear of crop", e.ours.weed_hit_rate_clear, t(&M::weed_hit_rate_clear), 100, "%", "");
  row("weeds touching a crop hit, crop dry", e.ours.weed_hit_rate_touching_crop_dry,
      t(&M::weed_hit_rate_touching_crop_dry), 100, "%", "");
  row("placement bias along (y_w)", e.ours.placement_bias_along_m, t(&M::placement_bias_along_m), 1000, "mm", "-23.1 mm (table 8.3)");
  row("placement bias across (x_w)", e.ours.placement_bias_across_m, t(&M::placement_bias_across_m), 1000, "mm", "9.7 mm (table 8.3)");
  row("placement RMS along", e.ours.placement_rms_along_m, t(&M::placement_rms_along_m), 1000, "mm", "34.4 mm (table 8.3)");
  row("placement RMS across", e.ours.placement_rms_across_m, t(&M::placement_rms_across_m), 1000, "mm", "33.6 mm (table 8.3)");
  row("RMS to plant centre, along", e.ours.centre_rms_along_m, t(&M::centre_rms_along_m), 1000, "mm", "");
  row("RMS to plant centre, across", e.ours.centre_rms_across_m, t(&M::centre_rms_across_m), 1000, "mm", "");
  row("treated area of the bed", e.ours.treated_area_fraction, t(&M::treated_area_fraction), 100, "%", "about 33 %");
  row("crop pixels labelled C", e.ours.crop_as_crop, t(&M::crop_as_crop), 100, "%", "95.1/78.9/81.7/55.0 % on A-D (tables 7.5-7.8)");
  row("crop of plant pixels as C", e.ours.crop_pixel_rate_of_plant, t(&M::crop_pixel_rate_of_plant), 100, "%", "TPR .964/.955/.948/.931 on A-D (table 7.9)");
  row("weed of plant pixels as C", e.ours.weed_pixel_fpr_of_plant, t(&M::weed_pixel_fpr_of_plant), 100, "%", "FPR .168/0/.065/.079 on A-D (table 7.9)");
  row("weed pixels labelled W", e.ours.weed_as_weed, t(&M::weed_as_weed), 100, "%", "");
  out << "  crop plants " << e.ours.crop_plants << ", weeds " << e.ours.weeds << ", shots "
      << e.ours.shots << ", fail-safe ticks " << e.ours.ticks_fail_safe << " of " << e.ours.ticks
      << ", map resets " << e.ours.map_resets << '\n';
  if (e.mrroc) {
    out << "  MRROC area " << e.mrroc->Auc() << "; operating point: min area "
        << e.operating_point.min_crop_area_m2 << " m2, chi2 " << e.operating_point.assoc_chi2
        << " (TPR " << e.operating_point.tpr << ", FPR " << e.operating_point.fpr << ")\n";
  }
  for (const std::string& why : e.example_why) out << "  plant: " << why << '\n';
}

}  // namespace

nlohmann::json ToJson(const TreatmentEvaluation& e) {
  nlohmann::json j = MetricsJson(e.ours);
  j["preset"] = e.preset;
  AddEngineJson(e.engine, j);
  nlohmann::json drawn = nlohmann::json::array();
  for (int k = 0; k < e.seeds; ++k) {
    const uint64_t seed = NthSeed(e.first_seed, k);
    drawn.push_back({{"seed", seed},
                     {"calibration_error",
                      CalibrationErrorJson(DrawnCalibrationError(e.engine.calibration_error, seed))}});
  }
  j["per_seed"] = drawn;
  j["seeds"] = e.seeds;
  j["mode"] = e.mode;
  j["distance_m"] = e.distance_m;
  j["example_why"] = e.example_why;
  nlohmann::json missed = nlohmann::json::array();
  for (const MissedCrop& m : e.missed_crops) {
    missed.push_back({{"seed", NthSeed(e.first_seed, m.seed_index)},
                      {"plant_id", m.plant_id},
                      {"root_x_m", m.root_m.x()},
                      {"root_y_m", m.root_m.y()},
                      {"radius_m", m.radius_m},
                      {"nearest_spray_m", std::isfinite(m.nearest_spray_m) ? m.nearest_spray_m : -1.0}});
  }
  j["missed_crops"] = missed;
  if (e.thesis) j["baseline_thesis"] = MetricsJson(*e.thesis);
  j["visual_motion"] = e.visual_motion;
  j["camera_substitutions"] = e.camera_substitutions;
  if (e.fault_stretch) {
    nlohmann::json f = OdometryFaultJson(e.odometry_fault);
    f["stretch"] = MetricsJson(*e.fault_stretch);
    j["odometry_fault"] = f;
  }
  if (e.mrroc) {
    nlohmann::json hull = nlohmann::json::array();
    for (const auto& p : e.mrroc->hull) hull.push_back(PointJson(p));
    j["mrroc"] = {{"auc", e.mrroc->Auc()},
                  {"costs_ratio", e.costs_ratio},
                  {"operating_point", PointJson(e.operating_point)},
                  {"nearest_corner", PointJson(e.nearest_corner)},
                  {"hull", hull}};
  }
  return j;
}

void WriteTable(const TreatmentEvaluation& e, std::ostream& out) {
  PrintFigures(e, out);
  if (e.fault_stretch) {
    const TreatmentMetrics& f = *e.fault_stretch;
    out << "  odometry fault " << Name(e.odometry_fault.kind) << " from "
        << e.odometry_fault.start_m << " m for " << e.odometry_fault.length_m
        << " m: " << f.crop_hits << " of " << f.crop_plants
        << " crops hit, placement RMS " << 1000.0 * f.placement_rms_m << " mm (along "
        << 1000.0 * f.placement_rms_along_m << ", across "
        << 1000.0 * f.placement_rms_across_m << ")"
        << (e.visual_motion ? " (visual motion on)" : " (wheels only)") << '\n';
  }
  WriteEngineLine(e.engine, out);
}

nlohmann::json TreatmentJsonShape() {
  TreatmentEvaluation e;
  e.odometry_fault.kind = OdometryFaultKind::kStop;
  e.thesis = TreatmentMetrics{};
  e.fault_stretch = TreatmentMetrics{};
  e.mrroc = classify::Mrroc{};
  return ToJson(e);
}

}  // namespace plantscale::app
