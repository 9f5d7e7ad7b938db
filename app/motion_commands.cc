#include "app/motion_commands.h"

#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "app/config_loader.h"
#include "app/motion_eval.h"
#include "app/segment_commands.h"

namespace plantscale::app {
namespace {

struct MotionArgs {
  std::string preset = "sanchiz_pla";
  int seeds = 3;
  int frames = 30;
  std::optional<int64_t> seed;
  std::string camera;
  std::optional<double> speed_m_s, frame_rate_hz, offset_m;
  bool json = false;
  std::string baseline;
  std::string prior = "image";
  std::string ground_shift = "soil";
  std::string soil_scale = "on";
  std::string camera_pitch = "soil";
};

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

// Ours at the top level (the keys the issue names), the paper's method
// under "baseline_paper", the published figures under "published".
nlohmann::json EvaluationJson(const MotionEvaluation& e) {
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

void PrintTable(const MotionEvaluation& e, bool with_paper, std::ostream& out) {
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

int EvaluateMotionCommand(const MotionArgs& a, const GlobalOptions& global) {
  MotionEvalOptions o;
  o.sim = LoadSimulatorPreset(a.preset, global.ConfigDir());
  if (a.seed) o.sim.seed = static_cast<uint64_t>(*a.seed);
  if (!a.camera.empty()) o.sim.camera = LoadCamera(a.camera, global.ConfigDir());
  if (a.speed_m_s) o.sim.vehicle.speed_m_s = *a.speed_m_s;
  if (a.frame_rate_hz) o.sim.vehicle.frame_rate_hz = *a.frame_rate_hz;
  if (a.offset_m) o.sim.vehicle.start_offset_m = *a.offset_m;
  o.seeds = a.seeds;
  o.frames = a.frames;
  o.paper = PaperMethod();
  o.ours = OursMethod(o.sim);
  for (const MotionPrior p : {MotionPrior::kNone, MotionPrior::kWheels, MotionPrior::kImage}) {
    if (a.prior == MotionPriorName(p)) o.prior = p;
  }
  if (a.ground_shift == "plants") o.ground_shift = motion::GroundShiftOptions{};
  o.soil_scale = a.soil_scale == "on";
  o.camera_pitch = a.camera_pitch == "soil";
  const MotionEvaluation e = EvaluateMotion(o);
  if (a.json) {
    std::cout << EvaluationJson(e).dump(2) << '\n';
  } else {
    PrintTable(e, a.baseline == "paper", std::cout);
  }
  return 0;
}

}  // namespace

void AddMotionCommands(CommandRegistry& registry) {
  const GlobalOptions& global = registry.global();
  MotionArgs& a = registry.Keep(MotionArgs{});
  CLI::App* cmd = registry.Add(
      "motion",
      "Sanchiz & Pla feature correspondence, motion without odometry and mosaic row fit",
      [&a, &global] { return EvaluateMotionCommand(a, global); }, EvaluateCommand(registry));
  AddRunOptions(cmd, a.preset, a.seeds, a.seed, nullptr, "number of sequences (seeds)");
  cmd->add_option("--frames", a.frames, "images per sequence")
      ->check(CLI::Range(2, 100000))->capture_default_str();
  cmd->add_option("--camera", a.camera,
                  "camera name or YAML file instead of the preset's (e.g. sanchiz_pla_90, the "
                  "paper's second set-up)");
  cmd->add_option("--speed-m-s", a.speed_m_s, "vehicle speed instead of the preset's")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--frame-rate-hz", a.frame_rate_hz, "frame rate instead of the preset's")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--offset-m", a.offset_m,
                  "drive this far right of the central row (a camera beside the rows)");
  cmd->add_flag("--json", a.json, "print one JSON object");
  cmd->add_option("--baseline", a.baseline, "paper: the published method beside ours")
      ->check(CLI::IsMember({"paper"}));
  cmd->add_option("--prior", a.prior,
                  "what ours searches each frame around: image (the ground's shift between the "
                  "two frames, phase-correlated on the ground: no odometry at all; where it reads "
                  "no clear shift, or the step is longer than its view can measure, as none), "
                  "none (the smoothed previous motion, no odometry at all) or wheels (the "
                  "simulated wheel odometry since the previous frame, as the vehicle's pipeline "
                  "does; the pose still composes the camera's motion only)")
      ->check(CLI::IsMember({"none", "wheels", "image"}))
      ->capture_default_str();
  cmd->add_option("--ground-shift", a.ground_shift,
                  "with --prior image, what is correlated: soil (the soil's texture on the "
                  "ground, the plants cut out: the ground's true scale) or plants (the plant "
                  "masks on the plane at plant height)")
      ->check(CLI::IsMember({"plants", "soil"}))
      ->capture_default_str();
  cmd->add_option("--soil-scale", a.soil_scale,
                  "with --prior image and the soil: on scales the features' locked translation "
                  "by the soil's distance over theirs (the features lie on the crop profile's "
                  "plane, the soil on the ground)")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  cmd->add_option("--camera-pitch", a.camera_pitch,
                  "with --prior wheels or image: soil places ours' features with the camera's "
                  "pitch from frame to frame, read off the soil view's near and far halves "
                  "(the bounce); off places them with the nominal camera")
      ->check(CLI::IsMember({"soil", "off"}))
      ->capture_default_str();
}

}  // namespace plantscale::app
