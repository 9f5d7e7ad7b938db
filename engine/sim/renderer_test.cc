#include "engine/sim/renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "engine/geometry/camera_model.h"
#include "engine/geometry/test_cameras.h"
#include "engine/sim/plant_shape.h"

namespace plantscale::sim {
namespace {

constexpr double kPi = std::numbers::pi;

// config/cameras/thesis.yaml: 1.5 m up, 45° below the horizontal.
using geometry::testing::ThesisCamera;

geometry::CameraOptions StraightDownCamera() {
  geometry::CameraOptions o = ThesisCamera();
  o.tilt_rad = kPi / 2.0;
  return o;
}

// One round crop at field (0, y_m) with nothing else in the field: a single
// row, one plant line (the next line would be 20 m further on), no weeds,
// stones, jitter, lean, lobes or size and brightness variation.
FieldOptions SinglePlantOptions(double height_ratio) {
  FieldOptions o;
  o.rows = 1;
  o.plant_spacing_m = 20.0;
  o.spacing_drift_fraction = 0.0;
  o.planting_jitter_m = 0.0;
  o.missing_plant_fraction = 0.0;
  o.crop_radius_m = 0.11;
  o.crop_radius_sd_fraction = 0.0;
  o.crop_height_ratio = height_ratio;
  o.crop_lean_sd_m = 0.0;
  o.crop_lobes = 0;
  o.fractured_fraction = 0.0;
  o.weed_density_per_m2 = 0.0;
  o.stone_density_per_m2 = 0.0;
  o.plant_brightness_sd = 0.0;
  return o;
}

Field SinglePlantField(double y_m, double height_ratio) {
  Field field(SinglePlantOptions(height_ratio), y_m, y_m + 1.0, 5);
  EXPECT_EQ(field.plants().size(), 1U);
  return field;
}

struct PixelStats {
  int count = 0;
  Eigen::Vector2d centroid{0.0, 0.0};
};

PixelStats LabelStats(const cv::Mat& labels, PlantClass cls) {
  PixelStats s;
  for (int v = 0; v < labels.rows; ++v) {
    for (int u = 0; u < labels.cols; ++u) {
      if (labels.at<uint8_t>(v, u) != static_cast<uint8_t>(cls)) continue;
      ++s.count;
      s.centroid += Eigen::Vector2d(u + 0.5, v + 0.5);
    }
  }
  if (s.count > 0) s.centroid /= s.count;
  return s;
}

RenderedFrame RenderOnce(const Field& field, const geometry::CameraOptions& camera_options,
                         const Pose2& pose, const RenderOptions& options = {}, uint64_t seed = 3,
                         uint64_t frame_seed = 7) {
  Renderer renderer(options, seed);
  const geometry::CameraModel camera(camera_options);
  RenderedFrame frame;
  renderer.Render(field, camera, pose, 0.0, 0.0, frame_seed, frame);
  return frame;
}

TEST(Renderer, FlatPlantCentroidIsItsProjectionStraightDown) {
  const Field field = SinglePlantField(1.0, 0.0);
  const Pose2 pose{-0.2, 0.9, 0.1};  // plant ≈ 0.2 m right, 0.1 m ahead, rotated view
  const RenderedFrame frame = RenderOnce(field, StraightDownCamera(), pose);
  const geometry::CameraModel camera(StraightDownCamera());
  const Eigen::Vector2d p = FieldToVehicle(pose, field.plants()[0].position_m);
  const auto expected = camera.Project({p.x(), p.y(), 0.0});
  ASSERT_TRUE(expected.has_value());
  const PixelStats crop = LabelStats(frame.labels, PlantClass::kCrop);
  // A disc of radius 0.11 m seen from 1.5 m: an ellipse of semi-axes
  // f/dx·r/h ≈ 41 px and f/dy·r/h ≈ 42 px, ≈ 5500 px (±5 % for the pixel grid).
  const double radius_px = camera.fx() * 0.11 / 1.5;
  EXPECT_NEAR(crop.count, kPi * radius_px * radius_px * 8.6 / 8.3, 0.05 * crop.count);
  // Looking straight down at a flat disc the image is a scaled ellipse: its
  // centroid is the projection of the centre, up to pixel quantisation
  // (0.1 px).
  EXPECT_NEAR(crop.centroid.x(), expected->x(), 0.1);
  EXPECT_NEAR(crop.centroid.y(), expected->y(), 0.1);
  EXPECT_EQ(LabelStats(frame.labels, PlantClass::kWeed).count, 0);
}

// Exact image centroid of a ground disc: ∫ (u, v)·|det ∂(u, v)/∂(x, y)| over
// the disc on a 1 mm grid, divided by the disc's image area.
Eigen::Vector2d DiscImageCentroid(const geometry::CameraModel& camera,
                                  const Eigen::Vector2d& centre_m, double radius_m) {
  Eigen::Vector2d sum(0.0, 0.0);
  double area = 0.0;
  constexpr double kStep = 0.001;
  for (double dy = -radius_m + 0.5 * kStep; dy < radius_m; dy += kStep) {
    for (double dx = -radius_m + 0.5 * kStep; dx < radius_m; dx += kStep) {
      if (dx * dx + dy * dy > radius_m * radius_m) continue;
      const Eigen::Vector3d p(centre_m.x() + dx, centre_m.y() + dy, 0.0);
      const auto uv = camera.Project(p);
      if (!uv) continue;
      const Eigen::Matrix<double, 2, 3> j = camera.ProjectJacobian(p);
      const double w = std::abs(j(0, 0) * j(1, 1) - j(0, 1) * j(1, 0));
      sum += w * *uv;
      area += w;
    }
  }
  return sum / area;
}

TEST(Renderer, FlatPlantCentroidIsItsProjectionOblique) {
  const Field field = SinglePlantField(1.7, 0.0);
  const Pose2 pose{0.15, 0.0, -0.05};
  const RenderedFrame frame = RenderOnce(field, ThesisCamera(), pose);
  const geometry::CameraModel camera(ThesisCamera());
  const Eigen::Vector2d p = FieldToVehicle(pose, field.plants()[0].position_m);
  const auto expected = camera.Project({p.x(), p.y(), 0.0});
  ASSERT_TRUE(expected.has_value());
  ASSERT_TRUE(camera.InImage(*expected, 60.0));
  const PixelStats crop = LabelStats(frame.labels, PlantClass::kCrop);
  ASSERT_GT(crop.count, 1000);
  // Under perspective the image of a disc's centre is not the centroid of
  // its image: the near half looks bigger. The exact centroid, integrated
  // over the disc, matches the labelled pixels to 0.1 px (pixel grid) ...
  const Eigen::Vector2d exact = DiscImageCentroid(camera, p, 0.11);
  EXPECT_NEAR(crop.centroid.x(), exact.x(), 0.1);
  EXPECT_NEAR(crop.centroid.y(), exact.y(), 0.1);
  // ... and the projection of the centre to 1 px (the shift is (r/d)²-small
  // for a 0.11 m disc 2.3 m away: ≈ 0.65 px, mostly down the image).
  EXPECT_NEAR(crop.centroid.x(), expected->x(), 1.0);
  EXPECT_NEAR(crop.centroid.y(), expected->y(), 1.0);
}

TEST(Renderer, TallPlantCentroidLiesBetweenRootAndRimProjections) {
  // A bowl 0.088 m high: seen obliquely its top (the rim disc) appears
  // higher in the image than its root, and the near wall shows below it.
  const Field field = SinglePlantField(1.7, 0.8);
  const Pose2 pose{0.0, 0.0, 0.0};
  const RenderedFrame frame = RenderOnce(field, ThesisCamera(), pose);
  const geometry::CameraModel camera(ThesisCamera());
  const Plant& plant = field.plants()[0];
  ASSERT_NEAR(plant.height_m, 0.088, 1e-12);
  const auto root = camera.Project({0.0, 1.7, 0.0});
  const auto rim = camera.Project({0.0, 1.7, plant.height_m});
  ASSERT_TRUE(root && rim);
  ASSERT_LT(rim->y(), root->y() - 5.0);  // height matters by more than 5 px here
  const PixelStats crop = LabelStats(frame.labels, PlantClass::kCrop);
  ASSERT_GT(crop.count, 1000);
  // On the image's centre column by symmetry (0.1 px for the pixel grid).
  EXPECT_NEAR(crop.centroid.x(), root->x(), 0.1);
  // Between the rim centre's and the root's projections (margin 0.5 px),
  // and nearer the rim's: most of what is seen is the top.
  EXPECT_GT(crop.centroid.y(), rim->y() - 0.5);
  EXPECT_LT(crop.centroid.y(), root->y() + 0.5);
  EXPECT_LT(std::abs(crop.centroid.y() - rim->y()), std::abs(crop.centroid.y() - root->y()));
}

TEST(Renderer, PlantsAreBrighterThanSoilInNir) {
  const Field field = SinglePlantField(1.6, 0.8);
  const RenderedFrame frame = RenderOnce(field, ThesisCamera(), Pose2{});
  ASSERT_EQ(frame.image.type(), CV_8UC1);
  const cv::Mat plant_mask = frame.labels == static_cast<uint8_t>(PlantClass::kCrop);
  const cv::Mat soil_mask = frame.labels == static_cast<uint8_t>(PlantClass::kSoil);
  ASSERT_GT(cv::countNonZero(plant_mask), 1000);
  const double plant = cv::mean(frame.image, plant_mask)[0];
  const double soil = cv::mean(frame.image, soil_mask)[0];
  // Reflectances 0.72 (crop, shaded 0.78–1.08) against 0.26 (soil): about
  // 100 grey levels apart; require 60.
  EXPECT_GT(plant - soil, 60.0) << "plant " << plant << " soil " << soil;
}

TEST(Renderer, RgbPlantsShowExcessGreen) {
  FieldOptions o;  // crops and weeds
  o.weed_density_per_m2 = 20.0;
  const Field field(o, -2.0, 8.0, 9);
  RenderOptions render;
  render.kind = ImageKind::kRgb;
  const RenderedFrame frame = RenderOnce(field, ThesisCamera(), Pose2{}, render);
  ASSERT_EQ(frame.image.type(), CV_8UC3);
  cv::Mat bgr;
  frame.image.convertTo(bgr, CV_32FC3);
  std::vector<cv::Mat> ch;
  cv::split(bgr, ch);
  const cv::Mat exg = 2.0 * ch[1] - ch[2] - ch[0];
  const cv::Mat crop_mask = frame.labels == static_cast<uint8_t>(PlantClass::kCrop);
  const cv::Mat weed_mask = frame.labels == static_cast<uint8_t>(PlantClass::kWeed);
  const cv::Mat soil_mask = frame.labels == static_cast<uint8_t>(PlantClass::kSoil);
  ASSERT_GT(cv::countNonZero(crop_mask), 1000);
  ASSERT_GT(cv::countNonZero(weed_mask), 50);
  const double crop = cv::mean(exg, crop_mask)[0];
  const double weed = cv::mean(exg, weed_mask)[0];
  const double soil = cv::mean(exg, soil_mask)[0];
  // 2G − R − B: crop 0.75, weed 0.58, soil −0.02 (fractions of full scale,
  // before shading): require a 100-level margin for crops, 80 for weeds.
  EXPECT_GT(crop - soil, 100.0) << "crop " << crop << " soil " << soil;
  EXPECT_GT(weed - soil, 80.0) << "weed " << weed << " soil " << soil;
}

TEST(Renderer, LabelsAndInstancesAreConsistent) {
  FieldOptions o;  // crops, weeds, stones
  o.weed_density_per_m2 = 20.0;
  o.stone_density_per_m2 = 10.0;
  const Field field(o, -2.0, 10.0, 13);
  ASSERT_FALSE(field.stones().empty());
  const RenderedFrame frame = RenderOnce(field, ThesisCamera(), Pose2{0.05, 0.3, 0.02});
  ASSERT_EQ(frame.labels.type(), CV_8UC1);
  ASSERT_EQ(frame.instances.type(), CV_16UC1);
  ASSERT_EQ(frame.labels.size(), frame.image.size());
  ASSERT_EQ(frame.instances.size(), frame.image.size());
  std::map<int, int> label_counts;
  std::vector<int> instance_counts(frame.plants.size() + 1, 0);
  std::vector<Eigen::Vector2d> sums(frame.plants.size() + 1, Eigen::Vector2d::Zero());
  for (int v = 0; v < frame.labels.rows; ++v) {
    for (int u = 0; u < frame.labels.cols; ++u) {
      const int label = frame.labels.at<uint8_t>(v, u);
      const int instance = frame.instances.at<uint16_t>(v, u);
      ++label_counts[label];
      ASSERT_LE(static_cast<size_t>(instance), frame.plants.size()) << u << "," << v;
      ++instance_counts[static_cast<size_t>(instance)];
      sums[static_cast<size_t>(instance)] += Eigen::Vector2d(u + 0.5, v + 0.5);
      if (instance == 0) {
        EXPECT_EQ(label, 0) << u << "," << v;
      } else {
        const RenderedPlant& r = frame.plants[static_cast<size_t>(instance - 1)];
        const Plant& plant = field.plants()[static_cast<size_t>(r.plant_index)];
        EXPECT_EQ(label, static_cast<int>(plant.cls)) << u << "," << v;
      }
    }
  }
  // Labels only soil, crop, weed (stones are soil), and each of them present.
  for (const auto& [label, count] : label_counts) EXPECT_TRUE(label >= 0 && label <= 2) << label;
  EXPECT_GT(label_counts[0], 0);
  EXPECT_GT(label_counts[1], 0);
  EXPECT_GT(label_counts[2], 0);
  // Every rendered plant's area is its instance pixel count, its centroid
  // their mean (1e-9 px), and each field plant appears at most once.
  int visible = 0;
  std::vector<int> seen(field.plants().size(), 0);
  for (size_t k = 0; k < frame.plants.size(); ++k) {
    const RenderedPlant& r = frame.plants[k];
    ASSERT_GE(r.plant_index, 0);
    ASSERT_LT(static_cast<size_t>(r.plant_index), field.plants().size());
    EXPECT_EQ(++seen[static_cast<size_t>(r.plant_index)], 1);
    EXPECT_EQ(r.area_px, instance_counts[k + 1]) << "instance " << k + 1;
    if (r.area_px == 0) continue;
    ++visible;
    const Eigen::Vector2d mean = sums[k + 1] / r.area_px;
    EXPECT_NEAR(r.centroid_px.x(), mean.x(), 1e-9);
    EXPECT_NEAR(r.centroid_px.y(), mean.y(), 1e-9);
  }
  EXPECT_GT(visible, 10);
}

TEST(PlantShape, StraightDownRayHitsCentreAndMissesBeyondRadius) {
  Plant p;
  p.position_m = {0.3, 0.5};
  p.radius_m = 0.1;
  p.height_m = 0.08;
  p.lobes = 6;
  p.lobe_depth = 0.3;
  p.lobe_phase_rad = 0.4;
  const Eigen::Vector3d down(0.0, 0.0, -1.0);
  const PlantHit centre = IntersectPlant(p, {0.3, 0.5, 1.5}, down);
  ASSERT_TRUE(centre.hit);
  EXPECT_NEAR(centre.radial, 0.0, 1e-9);
  EXPECT_NEAR(centre.z_m, 0.08, 1e-12);  // the top of the bowl is its rim
  for (int k = 0; k < 16; ++k) {
    const double a = k * kPi / 8.0;
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    // Beyond the leaf tips (R) the ray misses, whatever the direction.
    const Eigen::Vector2d outside = p.position_m + 0.101 * dir;
    EXPECT_FALSE(IntersectPlant(p, {outside.x(), outside.y(), 1.5}, down).hit) << a;
    // Inside the deepest notch (R·(1 − depth) = 0.07 m) it hits.
    const Eigen::Vector2d inside = p.position_m + 0.069 * dir;
    const PlantHit hit = IntersectPlant(p, {inside.x(), inside.y(), 1.5}, down);
    EXPECT_TRUE(hit.hit) << a;
    EXPECT_GT(hit.radial, 0.69 - 1e-6);  // ρ/R(θ) ≥ 0.069/0.1
    EXPECT_LE(hit.radial, 1.0);
  }
}

TEST(PlantShape, TallPlantHidesTheGroundJustBeyondIt) {
  // A 45° ray from behind aimed at the ground 0.12 m beyond the root passes
  // 0.04 m from the axis at the rim height 0.08 m: a tall plant is hit, a
  // flat one (same outline) is not.
  Plant p;
  p.position_m = {0.0, 2.0};
  p.radius_m = 0.1;
  p.lobes = 0;
  const Eigen::Vector3d origin(0.0, 2.12 - 1.5, 1.5);
  const Eigen::Vector3d ray(0.0, 1.0, -1.0);
  p.height_m = 0.08;
  const PlantHit tall = IntersectPlant(p, origin, ray);
  EXPECT_TRUE(tall.hit);
  EXPECT_NEAR(tall.z_m, 0.08, 1e-12);
  EXPECT_NEAR(tall.radial, 0.4, 1e-9);  // 0.04 / 0.1
  p.height_m = 0.0;
  EXPECT_FALSE(IntersectPlant(p, origin, ray).hit);
  // Aimed at the root, both are hit.
  const Eigen::Vector3d at_root(0.0, 2.0 - 1.5, 1.5);
  EXPECT_TRUE(IntersectPlant(p, at_root, ray).hit);
  p.height_m = 0.08;
  EXPECT_TRUE(IntersectPlant(p, at_root, ray).hit);
}

TEST(Renderer, SameSeedSameBytes) {
  FieldOptions o;
  const Field field(o, -2.0, 8.0, 4);
  const Pose2 pose{0.02, 0.4, 0.03};
  RenderOptions render;
  render.plant_shadow_depth = 0.3;
  render.specular_fraction = 0.05;
  const RenderedFrame a = RenderOnce(field, ThesisCamera(), pose, render, 3, 7);
  const RenderedFrame b = RenderOnce(field, ThesisCamera(), pose, render, 3, 7);
  EXPECT_EQ(cv::norm(a.image, b.image, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.labels, b.labels, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.instances, b.instances, cv::NORM_INF), 0.0);
  ASSERT_EQ(a.plants.size(), b.plants.size());
  for (size_t k = 0; k < a.plants.size(); ++k) {
    EXPECT_EQ(a.plants[k].plant_index, b.plants[k].plant_index);
    EXPECT_EQ(a.plants[k].area_px, b.plants[k].area_px);
  }
  // Another frame seed changes the sensor noise only (sd 0.015 ≈ 4 levels);
  // another renderer seed changes the soil texture.
  const RenderedFrame c = RenderOnce(field, ThesisCamera(), pose, render, 3, 8);
  EXPECT_GT(cv::norm(a.image, c.image, cv::NORM_L1) / static_cast<double>(a.image.total()), 1.0);
  EXPECT_EQ(cv::norm(a.labels, c.labels, cv::NORM_INF), 0.0);
  const RenderedFrame d = RenderOnce(field, ThesisCamera(), pose, render, 4, 7);
  EXPECT_GT(cv::norm(a.image, d.image, cv::NORM_L1) / static_cast<double>(a.image.total()), 1.0);
  // A renderer reused for a second frame gives the same bytes as a fresh one.
  Renderer renderer(render, 3);
  const geometry::CameraModel camera(ThesisCamera());
  RenderedFrame reused;
  renderer.Render(field, camera, Pose2{0.0, 2.0, 0.0}, 0.0, 0.0, 1, reused);
  renderer.Render(field, camera, pose, 0.0, 0.0, 7, reused);
  EXPECT_EQ(cv::norm(a.image, reused.image, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.instances, reused.instances, cv::NORM_INF), 0.0);
}

TEST(Renderer, OutputDoesNotDependOnTheThreadCount) {
  FieldOptions o;
  o.fractured_fraction = 0.3;
  const Field field(o, -2.0, 8.0, 4);
  const Pose2 pose{-0.03, 0.2, -0.02};
  RenderOptions render;
  render.plant_shadow_depth = 0.3;
  render.vehicle_shadow_depth = 0.4;
  for (ImageKind kind : {ImageKind::kNir, ImageKind::kRgb}) {
    render.kind = kind;
    render.threads = 1;
    const RenderedFrame one = RenderOnce(field, ThesisCamera(), pose, render);
    render.threads = 3;  // bands that do not divide 480 rows evenly
    const RenderedFrame three = RenderOnce(field, ThesisCamera(), pose, render);
    EXPECT_EQ(cv::norm(one.image, three.image, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(one.labels, three.labels, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(one.instances, three.instances, cv::NORM_INF), 0.0);
    ASSERT_EQ(one.plants.size(), three.plants.size());
    for (size_t k = 0; k < one.plants.size(); ++k) {
      EXPECT_EQ(one.plants[k].plant_index, three.plants[k].plant_index);
      EXPECT_EQ(one.plants[k].area_px, three.plants[k].area_px);
    }
  }
}

TEST(Renderer, VehicleShadowDarkensTheBottomRows) {
  FieldOptions o = SinglePlantOptions(0.0);  // bare soil in view (plant far ahead)
  const Field field(o, 30.0, 31.0, 2);
  RenderOptions lit;
  RenderOptions shaded;
  shaded.vehicle_shadow_depth = 0.5;
  // The shadow edge is 1.0 m ahead (±0.15 m across the image); the bottom
  // rows see the ground 0.62–0.7 m ahead, the top rows 3.6 m ahead.
  const RenderedFrame a = RenderOnce(field, ThesisCamera(), Pose2{}, lit);
  const RenderedFrame b = RenderOnce(field, ThesisCamera(), Pose2{}, shaded);
  const cv::Rect bottom(0, 460, 640, 20);
  const cv::Rect top(0, 0, 640, 200);
  const double lit_bottom = cv::mean(a.image(bottom))[0];
  const double shaded_bottom = cv::mean(b.image(bottom))[0];
  // 50 % darker, within 0.01 (rounding to whole grey levels of ≈ 35–70).
  EXPECT_NEAR(shaded_bottom / lit_bottom, 0.5, 0.01);
  EXPECT_GT(lit_bottom, 40.0);  // soil at 0.26 reflectance, not black
  // Beyond the edge nothing changes, byte for byte.
  EXPECT_EQ(cv::norm(a.image(top), b.image(top), cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace plantscale::sim
