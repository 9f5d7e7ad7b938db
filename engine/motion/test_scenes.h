#pragma once
// Synthetic scenes for the motion tests and benchmark: the Sanchiz & Pla
// first camera, a scatter of ground feature points with characteristics,
// and a vehicle driving forward with a slow turn.

#include <Eigen/Core>
#include <cmath>
#include <random>
#include <vector>

#include "engine/geometry/camera_model.h"
#include "engine/motion/features.h"
#include "engine/motion/planar_motion.h"

namespace plantscale::motion::testing {

// Sanchiz & Pla §5 first set-up (config/cameras/sanchiz_pla_66.yaml).
inline geometry::CameraOptions SanchizPlaCamera() {
  geometry::CameraOptions o;
  o.height_m = 1.2;
  o.tilt_rad = 66.0 * M_PI / 180.0;
  o.focal_length_m = 0.040;
  o.pixel_width_m = o.pixel_height_m = 16.7e-6;
  o.image_width_px = 768;
  o.image_height_px = 576;
  return o;
}

struct ScenePoint {
  Eigen::Vector2d world_m;
  double convexity_rad, orientation_rad;
};

// Points over x ∈ [−0.4, 0.4], y ∈ [0, length], `per_m2` of them per m².
inline std::vector<ScenePoint> ScatterPoints(double length_m, double per_m2, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-0.4, 0.4), y(0.0, length_m), angle(-M_PI, M_PI);
  std::vector<ScenePoint> points(static_cast<size_t>(per_m2 * 0.8 * length_m));
  for (auto& p : points) p = {{x(rng), y(rng)}, angle(rng) / 2.0, angle(rng)};
  return points;
}

// Features of the points the camera sees from `pose` (world = first frame),
// with Gaussian position noise; `ids` receives the index of each point.
inline std::vector<Feature> Observe(const std::vector<ScenePoint>& points, const VehiclePose2& pose,
                                    const geometry::CameraModel& camera, double noise_m,
                                    std::mt19937& rng, std::vector<int>* ids = nullptr) {
  std::normal_distribution<double> noise(0.0, noise_m);
  std::vector<Feature> out;
  if (ids) ids->clear();
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d p = pose.FromWorld(points[i].world_m);
    const auto uv = camera.Project({p.x(), p.y(), 0.0});
    if (!uv || !camera.InImage(*uv, 8.0)) continue;
    Feature f;
    f.position_m = p + Eigen::Vector2d(noise(rng), noise(rng));
    f.convexity_rad = points[i].convexity_rad;
    f.orientation_rad = points[i].orientation_rad;
    f.pixel = *uv;
    out.push_back(f);
    if (ids) ids->push_back(static_cast<int>(i));
  }
  return out;
}

}  // namespace plantscale::motion::testing
