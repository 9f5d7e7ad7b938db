#include "engine/treatment/nozzle_scheduler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace plantscale::treatment {

const char* ToString(SprayMode mode) { return mode == SprayMode::kCrop ? "crop" : "weed"; }

bool ParseSprayMode(const std::string& name, SprayMode& mode) {
  if (name == "crop") mode = SprayMode::kCrop;
  else if (name == "weed") mode = SprayMode::kWeed;
  else return false;
  return true;
}

OptionErrors SprayBarOptions::Validate() const {
  OptionErrors e;
  if (nozzles < 1 || nozzles > 64) e.push_back({"nozzles", "must be in [1, 64]"});
  RequireInRange(e, "nozzle_spacing_m", nozzle_spacing_m, 0.001, 1.0);
  RequireInRange(e, "bar_offset_m", bar_offset_m, -5.0, 5.0);
  RequireInRange(e, "centre_x_m", centre_x_m, -5.0, 5.0);
  RequireInRange(e, "valve_latency_s", valve_latency_s, 0.0, 1.0);
  return e;
}

Eigen::Vector2d SprayBarOptions::Nozzle(int i) const {
  return {centre_x_m + (i - 0.5 * (nozzles - 1)) * nozzle_spacing_m, -bar_offset_m};
}

OptionErrors FailSafeOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "max_pose_age_s", max_pose_age_s);
  RequirePositive(e, "max_frame_age_s", max_frame_age_s);
  // Positive; infinity (never) is allowed.
  for (const auto& [key, value] : {std::pair{"max_reach_across_m", max_reach_across_m},
                                   std::pair{"max_reach_along_m", max_reach_along_m}}) {
    if (!(value > 0.0)) e.push_back({key, "must be > 0 (infinite: never close on uncertainty)"});
  }
  return e;
}

OptionErrors SchedulerOptions::Validate() const {
  OptionErrors e = Prefixed("bar", bar.Validate());
  for (OptionError& x : Prefixed("fail_safe", fail_safe.Validate())) e.push_back(x);
  RequireInRange(e, "tick_s", tick_s, 0.001, 1.0);
  RequireInRange(e, "pose_period_s", pose_period_s, 0.001, 1.0);
  if (tick_s > pose_period_s) e.push_back({"tick_s", "must be at most pose_period_s"});
  return e;
}

int SchedulerOptions::TicksPerPose() const {
  return std::max(1, static_cast<int>(std::lround(pose_period_s / tick_s)));
}

namespace {

std::string Milliseconds(double s) {
  std::ostringstream out;
  out << std::lround(s * 1000.0) << " ms";
  return out.str();
}

std::string Millimetres(double m) {
  std::ostringstream out;
  out << std::lround(m * 1000.0) << " mm";
  return out.str();
}

}  // namespace

uint32_t CheckFailSafe(int64_t now, const SafetyInputs& in, const FailSafeOptions& o,
                       std::vector<std::string>* messages) {
  uint32_t reasons = 0;
  const auto say = [&](uint32_t bit, const std::string& text) {
    reasons |= bit;
    if (messages) messages->push_back(text);
  };
  const double pose_age = in.pose_utime < 0 ? std::numeric_limits<double>::infinity() : (now - in.pose_utime) * 1e-6;
  if (!(pose_age <= o.max_pose_age_s)) {
    say(kPoseStale, in.pose_utime < 0 ? "pose stale (no pose yet)"
                                      : "pose stale (" + Milliseconds(pose_age) + " > " +
                                            Milliseconds(o.max_pose_age_s) + ")");
  }
  const double frame_age = in.last_frame_utime < 0 ? std::numeric_limits<double>::infinity() : (now - in.last_frame_utime) * 1e-6;
  if (!in.camera_ok) {
    say(kCameraLost, "camera lost (source reports a fault)");
  } else if (!(frame_age <= o.max_frame_age_s)) {
    say(kCameraLost, in.last_frame_utime < 0 ? "camera lost (no frame yet)"
                                             : "camera lost (no frame for " +
                                                   Milliseconds(frame_age) + " > " +
                                                   Milliseconds(o.max_frame_age_s) + ")");
  }
  if (!in.odometry_valid) say(kOdometryInvalid, "odometry invalid (last sample refused)");
  if (!in.tracking) say(kTrackerLost, "tracker has lost the grid");
  if (in.held) say(kOperatorHold, "held by the operator (paused or spraying off)");
  const bool across = in.reach_across_m > o.max_reach_across_m;
  const bool along = in.reach_along_m > o.max_reach_along_m;
  if (in.tracking && (across || along)) {
    say(kPositionUncertain,
        "plant position uncertain at the bar (95 % ellipse reaches " +
            (across ? Millimetres(in.reach_across_m) + " across > " + Millimetres(o.max_reach_across_m)
                    : Millimetres(in.reach_along_m) + " along > " + Millimetres(o.max_reach_along_m)) +
            ")");
  }
  return reasons;
}

std::vector<std::string> FailReasonMessages(uint32_t reasons) {
  std::vector<std::string> out;
  if (reasons & kPoseStale) out.emplace_back("pose stale");
  if (reasons & kCameraLost) out.emplace_back("camera lost");
  if (reasons & kOdometryInvalid) out.emplace_back("odometry invalid");
  if (reasons & kTrackerLost) out.emplace_back("tracker lost");
  if (reasons & kOperatorHold) out.emplace_back("held by the operator");
  if (reasons & kPositionUncertain) out.emplace_back("plant position uncertain");
  return out;
}

NozzleScheduler::NozzleScheduler(const SchedulerOptions& options, NozzleSink sink)
    : options_(options), sink_(std::move(sink)) {
  ThrowIfInvalid("nozzle scheduler", options_.Validate());
}

NozzleTarget NozzleScheduler::Target(int i, const BedPose& pose, int64_t now) const {
  const SprayBarOptions& bar = options_.bar;
  // Where the nozzle will be when the valve has opened: led by the time
  // since the pose and the latency at the forward speed (the vehicle frame
  // moves along its own y).
  const double since_pose_s = std::max<int64_t>(0, now - pose.utime) * 1e-6;
  Eigen::Vector2d v = bar.Nozzle(i);
  v.y() += pose.speed_m_s * (since_pose_s + bar.valve_latency_s);
  const Eigen::Vector2d start = VehicleToBed(pose, v);
  const double travel = pose.speed_m_s * options_.tick_s;
  NozzleTarget t;
  t.nozzle = i;
  t.x0 = start.x() - 0.5 * bar.nozzle_spacing_m;
  t.x1 = start.x() + 0.5 * bar.nozzle_spacing_m;
  t.y0 = std::min(start.y(), start.y() + travel);
  t.y1 = std::max(start.y(), start.y() + travel);
  return t;
}

TickResult NozzleScheduler::Tick(int64_t now, const BedPose& pose, const TreatmentMap& map,
                                 const SafetyInputs& safety) {
  TickResult r;
  r.utime = now;
  r.fail_reasons = CheckFailSafe(now, safety, options_.fail_safe, &r.messages);
  if (r.fail_reasons == 0) {
    const CellClass treated =
        options_.mode == SprayMode::kCrop ? CellClass::kCrop : CellClass::kWeed;
    for (int i = 0; i < options_.bar.nozzles; ++i) {
      const NozzleTarget t = Target(i, pose, now);
      if (!map.AnyIn(t.x0, t.x1, t.y0, t.y1, treated)) continue;
      r.open_mask |= uint64_t{1} << i;
      r.opened.push_back(t);
    }
  }
  if (sink_) sink_(now, r.open_mask);
  return r;
}

}  // namespace plantscale::treatment
