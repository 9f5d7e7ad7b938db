#include "app/motion_commands.h"

#include <iostream>
#include <optional>

#include "app/config/config_loader.h"
#include "app/segment_commands.h"
#include "evaluation/motion_eval.h"
#include "evaluation/motion_writer.h"
#include "evaluation/writer.h"

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
  o.paper_in_table = a.baseline == "paper";
  WriteEvaluation(EvaluateMotion(o), a.json, std::cout);
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
