#include "engine/pipeline/motion_fusion.h"

#include <algorithm>
#include <cmath>

namespace plantscale::pipeline {

OptionErrors MotionFusionOptions::Validate() const {
  OptionErrors e;
  if (enabled) e = Prefixed("visual", visual.Validate());
  RequirePositive(e, "max_visual_age_s", max_visual_age_s);
  RequirePositive(e, "gate_chi2", gate_chi2);
  RequirePositive(e, "wheel_sd_fraction", wheel_sd_fraction);
  RequirePositive(e, "min_wheel_sd_m_s", min_wheel_sd_m_s);
  RequirePositive(e, "substitute_after_s", substitute_after_s);
  RequirePositive(e, "scale_memory_m", scale_memory_m);
  RequirePositive(e, "scale_min_distance_m", scale_min_distance_m);
  RequireInRange(e, "scale_bound", scale_bound, 0.0, 1.0, false, false);
  RequireInRange(e, "persistence_frames", persistence_frames, 2,
                 PersistentDisagreement::kMaxFrames);
  RequirePositive(e, "persistence_z", persistence_z);
  return e;
}

PlanarSpeed Scaled(const PlanarSpeed& s, double scale) {
  PlanarSpeed out = s;
  out.speed_m_s *= scale;
  out.speed_sd_m_s *= scale;
  return out;
}

void VisualScale::Add(double wheel_speed_m_s, double camera_speed_m_s, double dt_s) {
  if (!std::isfinite(wheel_speed_m_s) || !std::isfinite(camera_speed_m_s) || !(dt_s > 0.0)) return;
  const double w = std::abs(wheel_speed_m_s) * dt_s, c = std::abs(camera_speed_m_s) * dt_s;
  const double keep = std::exp(-w / options_.scale_memory_m);
  wheel_m_ = keep * wheel_m_ + w;
  camera_m_ = keep * camera_m_ + c;
}

bool VisualScale::learnt() const {
  return camera_m_ >= options_.scale_min_distance_m && wheel_m_ > 0.0;
}

double VisualScale::ratio() const {
  if (!learnt()) return 1.0;
  return std::clamp(wheel_m_ / camera_m_, 1.0 - options_.scale_bound, 1.0 + options_.scale_bound);
}

void PersistentDisagreement::Add(int64_t camera_utime, const PlanarSpeed& wheels,
                                 const PlanarSpeed& camera) {
  if (camera_utime == last_utime_) return;
  const double d = wheels.speed_m_s - camera.speed_m_s;
  const double var = wheels.speed_sd_m_s * wheels.speed_sd_m_s +
                     camera.speed_sd_m_s * camera.speed_sd_m_s;
  if (!std::isfinite(d) || !(var > 0.0)) return;
  last_utime_ = camera_utime;
  difference_[next_] = d;
  variance_[next_] = var;
  next_ = (next_ + 1) % options_.persistence_frames;
  count_ = std::min(count_ + 1, options_.persistence_frames);
}

double PersistentDisagreement::z() const {
  if (count_ < options_.persistence_frames) return 0.0;
  double sum = 0.0, var = 0.0;
  for (int i = 0; i < count_; ++i) {
    sum += difference_[i];
    var += variance_[i];
  }
  return sum / std::sqrt(var);
}

PlanarSpeed PersistentDisagreement::Corrected(const PlanarSpeed& wheels) const {
  if (count_ == 0) return wheels;
  double sum = 0.0, var = 0.0;
  for (int i = 0; i < count_; ++i) {
    sum += difference_[i];
    var += variance_[i];
  }
  PlanarSpeed out = wheels;
  out.speed_m_s -= sum / count_;
  out.speed_sd_m_s = std::hypot(wheels.speed_sd_m_s, std::sqrt(var) / count_);
  return out;
}

PlanarSpeed WheelSpeed(double left_m_s, double right_m_s, double scale, double track_width_m,
                       const MotionFusionOptions& options) {
  const double l = scale * left_m_s, r = scale * right_m_s;
  const double sl = std::max(options.min_wheel_sd_m_s, options.wheel_sd_fraction * std::abs(l));
  const double sr = std::max(options.min_wheel_sd_m_s, options.wheel_sd_fraction * std::abs(r));
  PlanarSpeed s;
  s.speed_m_s = 0.5 * (l + r);
  s.yaw_rate_rad_s = (r - l) / track_width_m;
  s.speed_sd_m_s = 0.5 * std::hypot(sl, sr);
  s.yaw_rate_sd_rad_s = std::hypot(sl, sr) / track_width_m;
  return s;
}

PlanarSpeed VisualSpeed(const motion::VisualMotion& v) {
  return {v.speed_m_s, v.yaw_rate_rad_s, v.speed_sd_m_s, v.yaw_rate_sd_rad_s};
}

const char* Name(FusedSource source) {
  switch (source) {
    case FusedSource::kWheels: return "wheels";
    case FusedSource::kFused: return "wheels and camera";
    case FusedSource::kCamera: return "camera";
  }
  return "?";
}

namespace {

// Precision-weighted mean of a and b with σ sa, sb; its σ in `sd`.
double Weighted(double a, double sa, double b, double sb, double& sd) {
  const double wa = 1.0 / (sa * sa), wb = 1.0 / (sb * sb);
  sd = 1.0 / std::sqrt(wa + wb);
  return (wa * a + wb * b) / (wa + wb);
}

}  // namespace

FusedSpeed Fuse(const PlanarSpeed& wheels, const PlanarSpeed* visual, double gate_chi2) {
  FusedSpeed out{wheels, FusedSource::kWheels, 0.0};
  if (visual == nullptr) return out;
  const double dv = wheels.speed_m_s - visual->speed_m_s;
  const double dw = wheels.yaw_rate_rad_s - visual->yaw_rate_rad_s;
  out.chi2 = dv * dv / (std::pow(wheels.speed_sd_m_s, 2) + std::pow(visual->speed_sd_m_s, 2)) +
             dw * dw / (std::pow(wheels.yaw_rate_sd_rad_s, 2) +
                        std::pow(visual->yaw_rate_sd_rad_s, 2));
  if (out.chi2 > gate_chi2) {
    out.speed = *visual;
    out.source = FusedSource::kCamera;
    return out;
  }
  out.source = FusedSource::kFused;
  out.speed.speed_m_s = Weighted(wheels.speed_m_s, wheels.speed_sd_m_s, visual->speed_m_s,
                                 visual->speed_sd_m_s, out.speed.speed_sd_m_s);
  out.speed.yaw_rate_rad_s =
      Weighted(wheels.yaw_rate_rad_s, wheels.yaw_rate_sd_rad_s, visual->yaw_rate_rad_s,
               visual->yaw_rate_sd_rad_s, out.speed.yaw_rate_sd_rad_s);
  return out;
}

void ToWheels(const PlanarSpeed& s, double scale, double track_width_m, double& left_m_s,
              double& right_m_s) {
  left_m_s = (s.speed_m_s - 0.5 * track_width_m * s.yaw_rate_rad_s) / scale;
  right_m_s = (s.speed_m_s + 0.5 * track_width_m * s.yaw_rate_rad_s) / scale;
}

double WheelSdFraction(const PlanarSpeed& s, double track_width_m) {
  const double wheel = std::hypot(s.speed_sd_m_s, 0.5 * track_width_m * s.yaw_rate_sd_rad_s);
  return wheel / std::max(0.1, std::abs(s.speed_m_s));
}

}  // namespace plantscale::pipeline
