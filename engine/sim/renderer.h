#pragma once
// Renders what the camera sees of the simulated field, through the same
// CameraModel the engine uses to interpret images: a near-infrared-like grey
// image (thesis §2.3.1: plants bright, soil dark) or an RGB image, plus the
// crop/weed/soil label image and a per-plant instance image.
//
// Error sources (docs/simulator.md), each with a knob: soil texture and clods,
// stones, specular soil, an illumination gradient down the image (§2.3.4),
// a hard-edged vehicle shadow, plant shadows (with fractured leaves they
// split blobs), sensor noise, motion blur. Buffers are reused frame to frame.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/sim/field.h"
#include "engine/sim/vehicle.h"

namespace plantscale::sim {

enum class ImageKind { kNir, kRgb };

struct RenderOptions {
  ImageKind kind = ImageKind::kNir;
  double exposure = 1.0;           // overall gain
  double soil_reflectance = 0.26;  // NIR, relative to a white target
  double crop_reflectance = 0.72;
  double weed_reflectance = 0.66;
  double stone_reflectance = 0.42;
  double soil_texture_contrast = 0.22;  // clods and furrows, fraction of soil brightness
  double leaf_texture_contrast = 0.08;
  double illumination_gradient = 0.15;  // brightness change from top to bottom of the image
  double vehicle_shadow_depth = 0.0;    // 0: no shadow; 0.7: 70 % darker inside
  double vehicle_shadow_edge_m = 1.0;   // forward distance of the shadow edge (vehicle frame)
  double vehicle_shadow_slope = 0.15;   // edge slope dy/dx across the image
  double plant_shadow_depth = 0.0;      // darkening of soil under plant shadows
  double sun_azimuth_rad = 0.6;         // direction shadows fall (field frame, from +x, CCW)
  double sun_elevation_rad = 0.9;
  double specular_fraction = 0.0;  // fraction of soil that glints
  double specular_gain = 1.8;
  // Self-shadowed leaf area (inner leaves under outer ones, gaps between
  // overlapping leaves): this fraction of each plant's pixels is darkened by
  // leaf_shadow_depth. Real plants are not evenly bright (thesis table 2.2:
  // 17 % of plant pixels missed on sequences B and C).
  double leaf_shadow_fraction = 0.0;
  double leaf_shadow_depth = 0.5;
  double optical_blur_px = 0.0;  // Gaussian sigma of the lens and sensor, pixels
  double sensor_noise = 0.015;  // sd, fraction of full scale
  double max_range_m = 12.0;    // ground beyond this is not rendered (horizon haze)
  int ray_samples = 4;          // heights tested per plant ray
  int threads = 0;              // row bands rendered in parallel; 0: one per core (≤ 4).
                                // Output does not depend on it.

  OptionErrors Validate() const;
};

// One rendered plant, for the ground truth.
struct RenderedPlant {
  int plant_index = 0;  // index into Field::plants()
  int area_px = 0;      // visible pixels (after occlusion)
  Eigen::Vector2d centroid_px{0.0, 0.0};
};

struct RenderedFrame {
  cv::Mat image;      // CV_8UC1 (NIR) or CV_8UC3 (BGR)
  cv::Mat labels;     // CV_8UC1: PlantClass values
  cv::Mat instances;  // CV_16UC1: 0 soil, k = plants[k − 1]
  std::vector<RenderedPlant> plants;
};

class Renderer {
 public:
  Renderer(const RenderOptions& options, uint64_t seed);

  // Renders the field seen by `camera` (vehicle frame) on a vehicle at `pose`.
  // `speed_m_s`·`exposure_s` sets the motion blur; `frame_seed` the noise.
  void Render(const Field& field, const geometry::CameraModel& camera, const Pose2& pose,
              double speed_m_s, double exposure_s, uint64_t frame_seed, RenderedFrame& out);
  const RenderOptions& options() const { return options_; }

 private:
  struct View;
  void RenderGround(View& view);
  void SetGroundBounds(View& view) const;
  void RenderStones(const Field& field, const View& view);
  void RenderPlantShadows(const Field& field, const View& view);
  void RenderPlants(const Field& field, const View& view, RenderedFrame& out);
  void Compose(const View& view, uint64_t frame_seed, RenderedFrame& out);
  void Blur(const View& view, double blur_m, RenderedFrame& out);

  RenderOptions options_;
  int threads_ = 1;
  std::vector<float> soil_texture_;  // tileable value noise, kTexture²
  std::vector<float> leaf_texture_;
  float specular_threshold_ = 1e9F;     // soil texture level above which soil glints
  float leaf_shadow_threshold_ = 1e9F;  // leaf texture level above which a leaf is shaded
  std::vector<float> noise_table_;  // N(0, 1) samples
  cv::Mat shade_;                   // CV_32F brightness factor per pixel
  cv::Mat material_;                // CV_8U: 0 soil, 1 crop, 2 weed, 3 stone, 4 beyond range
  cv::Mat shadow_;                  // CV_8U: bit 1 plant shadow, bit 2 vehicle shadow
  std::vector<int> visible_;        // field plant indices drawn this frame
};

}  // namespace plantscale::sim
