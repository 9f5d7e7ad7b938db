#pragma once
// The grid tracker's private types, shared by its parts (engine/tracking
// only; the public face is grid_tracker.h). Indices are into one frame's
// `in_view` (GridModel::PlantsInView) and its features.

#include <sstream>
#include <string>
#include <vector>

namespace plantscale::tracking {

// A plant of the view and a feature gated together, with the innovation's
// normalised square γ² (eq. 6.5).
struct Candidate {
  int plant;
  int feature;
  double gamma2;
};

// A merged blob along one row (TrackerOptions::merged_row_strips): the
// feature and the plants of the view its box holds, not matched otherwise.
struct Strip {
  int feature;
  std::vector<int> plants;
};

// A plant (m, n) matched to a feature, for height_from_size.
struct SizeMatch {
  int m, n, feature;
};

// Per feature of a frame: not taken for a plant's centroid (merged or
// weed-sized), and merged (its box holds two or more predictions).
struct FeatureFlags {
  std::vector<bool> skipped;
  std::vector<bool> merged;
};

// "0.25 s": a duration in the tracker's reasons.
inline std::string Seconds(double s) {
  std::ostringstream out;
  out.precision(3);
  out << s << " s";
  return out.str();
}

}  // namespace plantscale::tracking
