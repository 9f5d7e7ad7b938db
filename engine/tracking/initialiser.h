#pragma once
// Automatic initialisation of the crop-grid tracker (thesis ch. 6, app. A):
// a Hough transform over (t_x, Ψ) with a comb of the bed's rows finds the
// rows (Marchant & Brivot's accumulator, here voted from features on the
// calibrated virtual ground plane, which is eq. A.7 without its small-angle
// approximation; the votes are engine/rows' VoteComb, the row comb the
// image-plane detector shares), a least-squares fit to the features near
// the winning rows refines it, and the phase of the plant-spacing frequency
// along the rows (eq. 6.1) gives Y. A candidate is only accepted when the next frame,
// predicted by odometry, agrees with it; otherwise the initialiser retries
// and says why.

#include <optional>
#include <span>
#include <string>

#include "engine/common/options.h"
#include "engine/geometry/grid_model.h"
#include "engine/tracking/feature.h"
#include "engine/tracking/motion_model.h"

namespace plantscale::tracking {

struct InitialiserOptions {
  double max_bearing_rad = 0.2618;      // ±15° searched
  double bearing_step_rad = 0.004363;   // 0.25°
  double offset_step_m = 0.004;         // Hough t_x bin
  double max_offset_fraction = 0.75;    // |t_x| searched up to this × r̄
  double row_halfwidth_fraction = 0.25; // features within ± this × r̄ of a row support it
  double max_range_m = 4.0;             // features farther ahead are ignored
  double weight_cap_m2 = 0.05;          // a feature votes with its ground area, capped
  double min_row_support = 0.45;        // fraction of the vote weight on the rows
  double min_phase_coherence = 0.35;    // |Σ w e^{-iθ}| / Σ w along the rows
  int min_features = 4;
  // A closed canopy: plants touching along a row are segmented as one long
  // blob (a band: elongation ≥ band_min_elongation, its 2σ axis at least
  // band_min_length_m on the ground), often cut by the image's border. The
  // Hough of centroids leaves cut blobs out and reads a band as one point,
  // so on a closed canopy the few plants seen apart decide the bearing
  // alone, and a wrong one holds (the `treatment` preset: starts 4–14° off).
  // When bands hold more than closed_canopy_fraction of the plant matter in
  // range, the rows' bearing is the bands' own (their axes, area-weighted),
  // the Hough searches only band_bearing_window_rad about it with the
  // bands' centroids voting too, and the offset is fitted at that bearing.
  // The phase along the rows still comes from the plants seen apart.
  double band_min_elongation = 3.0;
  double band_min_length_m = 0.3;
  double closed_canopy_fraction = 0.5;
  double band_bearing_window_rad = 0.035;  // ±2°
  int confirm_frames = 3;               // consecutive agreeing frames to accept
  double confirm_offset_m = 0.03;
  double confirm_bearing_rad = 0.026;   // 1.5°
  double confirm_forward_m = 0.05;
  // Initial standard deviations (thesis §6.1: Hough 12.5 mm and 1°, DFT 24.5 mm).
  double offset_sd_m = 0.0125;
  double bearing_sd_rad = 0.01745;
  double forward_sd_m = 0.0245;

  OptionErrors Validate() const;
};

struct RowFit {
  double offset_m = 0.0;   // t_x
  double bearing_rad = 0.0;  // Ψ
  double support = 0.0;    // fraction of the vote weight within the rows
  int features_on_rows = 0;
  bool closed_canopy = false;  // the bearing is the bands' (InitialiserOptions)
};

// Hough + least squares: the rows n = −k..k of spacing r̄ through the features.
std::optional<RowFit> FitRowsOnGround(std::span<const Feature> features, double row_spacing_m,
                                      int rows_each_side, const InitialiserOptions& options);

struct LinePhase {
  double forward_m = 0.0;  // Y in [0, l̄)
  double coherence = 0.0;  // 1: every feature exactly on a plant line
};

// Thesis eq. 6.1: Y from the phase of the l̄ frequency of the features along
// the fitted rows (all rows pooled, weights as in the Hough).
std::optional<LinePhase> PlantLinePhaseOnGround(std::span<const Feature> features,
                                                const RowFit& rows, double row_spacing_m,
                                                double plant_spacing_m, int rows_each_side,
                                                const InitialiserOptions& options);

struct InitialiserResult {
  std::optional<geometry::GridState> state;  // set once confirmed
  std::string reason;                        // why not (yet)
};

class GridInitialiser {
 public:
  GridInitialiser(const InitialiserOptions& options, double row_spacing_m, double plant_spacing_m,
                  int rows_each_side, double track_width_m);

  // One frame's features, and the wheel motion since the previous offer.
  InitialiserResult Offer(std::span<const Feature> features, const WheelIncrement& motion);
  void Reset();
  const InitialiserOptions& options() const { return options_; }

 private:
  InitialiserOptions options_;
  double row_spacing_m_;
  double plant_spacing_m_;
  int rows_each_side_;
  double track_width_m_;
  std::optional<geometry::GridState> previous_;
  int agreeing_ = 0;
};

}  // namespace plantscale::tracking
