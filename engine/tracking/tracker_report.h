#pragma once
// What the grid tracker reports (GridTracker, grid_tracker.h): its mode,
// each input's acceptance, each frame's associations and update, the grid
// predicted ahead, and the planter's spread as the plants show it.

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
