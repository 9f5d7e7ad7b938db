#pragma once
// What the grid tracker reports (GridTracker, grid_tracker.h): its mode,
// each input's acceptance, each frame's associations and update, the grid
// predicted ahead, and the planter's spread as the plants show it.

#include <optional>
#include <string>
#include <vector>

#include "engine/geometry/grid_model.h"

namespace plantscale::tracking {

enum class TrackerMode { kInitialising, kTracking, kLost };
const char* ToString(TrackerMode mode);

// Accepted or refused input, with the reason.
struct InputStatus {
  bool accepted = true;
  std::string reason;
};

struct Association {
  int feature = -1;  // index into the frame's features
  int m = 0;         // grid line (0: bottom-most in view)
  int n = 0;         // row (0: central)
  double gamma2 = 0.0;  // normalised innovation (eq. 6.5)
};

// The bed's row spacing disagrees with the crop profile's beyond what the
// profile's precision (row_spacing_sd_m, with the spacing's random walk)
// and the filter's covariance allow (SpacingCheck, spacing_check.h).
struct SpacingMismatch {
  double measured_m = 0.0;     // what the frames measured, the profile's share taken out
  double measured_sd_m = 0.0;
  double estimate_m = 0.0;     // the filter's r̄ (the profile's prior in it)
  double profile_m = 0.0;      // the crop profile's row_spacing_m
  double profile_sd_m = 0.0;   // its precision, with the random walk since the start and the camera's scale
  double chi2 = 0.0;           // d² = (r̂ − r₀)² / (V₀ − P + (s·r₀)²)
  std::string Text() const;    // "row spacing measured 0.501 m ± 0.002, the crop profile says ..."
};

struct FrameReport {
  InputStatus input;
  TrackerMode mode = TrackerMode::kInitialising;
  bool initialised_now = false;
  bool updated = false;
  std::string skipped_reason;  // why no update was made, when it was not
  int predicted = 0;           // grid plants in view
  int matched = 0;
  int strips = 0;              // merged blobs along one row taken for its lateral position
  int lines_shifted = 0;       // reference shifts (eq. 4.6) before this frame's update
  double nis = 0.0;            // stacked normalised innovation squared
  // The first frame of a run (tracker's life, until Reset) whose update
  // finds the row spacing disagreeing with the crop profile's: the event.
  // GridTracker::row_spacing_mismatch() holds it while it lasts.
  std::optional<SpacingMismatch> row_spacing_mismatch;
  std::vector<Association> associations;
};

// The grid predicted ahead by dead reckoning alone (GridTracker::PredictAhead).
struct GridAhead {
  geometry::GridState state;
  geometry::Matrix5d covariance = geometry::Matrix5d::Zero();  // of (t_x, Y, Ψ, r̄, l̄)
};

// The planter's spread as the plants show it (the crop profile's
// planter_sd_m is a grower's guess): when a plant leaves the view, the
// square of its offset's estimate on each axis the frames pinned (its
// variance below half the prior's); the root mean square over the
// tracker's life, starts and losses included (AddPlant says why this
// estimator). GridTracker::PlantSpread.
struct PlantSpread {
  double across_sum2 = 0.0, along_sum2 = 0.0;
  int across = 0, along = 0;
  double across_sd_m() const;  // NaN before any plant
  double along_sd_m() const;
  // A plant leaving the view: its offset's estimates and variances across
  // and along, against the prior variance of an offset.
  void AddPlant(double across_m, double across_var, double along_m, double along_var,
                double prior_var);
};

}  // namespace plantscale::tracking
