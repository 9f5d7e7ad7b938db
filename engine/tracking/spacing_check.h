#pragma once
// Does the bed's row spacing agree with the crop profile's? The profile
// gives the drill's setting r₀ and how precisely it is known (σ₀, the crop
// profile's row_spacing_sd_m); the filter starts r̄ at r₀ with that prior
// and adds its random walk (spacing_step_sd_m per plant line entering or
// leaving the view), so without a single frame r̄ ~ N(r₀, V₀) with
// V₀ = σ₀² + Σq. The frames then move r̄ to r̂ with variance P. In a linear
// Gaussian filter the estimate's move and its error are uncorrelated, so
// when the profile is right
//
//   r̂ − r₀ ~ N(0, V₀ − P),   d² = (r̂ − r₀)² / (V₀ − P) ~ χ²₁,
//
// the filter's own test of its prior against what the frames measured. A
// d² beyond spacing_check_chi2 says the profile's spacing is wrong (a
// drill set to 0.50 m written as 0.45 m): a mismatch naming the spacing
// the frames measured, which is r̂ with the prior's share taken out,
//
//   r_frames = r₀ + (r̂ − r₀)·V₀/(V₀ − P),  σ² = P·V₀/(V₀ − P)
//
// (the data-only estimate whose product with N(r₀, V₀) is N(r̂, P)).
// Tested only once the frames know r̄ better than the prior did (P ≤ V₀/2):
// before that d² divides by a difference of two nearly equal numbers.
//
// A camera off from its calibration (tilt, height, focal length) scales
// every distance it sees, the rows' spacing with them, and the filter does
// not carry that scale (the product's tilt, height and focal are taken as
// calibrated): r̂ then stands off r₀ by the scale's error too, so its
// variance (s·r₀)², s the fractional sd of the scale the calibration leaves
// (spacing_check_scale_sd), is added to d²'s denominator and to the
// measured spacing's sd. A spacing beyond both is not the camera's: it is
// reported, not fitted to the camera.

#include <optional>

#include "engine/tracking/tracker_report.h"

namespace plantscale::tracking {

class SpacingCheck {
 public:
  // chi2: the d² beyond which the spacing disagrees (0: never checked).
  explicit SpacingCheck(double chi2) : chi2_(chi2) {}

  // A (re)start: r̄'s prior mean and variance, and the variance of the
  // spacing the camera's scale error makes ((s·r₀)²).
  void Start(double prior_m, double prior_var, double scale_var = 0.0);
  // The random walk's variance added to r̄ since (AddSpacingNoise).
  void AddNoise(double var) { prior_var_ += var; }
  // After an update: the filter's r̂ and its variance P. The mismatch when
  // d² exceeds the threshold (also kept in current()), else none.
  std::optional<SpacingMismatch> Check(double estimate_m, double variance);
  // The last Check's mismatch, until a Check finds none or a Start.
  const std::optional<SpacingMismatch>& current() const { return current_; }
  double prior_m() const { return prior_m_; }
  double prior_var() const { return prior_var_; }

 private:
  double chi2_;
  double prior_m_ = 0.0;
  double prior_var_ = 0.0;
  double scale_var_ = 0.0;
  std::optional<SpacingMismatch> current_;
};

}  // namespace plantscale::tracking
