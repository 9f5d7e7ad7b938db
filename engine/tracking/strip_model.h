#pragma once
// The merged-blob strip's observation model (TrackerOptions::
// merged_row_strips): plants touching along one row seen as one blob, a
// measurement of the row's lateral position alone. Its prediction is the
// mean of the plants' (plant_point_model.h) and its Jacobian normalᵀ·J,
// the mean of theirs across the row: an extension of the thesis's point
// features (§4.2), not in it. Its finite-difference test:
// strip_model_test.cc. Which merged blobs are strips (their gating):
// association.h.

#include <Eigen/Core>
#include <span>
#include <vector>

#include "engine/geometry/grid_model.h"
#include "engine/tracking/grid_tracker_internal.h"
#include "engine/tracking/kalman_filter.h"
#include "engine/tracking/observation_model.h"

namespace plantscale::tracking {

// Plants touching along one row, seen as one blob (a strip,
// TrackerOptions::merged_row_strips): its centroid is taken as the mean of
// their predictions, and only across the row. `normal`: the unit normal of
// the line through the first and last of `plants` (ordered along the row),
// held at the prediction; `value` and `jacobian`: the mean of the plants'
// predictions and of their Jacobians, so that the strip's lateral position
// is normalᵀ·value with the Jacobian normalᵀ·jacobian. `plants` holds two or
// more predictions with Jacobians of one size.
struct StripPrediction {
  Eigen::Vector2d normal;
  Eigen::Vector2d value;
  Eigen::MatrixXd jacobian;
  Eigen::Matrix<double, 2, 3> bounce_jacobian;  // the mean of the plants'
};
StripPrediction PredictStrip(std::span<const Prediction> plants);

// The strip's prediction at the filter's state, its plants ordered along
// the row; with `nuisance` the bounce's columns are the per-frame nuisance
// states' (the last three). `prior`, when given, gets the offset prior of
// its plants not yet carried as states.
StripPrediction PredictStripAt(const ObservationModel& h, const GridFilter& filter,
                               const geometry::GridState& s,
                               const std::vector<geometry::GridPlant>& in_view, const Strip& strip,
                               bool nuisance, Eigen::Matrix2d* prior = nullptr);

}  // namespace plantscale::tracking
