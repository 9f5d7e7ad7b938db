#pragma once
// Feature points: dominant points of plant contours on the feature plane,
// with the two characteristics Sanchiz & Pla use for similarity (§5, fig. 7):
// convexity α and orientation β at the point.
//
// The paper finds dominant points with a trained network over the chain
// code; we use the same output shape (a relevance signal along the contour,
// thresholded, one point per segment over the threshold) with a geometric
// relevance: the sharpness 180° − |α| measured with short arms.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <span>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/vision/blobs.h"

namespace plantscale::motion {

struct FeatureOptions {
  double plane_height_m = 0.0;          // crop feature plane above the soil (0: the paper's ground)
  double min_plant_area_m2 = 0.004;     // blobs smaller than this are weeds
  bool weed_features = true;            // features on weed blobs too (else crop only, §5)
  double weed_plane_height_m = 0.0;     // their plane (weeds are low)
  // When > 0, each blob's plane is its own height: this ratio times the
  // radius of a disc of the blob's ground area (plants are bowls whose
  // height grows with their size); overrides the fixed heights above.
  double crop_height_per_radius = 0.0;
  double weed_height_per_radius = 0.0;
  double detection_arm_m = 0.02;        // arm of the relevance (sharpness) measure
  double min_sharpness_rad = 0.9;       // relevance threshold: 180° − |α| above this
  double characteristic_arm_fraction = 0.10;  // arm of α and β: fraction of the contour length
  int border_margin_px = 3;             // contour points this close to the image edge are cut edges
  int max_features_per_blob = 24;

  OptionErrors Validate() const;
};

struct Feature {
  Eigen::Vector2d position_m{0.0, 0.0};  // feature plane, vehicle frame
  double convexity_rad = 0.0;            // α: (0, π] convex, [−π, 0) concave
  double orientation_rad = 0.0;          // β: bisector from the x axis
  Eigen::Vector2d pixel{0.0, 0.0};       // image position (u, v)
  int blob = -1;                         // index of the blob in the frame
  bool on_plant = true;                  // crop blob (else weed)
};

// Signed angle α at p between arms to a and b, and the bisector angle β
// (fig. 7). `convex_sign` is +1 when the contour winds so that a left turn
// from a through p to b is convex.
void ConvexityOrientation(const Eigen::Vector2d& a, const Eigen::Vector2d& p,
                          const Eigen::Vector2d& b, double convex_sign, double& alpha_rad,
                          double& beta_rad);

// Dominant points of one closed contour already on the feature plane.
// `cut[i]` marks points on the image edge: no feature is placed where either
// arm reaches one. Returns contour indices.
std::vector<int> DominantPoints(std::span<const Eigen::Vector2d> contour_m,
                                std::span<const uint8_t> cut, const FeatureOptions& options);

// Stability of a feature detector (Sanchiz & Pla §3, eq. 5), in %: of the
// n_k features of image k, det also appeared and were detected in image
// k−1 and notview were out of image k−1's view. 0 when n_k = notview.
double FeatureStability(int n_k, int detected, int not_in_view);

// Features of every plant blob (contours traced) of a frame.
class FeatureExtractor {
 public:
  explicit FeatureExtractor(const FeatureOptions& options);

  const std::vector<Feature>& Extract(std::span<const vision::Blob> blobs,
                                      const geometry::CameraModel& camera);
  const FeatureOptions& options() const { return options_; }
  // True when a blob counts as a plant (crop) by its ground area.
  bool IsPlant(const vision::Blob& blob) const;
  // Height of the plane a blob's contour is placed on.
  double PlaneHeight(const vision::Blob& blob, bool plant) const;

 private:
  void AddBlobFeatures(const vision::Blob& blob, int index, bool plant,
                       const geometry::CameraModel& camera);

  FeatureOptions options_;
  std::vector<Feature> features_;
  std::vector<Eigen::Vector2d> contour_m_;
  std::vector<uint8_t> cut_;
};

}  // namespace plantscale::motion
