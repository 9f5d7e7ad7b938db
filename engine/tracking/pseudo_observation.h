#pragma once
// The vision node's update (thesis eqs. 4.77–4.78, then 4.73–4.74): every
// match of a frame (plant points, plant_point_model.h) and every strip
// (strip_model.h) whitened by its measurement noise and stacked into one
// compressed pseudo-observation (kalman_filter.h's PseudoObservation),
// applied at once by the filter.

#include <Eigen/Core>
#include <span>
#include <vector>

#include "engine/geometry/grid_model.h"
#include "engine/tracking/feature.h"
#include "engine/tracking/grid_tracker_internal.h"
#include "engine/tracking/kalman_filter.h"
#include "engine/tracking/observation_model.h"

namespace plantscale::tracking {

// The stacked, whitened measurements at the filter's state: two rows per
// match (C⁻¹H, C⁻¹ν with R = CCᵀ), then one per strip (its lateral
// innovation over its σ). With `nuisance` the filter carries the bounce's
// nuisance block as its last three states.
PseudoObservation StackMeasurements(const ObservationModel& h, const GridFilter& filter,
                                    const geometry::GridState& s, std::span<const Feature> features,
                                    const std::vector<geometry::GridPlant>& in_view,
                                    const std::vector<Candidate>& matches,
                                    const std::vector<Strip>& strips, bool nuisance);

// The update on every match and strip at once: new plants get their own
// states first (plant_offsets); a bounce that does not persist is a
// nuisance block, appended for the update and marginalised after it.
// Returns the normalised innovation squared.
double UpdateOnFrame(GridFilter& filter, const ObservationModel& h, const geometry::GridState& s,
                     std::span<const Feature> features,
                     const std::vector<geometry::GridPlant>& in_view,
                     const std::vector<Candidate>& matches, const std::vector<Strip>& strips,
                     const Eigen::Vector3d& bounce_prior);

}  // namespace plantscale::tracking
