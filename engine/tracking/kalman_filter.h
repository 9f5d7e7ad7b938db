#pragma once
// The grid tracker's filter: the state x, its covariance P and the plants
// carried in it (state_layout.h names the blocks), with what changes them.
//
//   Predict        x, P ← f(x), A P Aᵀ + Q over one dead-reckoning step
//                  (eq. 4.3; A and Q from process_model.h), plus each
//                  plant's random walk
//   Apply          the compressed pseudo-observation (eqs. 4.73–4.74,
//                  the measurements stacked as in eqs. 4.77–4.78) by the
//                  matrix inversion lemma; Schmidt's consider form for the
//                  calibration's scale states; returns the NIS, the
//                  filter's consistency check (eq. 6.5 stacked)
//   ShiftLines     the reference shift of the plant lines (eqs. 4.6–4.8)
//   AddPlant,      a plant's own states enter at their prior, and leave
//   Marginalise    (marginalised) when the plant leaves the view
//
// It is the state's arithmetic only: when to predict, what to observe and
// when the grid is lost are the tracker's (grid_tracker.cc).

#include <Eigen/Core>
#include <vector>

#include "engine/geometry/grid_model.h"
#include "engine/tracking/process_model.h"
#include "engine/tracking/state_layout.h"
#include "engine/tracking/tracker_options.h"
#include "engine/tracking/tracker_report.h"

namespace plantscale::tracking {

// The vision node's compressed measurement (eqs. 4.77–4.78) in square-root
// information form: with each feature's innovation whitened by its R
// (R = C Cᵀ), L stacks C⁻¹ H and r stacks C⁻¹ ν, so that Ĩ = Σ Hᵀ R⁻¹ H =
// LᵀL and Σ Hᵀ R⁻¹ ν = Lᵀ r, linearised at the dead-reckoning
// prediction. It is defined even when the features do not observe every
// state on their own, and L's columns are zero outside `support` (the grid,
// the bounce and the matched plants' own states), which the update uses.
struct PseudoObservation {
  Eigen::MatrixXd factor;    // L: rows × state size
  Eigen::VectorXd residual;  // r
  std::vector<int> support;  // the states L touches
};

class GridFilter {
 public:
  explicit GridFilter(const TrackerOptions& options);

  // The state before initialisation: the nominal grid, k at its prior.
  void Reset();
  // Start at the grid `s` with the covariance of (t_x, Y, Ψ, r̄, l̄): no
  // plants, a fresh bounce; k and the calibration keep what was learnt.
  void Restart(const geometry::GridState& s, const geometry::Matrix5d& covariance);

  const StateLayout& layout() const { return layout_; }
  const Eigen::VectorXd& x() const { return x_; }
  const Eigen::MatrixXd& p() const { return p_; }
  const std::vector<PlantOffset>& plants() const { return offsets_; }
  // The grid; r̄ and l̄ are the fixed values in the 3-state filter.
  geometry::GridState state() const;
  // Covariance of (t_x, Y, Ψ, r̄, l̄); zero rows for fixed spacings.
  geometry::Matrix5d covariance() const;
  double OdometryScale() const;
  // (t_x, Y, Ψ) alone, moved without the covariance (a held frame lag).
  Eigen::Vector3d pose() const { return x_.head<3>(); }
  void SetPose(const Eigen::Vector3d& pose) { x_.head<3>() = pose; }

  // One dead-reckoning step (process_model.h) over `distance_m` driven.
  void Predict(const Transition& t, double distance_m);
  // Thesis eq. 4.2: constant process noise per frame.
  void AddFrameNoise();
  // Process noise on r̄ and l̄ for `lines_changed` plant lines entering or
  // leaving the view (§4.1.2); the variance added to each (0 when the
  // spacings are fixed).
  double AddSpacingNoise(int lines_changed);
  // The reference moved by k plant lines (grid_model.h's ShiftReference on
  // the state gave `shifted`): eq. 4.8 when l̄ is estimated, 4.7 when not.
  void ShiftLines(int k, const geometry::GridState& shifted);

  // Where plant (m, n)'s δx sits in x, or −1 when it has no states.
  int OffsetIndex(int m, int n) const;
  // Plant (m, n)'s states at their prior; returns their index.
  int AddPlant(int m, int n);
  // The plants not in `in_view` are marginalised; each adds to `spread`.
  void Marginalise(const std::vector<geometry::GridPlant>& in_view, PlantSpread& spread);
  // A bounce that does not persist, appended as a nuisance block at its
  // prior for one update and dropped after it; Append returns the size of
  // the state without it.
  int AppendNuisance(const Eigen::Vector3d& bounce_prior);
  void DropNuisance(int persistent_size);
  // Eqs. 4.73–4.74; returns the normalised innovation squared.
  double Apply(const PseudoObservation& z);
  // The grid is lost: its plants go, and a state that is not finite
  // restarts at zero (k at its prior).
  void Lose();

 private:
  void ResetBounce();
  void ResetCalibration();

  TrackerOptions options_;
  StateLayout layout_;
  Eigen::VectorXd x_;  // the head, then each plant's states
  Eigen::MatrixXd p_;
  std::vector<PlantOffset> offsets_;
};

}  // namespace plantscale::tracking
