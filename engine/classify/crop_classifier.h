#pragma once
// Crop/weed classification of segmented blobs (thesis ch. 7, as run on-line
// in ch. 8): a size filter, then association with the predicted crop grid.
// A blob is crop when its ground area is at least `min_crop_area_m2` and its
// centroid falls inside the association region of a predicted crop plant:
//
//   γ² = νᵀ S_assoc⁻¹ ν ≤ assoc_chi2,   S_assoc = H P Hᵀ + F_w R F_wᵀ   (eq. 7.4)
//
// with ν the centroid minus the predicted plant position on the virtual
// ground plane, H = d(plant)/d(t_x, Y, Ψ, r̄, l̄) (eq. A.1), P the tracker's
// covariance, and F_w R F_wᵀ the centroid noise on the ground (R_w, eq. 4.28)
// plus each plant's own spread about its grid position (planting error and
// lean, σ_plant² I), which the thesis folded into R, and the camera's
// bounce (pitch, roll, height; tracking::BounceJacobian), which moves every
// centroid of a frame together by centimetres at the far end of the view and
// which the predictions from the nominal camera leave out. Blobs clipped by the
// image border skip the size filter (their area is cut) but must associate.
// Blobs bigger than any weed grows (`sure_crop_area_m2`) are crop wherever
// they lie: touching plants merge into one blob whose centroid falls
// between them (thesis fig. 2.17; its table 7.2 met this on sequence A with
// a 450 mm region, i.e. by size alone).

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/grid_model.h"
#include "engine/tracking/feature.h"

namespace plantscale::classify {

struct ClassifierOptions {
  double min_crop_area_m2 = 0.004;  // ς: the size filter, on the ground
  // The size filter follows the crop's growth: it is at most this fraction
  // of the median ground area of the last `crop_size_window` whole crop
  // blobs (associated, not clipped), once `crop_size_min_samples` were seen;
  // 0: ς alone. The thesis set ς by hand per sequence (table 7.2: 30 px on
  // the 3-week crops of B and D, 80–100 px on A and C); a fixed 0.004 m²
  // leaves a 3-week crop (r ≈ 0.06 m) below the filter in some plants
  // (docs/results/2026-11-27-option-choices.md). Crops large beside ς (A, C, field)
  // keep ς.
  double crop_size_fraction = 0.3;
  int crop_size_window = 101;
  int crop_size_min_samples = 20;
  double assoc_chi2 = 9.21;         // association region (99 % for 2 dof)
  // This big: crop without association. Off (∞) by default: it lifts the
  // crop pixels of merged plants but such blobs mark no map cells, and
  // without their weed votes the crop cells spread (more of the bed
  // treated, placement along worse: docs/results/2026-11-27-option-choices.md).
  double sure_crop_area_m2 = std::numeric_limits<double>::infinity();
  double feature_sd_m = 0.008;      // R_w per axis
  double plant_sd_m = 0.02;         // a plant's spread about its grid position, per axis
  double camera_pitch_sd_rad = 0.005;  // bounce, as the tracker's TrackerOptions
  double camera_roll_sd_rad = 0.0035;
  double camera_height_sd_m = 0.004;
  // SplitMerged: a pixel belongs to the nearest predicted crop this close.
  double split_radius_m = 0.3;  // beyond the largest crop's leaves (A: 0.2 m plants) plus spread
  // SplitMerged: a part's association gate (γ² of its centroid to its own
  // prediction). A part is the pixels nearest one prediction: where a
  // neighbour's leaves reach past the halfway line the cut moves its centroid
  // off the plant's by more than a blob's would be.
  double split_assoc_chi2 = 9.21;
  // SplitMerged: a part (of at least the size filter) with plant matter this
  // close to its prediction is that crop whatever its centroid: the cut
  // takes a big plant's leaves from one side and gives it a neighbour's, so
  // its centroid strays by more than a plant's spread. 0: the gate alone.
  // About one plant_sd_m.
  double split_cover_m = 0.02;
  // SplitMerged, a blob cut by the image border: its part is that crop when
  // it has plant matter within this many of the crops' typical radius
  // (sqrt(median whole crop area / π), learnt as the size filter) of its
  // prediction. Such a blob is mostly a crop entering or leaving the view
  // with its root beyond the border: its visible leaves neither reach the
  // prediction nor centre on it, so the plants beyond the border within
  // this reach are predicted too (PredictCrops). 0: as an uncut blob.
  double split_clipped_reach = 1.0;
  // Leaf fragments: a blob under the size filter (not cut by the border)
  // whose centroid lies within this many of the crops' typical radius of a
  // prediction that a crop blob of the same frame associated with is that
  // crop's leaf, cut off by segmentation (shaded leaf between it and the
  // plant). It marks no map cells (it is not associated) and casts no weed
  // votes. 0: off (the thesis: under the size filter is weed). Larger
  // reaches take weeds beside crops for leaves.
  double fragment_reach = 1.0;
  // Lone small crops: a blob under the size filter but at least this
  // fraction of it, not cut by the border, inside the association region
  // of a prediction that no crop blob of the same frame took, is that crop
  // (a stunted plant, or one whose shaded leaves segmentation lost). 0: off
  // (the thesis: under the size filter is weed). A weed standing where a
  // crop is missing is taken for it. It matters on small crops (B, D), whose
  // missed crops had mostly been voted weed in the frames that saw them
  // small.
  double lone_crop_fraction = 0.25;
  // Weeds merged with a crop's blob (BeyondCropOutline): plant matter of an
  // associated crop blob beyond this many standard deviations of the blob's
  // own outline ellipse is not that crop. A crop's lobed outline reaches
  // 2.16 sd at its leaf tips (a disc 2.0); lower limits take leaf tips for
  // weeds (docs/results/2026-11-27-report.md, session 27). 0: off (the
  // whole blob is crop).
  double outline_limit_sd = 2.2;
  // A learned model's class of a blob (vision::Blob::learned_class, the
  // grower's model; FuseLearned) decides crop or weed where the model's
  // confidence in it reaches this; below it, the grid's rule above decides.
  // > 1: the model never decides.
  double learned_min_confidence = 0.6;

  OptionErrors Validate() const;
};

// A predicted crop plant: grid line m, row n, position on the virtual ground
// plane (vehicle frame) and d(position)/d(t_x, Y, Ψ, r̄, l̄).
struct PredictedCrop {
  int m = 0;
  int n = 0;
  Eigen::Vector2d ground_m{0.0, 0.0};
  Eigen::Matrix<double, 2, 5> jacobian = Eigen::Matrix<double, 2, 5>::Zero();
  Eigen::Matrix<double, 2, 3> bounce_jacobian = Eigen::Matrix<double, 2, 3>::Zero();
};

// Predictions of every grid plant in view from the tracker's state; with
// `reach_m` > 0 also of those beyond the view's border whose leaves may
// reach into it (GridModel::PlantsReachingView).
std::vector<PredictedCrop> PredictCrops(const geometry::GridModel& model,
                                        const geometry::GridState& state, double reach_m = 0.0);

// S_assoc of eq. 7.4 for one prediction.
Eigen::Matrix2d AssociationCovariance(const PredictedCrop& crop, const geometry::Matrix5d& p,
                                      const ClassifierOptions& options);

// Why a blob got its class: its size and its nearest predicted crop.
struct BlobDecision {
  bool crop = false;
  bool associated = false;  // inside a predicted crop's association region
  double area_m2 = 0.0;
  bool clipped = false;
  bool fragment = false;  // under the size filter, crop as a leaf of an associated crop
  bool lone = false;      // under the size filter, crop alone in its region (lone_crop_fraction)
  double size_filter_m2 = 0.0;  // the size filter it was held to
  double gamma2 = std::numeric_limits<double>::infinity();  // to the nearest prediction (γ²)
  double distance_m = std::numeric_limits<double>::infinity();  // Euclidean, to that prediction
  int m = 0, n = 0;  // the nearest prediction's grid indices (valid when gamma2 is finite)
  Eigen::Vector2d predicted_ground_m{0.0, 0.0};  // and its position (vehicle frame)
  // The learned model's class of the blob (vision::PixelClass; −1: no model)
  // and its confidence; `learned` when that class decided (FuseLearned).
  int learned_class = -1;
  double learned_confidence = 0.0;
  bool learned = false;
};

// The learned model's class of a blob fused with the grid's rule (`d`, as
// Classify decided it): where the model is sure (confidence ≥
// learned_min_confidence) of crop or weed, its class decides; elsewhere
// (unsure, or it calls the blob soil) the rule's decision stands. A blob
// the model is sure is a weed is no crop's, even inside a crop's
// association region (a weed touching a crop is a blob of its own once the
// mask is cut along the model's classes), so it loses its association.
// The model's class and confidence are kept in `d` either way.
void FuseLearned(int learned_class, double confidence, const ClassifierOptions& options,
                 BlobDecision& d);

// Weeds merged with a crop (the oblique view joins a weed beside a crop, or
// one seen past the crop's leaf tips, to the crop's blob): flags the points
// (`ground_m`, a crop blob's pixels on the crops' plane) that lie beyond
// `limit_sd` standard deviations of the blob's outline, the ellipse of its
// second moments about its centroid. The ellipse is the crop as the camera
// sees it: its leaf-tip disc at the leaf height, lengthened along the line
// of sight by the flank below its near leaf tips, and its own size rather
// than the crops' typical one. It is taken twice, the second time over the
// points inside the first, so that a merged weed widens it little. No point
// is flagged when there are fewer than 8 or the ellipse is degenerate.
// Returns the number flagged.
int BeyondCropOutline(std::span<const Eigen::Vector2d> ground_m, double limit_sd,
                      std::vector<uint8_t>& beyond);

// The two-parameter rule alone (for sweeps): size filter, then association.
bool IsCrop(double area_m2, bool clipped, double gamma2, double min_crop_area_m2,
            double assoc_chi2,
            double sure_crop_area_m2 = std::numeric_limits<double>::infinity());

class CropClassifier {
 public:
  // Throws InvalidOptionsError.
  explicit CropClassifier(const ClassifierOptions& options);

  // One decision per feature, in order. With no predictions (the grid is not
  // tracked) every blob is weed: nothing is known to be crop. The whole crop
  // blobs found are then remembered for the size filter (crop_size_fraction).
  void Classify(std::span<const tracking::Feature> features,
                std::span<const PredictedCrop> predictions, const geometry::Matrix5d& covariance,
                std::vector<BlobDecision>& out);
  // The size filter in force: min(ς, crop_size_fraction × the crops' median
  // area) once enough crops were seen, else ς.
  double size_filter_m2() const { return size_filter_m2_; }
  // The median ground area of the last whole crops (0 before enough seen).
  double median_crop_area_m2() const { return median_crop_area_m2_; }
  // The radius of a disk of the median area (0 before enough crops were
  // seen), and how far a crop's leaves reach from its root: that times
  // split_clipped_reach.
  double typical_crop_radius_m() const;
  double crop_reach_m() const;

  // Merged plants (thesis fig. 2.17): a blob whose centroid missed every
  // association region may be several touching plants, its centroid between
  // them. Its pixels (ground points on the virtual plane, each standing for
  // `pixel_area_m2[i]`) are split among the predicted crops, each pixel to
  // the nearest prediction within `split_radius_m`, and every part is then
  // classified as a blob of its own (size filter, then its centroid against
  // its prediction's association region with `split_assoc_chi2`, or plant
  // matter within `split_cover_m` of the prediction, or when `clipped`
  // within split_clipped_reach × the crops' typical radius; `clipped` as the
  // whole blob's).
  // Writes 1 (crop) or 0 (weed) per pixel into `crop`; pixels beyond every
  // prediction's radius are weed. Returns the number of crop parts. With
  // `part`, also writes each pixel's part: the index of its prediction in
  // `predictions`, −1 beyond every radius.
  int SplitMerged(std::span<const Eigen::Vector2d> ground_m, std::span<const double> pixel_area_m2,
                  bool clipped, std::span<const PredictedCrop> predictions,
                  const geometry::Matrix5d& covariance, std::vector<uint8_t>& crop,
                  std::vector<int>* part = nullptr) const;

  const ClassifierOptions& options() const { return options_; }

 private:
  BlobDecision Decide(const tracking::Feature& f, std::span<const PredictedCrop> predictions,
                      std::span<const Eigen::Matrix2d> s_inverse) const;
  void MarkFragments(std::span<const tracking::Feature> features, std::vector<BlobDecision>& out) const;
  void MarkLoneCrops(std::vector<BlobDecision>& out) const;
  void RememberCropArea(double area_m2);
  void UpdateSizeFilter();

  ClassifierOptions options_;
  std::vector<double> crop_areas_;  // ring of the last crop_size_window
  size_t next_area_ = 0;
  std::vector<double> scratch_;
  double size_filter_m2_ = 0.0;
  double median_crop_area_m2_ = 0.0;
};

}  // namespace plantscale::classify
