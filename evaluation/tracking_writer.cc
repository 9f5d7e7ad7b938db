#include "evaluation/tracking_writer.h"

#include <cstdio>
#include <optional>
#include <string>

#include "evaluation/writer.h"

namespace plantscale::app {
namespace {

nlohmann::json RowSpacingEventsJson(const std::vector<RowSpacingEvent>& events) {
  nlohmann::json out = nlohmann::json::array();
  for (const RowSpacingEvent& e : events) {
    out.push_back({{"distance_m", e.distance_m},
                   {"since_start_m", e.since_start_m},
                   {"measured_row_spacing_m", e.mismatch.measured_m},
                   {"measured_row_spacing_sd_m", e.mismatch.measured_sd_m},
                   {"estimated_row_spacing_m", e.mismatch.estimate_m},
                   {"profile_row_spacing_m", e.mismatch.profile_m},
                   {"profile_row_spacing_sd_m", e.mismatch.profile_sd_m},
                   {"chi2", e.mismatch.chi2},
                   {"true_row_spacing_m", e.true_row_spacing_m},
                   {"text", e.mismatch.Text()}});
  }
  return out;
}

nlohmann::json CalibrationEstimateJson(const TrackingRun::CalibrationEstimate& c) {
  constexpr double kDeg = 180.0 / 3.14159265358979323846;
  return {{"tilt_deg", Finite(c.value(0) * kDeg)},  {"roll_deg", Finite(c.value(1) * kDeg)},
          {"height_m", Finite(c.value(2))},          {"focal", Finite(c.value(3))},
          {"tilt_sd_deg", Finite(c.sd(0) * kDeg)},   {"roll_sd_deg", Finite(c.sd(1) * kDeg)},
          {"height_sd_m", Finite(c.sd(2))},          {"focal_sd", Finite(c.sd(3))}};
}

nlohmann::json RunsJson(const std::vector<TrackingRun>& runs) {
  nlohmann::json out = nlohmann::json::array();
  for (const TrackingRun& r : runs) {
    out.push_back({{"seed", r.seed},
                   {"calibration_error", CalibrationErrorJson(r.calibration_error)},
                   {"started", r.started},
                   {"frames_scored", r.frames},
                   {"frames_lost", r.frames_lost},
                   {"losses", r.losses},
                   {"lateral_rmse_m", Finite(r.lateral_rmse_m)},
                   {"nees_in_bounds_fraction", r.nees_in_bounds_fraction},
                   {"row_spacing_events", RowSpacingEventsJson(r.row_spacing_events)},
                   {"calibration_estimate_at_20m", CalibrationEstimateJson(r.calibration_at_20m)},
                   {"calibration_estimate_at_end", CalibrationEstimateJson(r.calibration_at_end)}});
  }
  return out;
}

}  // namespace

nlohmann::json MetricsJson(const TrackingMetrics& m) {
  return {
      {"lateral_rmse_m", m.lateral_rmse_m},
      {"lateral_mean_m", m.lateral_mean_m},
      {"forward_mean_m", m.forward_mean_m},
      {"row_spacing_mean_error_m", m.row_spacing_mean_error_m},
      {"plant_spacing_mean_error_m", m.plant_spacing_mean_error_m},
      {"bearing_rmse_deg", m.bearing_rmse_deg},
      {"forward_drift_cm_per_m", m.forward_drift_cm_per_m},
      {"forward_drift_abs_max_cm_per_m", m.forward_drift_abs_max_cm_per_m},
      {"row_spacing_error_m", m.row_spacing_error_m},
      {"plant_spacing_error_m", m.plant_spacing_error_m},
      {"nees_in_bounds_fraction", m.nees_in_bounds_fraction},
      {"nees_mean", m.nees_mean},
      {"normalised_error2", {{"offset", m.normalised_error2(0)}, {"forward", m.normalised_error2(1)},
                             {"bearing", m.normalised_error2(2)}}},
      {"lateral_sd_mean_m", m.lateral_sd_mean_m},
      {"init_success_rate", m.init_success_rate},
      {"init_frames_p95", m.init_frames_p95},
      {"init_trials", m.init_trials},
      {"frames_scored", m.frames},
      {"frames_lost", m.frames_lost},
      {"runs_not_started", m.runs_not_started},
      {"per_seed", RunsJson(m.runs)},
      {"planter_spread",
       {{"measured_across_m", Finite(m.plant_spread.across_sd_m())},
        {"measured_along_m", Finite(m.plant_spread.along_sd_m())},
        {"plants_across", m.plant_spread.across},
        {"plants_along", m.plant_spread.along}}},
      {"frames_tracking", m.frames_tracking},
      {"updates", m.updates},
      {"losses", m.losses},
      {"row_spacing_events", m.row_spacing_events},
      {"mean_matched", m.mean_matched},
      {"run_lateral_rmse_m", m.run_lateral_rmse_m},
      {"run_forward_drift_cm_per_m", m.run_forward_drift_cm_per_m},
  };
}

namespace {

// The thesis's own figures for its tracker (tables 5.22, 8.1, 8.2; §8.1.1).
struct ThesisFigure {
  const char* key;
  const char* text;
};
constexpr ThesisFigure kThesis[] = {
    {"lateral_rmse_m", "15.3 mm field (table 8.1), 5.8-7.3 mm test bed (table 5.22)"},
    {"bearing_rmse_deg", "not measured"},
    {"forward_drift_cm_per_m", "-3.0 to -4.1 cm/m field (table 8.2)"},
    {"row_spacing_error_m", "fixed grid"},
    {"plant_spacing_error_m", "fixed grid"},
    {"nees_in_bounds_fraction", "about 2x overconfident (table 5.22)"},
    {"lateral_sd_mean_m", "2.25 mm field, 3.1 mm test bed (§8.1.1)"},
    {"init_success_rate", "hand start fails ~5 % (ch. 6)"},
};

void PrintFigures(const TrackingEvaluation& e, std::ostream& out) {
  out << "evaluate tracking: preset " << e.preset << ", " << e.seeds << " seed(s), "
      << e.distance_m << " m per run\n";
  const auto row = [&](const char* name, double ours, std::optional<double> thesis_run,
                       const char* key, double scale, const char* unit) {
    char buffer[256];
    std::snprintf(buffer, sizeof buffer, "  %-26s %10.3f %-6s", name, ours * scale, unit);
    out << buffer;
    if (thesis_run) {
      std::snprintf(buffer, sizeof buffer, " | thesis tracker here %10.3f", *thesis_run * scale);
      out << buffer;
    }
    for (const ThesisFigure& f : kThesis) {
      if (std::string(f.key) == key) out << " | thesis: " << f.text;
    }
    out << '\n';
  };
  const auto t = [&](double TrackingMetrics::*field) -> std::optional<double> {
    if (!e.thesis) return std::nullopt;
    return (*e.thesis).*field;
  };
  row("lateral RMSE", e.ours.lateral_rmse_m, t(&TrackingMetrics::lateral_rmse_m),
      "lateral_rmse_m", 1000.0, "mm");
  row("filter sigma(t_x), mean", e.ours.lateral_sd_mean_m, t(&TrackingMetrics::lateral_sd_mean_m),
      "lateral_sd_mean_m", 1000.0, "mm");
  row("bearing RMSE", e.ours.bearing_rmse_deg, t(&TrackingMetrics::bearing_rmse_deg),
      "bearing_rmse_deg", 1.0, "deg");
  row("forward drift (mean)", e.ours.forward_drift_cm_per_m,
      t(&TrackingMetrics::forward_drift_cm_per_m), "forward_drift_cm_per_m", 1.0, "cm/m");
  row("forward drift (worst run)", e.ours.forward_drift_abs_max_cm_per_m,
      t(&TrackingMetrics::forward_drift_abs_max_cm_per_m), "", 1.0, "cm/m");
  row("row spacing error", e.ours.row_spacing_error_m, t(&TrackingMetrics::row_spacing_error_m),
      "row_spacing_error_m", 1000.0, "mm");
  row("plant spacing error", e.ours.plant_spacing_error_m,
      t(&TrackingMetrics::plant_spacing_error_m), "plant_spacing_error_m", 1000.0, "mm");
  row("NEES in 95 % bounds", e.ours.nees_in_bounds_fraction,
      t(&TrackingMetrics::nees_in_bounds_fraction), "nees_in_bounds_fraction", 1.0, "");
  row("NEES mean (3 ideal)", e.ours.nees_mean, t(&TrackingMetrics::nees_mean), "", 1.0, "");
  row("init success rate", e.ours.init_success_rate, t(&TrackingMetrics::init_success_rate),
      "init_success_rate", 1.0, "");
  row("init frames, p95", e.ours.init_frames_p95, t(&TrackingMetrics::init_frames_p95), "", 1.0,
      "frames");
  out << "  init trials " << e.ours.init_trials << ", losses " << e.ours.losses
      << ", mean matched " << e.ours.mean_matched << " per frame\n";
}

void AddReference(nlohmann::json& j, TrackingReference reference, const TrackingMetrics& m,
                  double grid) {
  j["reference"] = Name(reference);
  j["grid_lateral_rmse_m"] = grid;
  j["plant_line_lateral_rmse_m"] = m.plant_line_lateral_rmse_m;
  j["plant_lines_scored"] = m.plant_lines_scored;
}

}  // namespace

nlohmann::json ToJson(const TrackingEvaluation& e) {
  nlohmann::json j = MetricsJson(e.ours);
  AddReference(j, e.reference, e.ours, e.grid_lateral_rmse_m);
  j["preset"] = e.preset;
  j["seeds"] = e.seeds;
  j["distance_m"] = e.distance_m;
  j["spacing_offset_m"] = e.spacing_offset_m;
  j["planter_spread"]["profile_m"] = e.planter_sd_profile_m;
  j["planter_spread"]["generator_m"] = e.planter_sd_generator_m;
  AddEngineJson(e.engine, j);
  j["visual_motion"] = e.visual_motion;
  j["camera_substitutions"] = e.ours.camera_substitutions;
  if (e.odometry_fault.kind != OdometryFaultKind::kNone) {
    nlohmann::json f = OdometryFaultJson(e.odometry_fault);
    f["frames"] = e.ours.fault_frames;
    f["frames_tracking"] = e.ours.fault_frames_tracking;
    f["losses"] = e.ours.fault_losses;
    f["lateral_rmse_m"] = e.ours.fault_lateral_rmse_m;
    f["forward_rmse_m"] = e.ours.fault_forward_rmse_m;
    j["odometry_fault"] = f;
  }
  if (e.thesis) {
    j["baseline_thesis"] = MetricsJson(*e.thesis);
    AddReference(j["baseline_thesis"], e.reference, *e.thesis, e.thesis_grid_lateral_rmse_m);
  }
  return j;
}

void WriteTable(const TrackingEvaluation& e, std::ostream& out) {
  PrintFigures(e, out);
  out << "  reference " << Name(e.reference)
      << (e.reference == TrackingReference::kPlantLines
              ? " (lateral scored at each line of plants against its mean root "
                "position, thesis §8.1; " + std::to_string(e.ours.plant_lines_scored) + " lines)"
              : " (the planted grid, every frame)")
      << '\n';
  if (e.odometry_fault.kind != OdometryFaultKind::kNone) {
    out << "  odometry fault " << Name(e.odometry_fault.kind) << " from "
        << e.odometry_fault.start_m << " m for " << e.odometry_fault.length_m
        << " m: " << e.ours.fault_frames_tracking << " of " << e.ours.fault_frames
        << " frames tracking, " << e.ours.fault_losses << " losses, lateral RMSE "
        << 1000.0 * e.ours.fault_lateral_rmse_m << " mm, forward RMSE "
        << 1000.0 * e.ours.fault_forward_rmse_m << " mm"
        << (e.visual_motion ? " (visual motion on)" : " (wheels only)") << '\n';
  }
  WriteEngineLine(e.engine, out);
}

nlohmann::json TrackingJsonShape() {
  TrackingEvaluation e;
  e.reference = TrackingReference::kPlantLines;
  e.odometry_fault.kind = OdometryFaultKind::kStop;
  e.thesis = TrackingMetrics{};
  return ToJson(e);
}

}  // namespace plantscale::app
