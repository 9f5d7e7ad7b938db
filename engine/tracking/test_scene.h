#pragma once
// A synthetic crop grid for the tracker tests: features exactly where the
// truth grid puts its plants (plus a fixed per-plant offset and per-frame
// noise), seen through the thesis camera while the vehicle drives.

#include <cmath>
#include <random>
#include <vector>

#include "engine/geometry/grid_model.h"
#include "engine/geometry/test_cameras.h"
#include "engine/tracking/feature.h"
#include "engine/tracking/motion_model.h"

namespace plantscale::tracking::testing {

struct TestScene {
  geometry::CameraModel camera{geometry::testing::ThesisCamera()};
  geometry::GridModel model{camera, geometry::GridModelOptions{}};
  geometry::GridState truth{0.02, 0.3, 0.02, 0.475, 0.45};
  double plant_offset_sd_m = 0.01;
  double noise_sd_m = 0.004;
  int weeds_per_frame = 0;
  double plant_area_m2 = 0.03;
  // One plant (absolute line, row) whose blob has this area instead (0: none).
  int big_line = 0, big_row = 0;
  double big_area_m2 = 0.0;
  std::mt19937 rng{7};
  int lines_passed = 0;

  // Features of the plants in view of the truth grid.
  std::vector<Feature> Features() {
    std::vector<Feature> out;
    std::normal_distribution<double> noise(0.0, noise_sd_m);
    for (const auto& g : model.PlantsInView(truth)) {
      // The plant's own offset: fixed for its absolute line and row.
      std::mt19937 plant_rng(static_cast<unsigned>(1000 * (g.m + lines_passed) + g.n + 5000));
      std::normal_distribution<double> offset(0.0, plant_offset_sd_m);
      const Eigen::Vector2d d(offset(plant_rng), offset(plant_rng));
      const double c = std::cos(truth.bearing_rad);
      const double s = std::sin(truth.bearing_rad);
      Feature f;
      f.ground_m = g.ground_m + Eigen::Vector2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y()) +
                   Eigen::Vector2d(noise(rng), noise(rng));
      const auto uv = camera.Project({f.ground_m.x(), f.ground_m.y(), 0.0});
      if (!uv || !camera.InImage(*uv, 2.0)) continue;
      f.image_px = *uv;
      f.area_m2 = big_area_m2 > 0.0 && g.m + lines_passed == big_line && g.n == big_row
                      ? big_area_m2
                      : plant_area_m2;
      out.push_back(f);
    }
    std::uniform_real_distribution<double> x(-0.8, 0.8);
    std::uniform_real_distribution<double> y(0.6, 3.0);
    for (int i = 0; i < weeds_per_frame; ++i) {
      Feature f;
      f.ground_m = {x(rng), y(rng)};
      const auto uv = camera.Project({f.ground_m.x(), f.ground_m.y(), 0.0});
      if (!uv || !camera.InImage(*uv, 2.0)) continue;
      f.image_px = *uv;
      f.area_m2 = 0.002;
      out.push_back(f);
    }
    return out;
  }

  // Drives the truth by a wheel increment and keeps line 0 in view.
  void Drive(const WheelIncrement& u, double track_width_m = 1.5) {
    truth = PredictGridMotion(truth, u, track_width_m).state;
    lines_passed += model.ShiftReference(truth);
  }
};

}  // namespace plantscale::tracking::testing
