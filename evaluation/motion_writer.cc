#include "evaluation/motion_writer.h"

#include <iomanip>

namespace plantscale::app {
namespace {

nlohmann::json MethodJson(const MotionMethodEvaluation& m) {
  return {{"method", m.method},
          {"correct_correspondence_rate", m.correct_correspondence_rate},
          {"matches", m.matches},
          {"correct_matches", m.correct_matches},
          {"matches_on_ground", m.matches_on_ground},
          {"pairs", m.pairs},
          {"locked_pairs", m.locked_pairs},
          {"rotation_rmse_deg", m.rotation_rmse_deg},
          {"translation_rmse_m", m.translation_rmse_m},
          {"drift_cm_per_m", m.drift_cm_per_m},
          {"drift_along_cm_per_m", m.drift_along_cm_per_m},
          {"drift_across_cm_per_m", m.drift_across_cm_per_m},
          {"rows_fitted", m.rows_fitted},
          {"row_fit_rms_m", m.row_fit_rms_m},
          {"row_angle_deg", m.row_angle_deg},
          {"row_spacing_m", m.row_spacing_m},
          {"row_rms_m", m.row_rms_m},
          {"row_spacings_m", m.row_spacings_m},
          {"ms_per_frame", m.ms_per_frame},
          {"prior_valid_pairs", m.prior_valid_pairs},
          {"prior_translation_rmse_m", m.prior_translation_rmse_m},
          {"prior_turn_pairs", m.prior_turn_pairs},
          {"prior_rotation_rmse_deg", m.prior_rotation_rmse_deg},
          {"soil_scale", m.soil_scale}};
}

}  // namespace

nlohmann::json ToJson(const MotionEvaluation& e) {
  nlohmann::json j = MethodJson(e.ours);
  j["preset"] = e.preset;
  j["seeds"] = e.seeds;
  j["frames"] = e.frames;
  j["distance_m"] = e.distance_m;
  j["true_row_spacing_m"] = e.true_row_spacing_m;
  j["prior"] = MotionPriorName(e.prior);
  if (e.prior == MotionPrior::kImage) {
    j["ground_shift"] = e.ground_shift_source == motion::GroundShiftSource::kSoil ? "soil" : "plants";
    j["soil_scale_applied"] = e.soil_scale;
  }
  j["camera_pitch_applied"] = e.camera_pitch;
  j["baseline_paper"] = MethodJson(e.paper);
  j["published"] = {{"correct_correspondence_rate_min", 0.95},
                    {"row_fit_rms_m", {0.0327, 0.0272, 0.0086}},
                    {"row_angle_deg", {0.42, 0.54}},
                    {"row_spacing_m", {0.4132, 0.4083}},
                    {"true_row_spacing_m", 0.4}};
  return j;
}

void WriteTable(const MotionEvaluation& e, std::ostream& out) {
  const bool with_paper = e.paper_in_table;
  const auto row = [&](const char* name, double ours, double paper, const char* published) {
    out << "  " << std::left << std::setw(30) << name << std::right << std::setw(10) << ours;
    if (with_paper) out << std::setw(12) << paper;
    out << "   " << published << '\n';
  };
  out << std::fixed << std::setprecision(4) << "motion on preset " << e.preset << " (" << e.seeds
      << " seeds x " << e.frames << " frames, " << std::setprecision(2) << e.distance_m
      << " m per sequence, prior " << MotionPriorName(e.prior) << ")\n"
      << std::setprecision(4) << "  " << std::left << std::setw(30) << "figure" << std::right
      << std::setw(10) << "ours";
  if (with_paper) out << std::setw(12) << "paper's m.";
  out << "   Sanchiz & Pla 1999, published\n";
  const MotionMethodEvaluation &o = e.ours, &p = e.paper;
  row("correct correspondences", o.correct_correspondence_rate, p.correct_correspondence_rate,
      "> 0.95 over 30 images");
  row("locked pairs", o.locked_pairs, p.locked_pairs, "-");
  row("rotation RMSE (deg)", o.rotation_rmse_deg, p.rotation_rmse_deg, "-");
  row("translation RMSE (m)", o.translation_rmse_m, p.translation_rmse_m, "-");
  row("drift (cm/m)", o.drift_cm_per_m, p.drift_cm_per_m, "-");
  row("  of it along, signed", o.drift_along_cm_per_m, p.drift_along_cm_per_m, "-");
  row("  of it across, signed", o.drift_across_cm_per_m, p.drift_across_cm_per_m, "-");
  row("row-fit RMS (m)", o.row_fit_rms_m, p.row_fit_rms_m, "0.0327, 0.0272, 0.0086");
  row("angle between rows (deg)", o.row_angle_deg, p.row_angle_deg, "0.42, 0.54");
  row("row spacing (m)", o.row_spacing_m, p.row_spacing_m, "0.4132, 0.4083");
  row("true row spacing (m)", e.true_row_spacing_m, e.true_row_spacing_m, "0.400");
  row("rows fitted", o.rows_fitted, p.rows_fitted, "3");
  row("ms per frame (corr. + motion)", o.ms_per_frame, p.ms_per_frame, "-");
}

}  // namespace plantscale::app
