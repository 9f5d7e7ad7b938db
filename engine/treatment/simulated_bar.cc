#include "engine/treatment/simulated_bar.h"

#include <algorithm>
#include <cmath>

namespace plantscale::treatment {

Eigen::Vector2d VehicleToField(const FieldPose& pose, const Eigen::Vector2d& v) {
  const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
  return {pose.x_m + c * v.x() - s * v.y(), pose.y_m + s * v.x() + c * v.y()};
}

FieldPose Interpolate(std::span<const FieldPose> track, int64_t utime) {
  if (track.empty()) return {};
  if (utime <= track.front().utime) return track.front();
  if (utime >= track.back().utime) return track.back();
  const auto it = std::upper_bound(track.begin(), track.end(), utime,
                                   [](int64_t t, const FieldPose& p) { return t < p.utime; });
  const FieldPose& b = *it;
  const FieldPose& a = *(it - 1);
  const double f = static_cast<double>(utime - a.utime) / static_cast<double>(b.utime - a.utime);
  FieldPose p;
  p.utime = utime;
  p.x_m = a.x_m + f * (b.x_m - a.x_m);
  p.y_m = a.y_m + f * (b.y_m - a.y_m);
  p.heading_rad = a.heading_rad + f * std::remainder(b.heading_rad - a.heading_rad, 2 * M_PI);
  return p;
}

SimulatedBar::SimulatedBar(const SprayBarOptions& bar, double true_latency_s, double tick_s)
    : bar_(bar),
      latency_us_(std::llround(true_latency_s * 1e6)),
      tick_us_(std::max<int64_t>(1, std::llround(tick_s * 1e6))) {}

void SimulatedBar::Command(int64_t utime, uint64_t open_mask) {
  commands_.push_back({utime, open_mask});
}

std::vector<Shot> SimulatedBar::Shots(std::span<const FieldPose> track) const {
  std::vector<Shot> shots;
  if (commands_.empty()) return shots;
  const int64_t end = commands_.back().utime;
  for (int i = 0; i < bar_.nozzles; ++i) {
    const uint64_t bit = uint64_t{1} << i;
    int64_t opened = -1;
    for (size_t k = 0; k <= commands_.size(); ++k) {
      const bool on = k < commands_.size() && (commands_[k].mask & bit);
      const int64_t t = k < commands_.size() ? commands_[k].utime : end;
      if (on && opened < 0) opened = t;
      if (!on && opened >= 0) {
        Shot s;
        s.nozzle = i;
        s.open_utime = opened + latency_us_;
        s.close_utime = t + latency_us_;
        s.width_m = bar_.nozzle_spacing_m;
        const Eigen::Vector2d nozzle = bar_.Nozzle(i);
        for (int64_t u = s.open_utime;; u = std::min(u + tick_us_, s.close_utime)) {
          s.path_field_m.push_back(VehicleToField(Interpolate(track, u), nozzle));
          if (u >= s.close_utime) break;
        }
        shots.push_back(std::move(s));
        opened = -1;
      }
    }
  }
  return shots;
}

}  // namespace plantscale::treatment
