#pragma once
// Gating and association of one frame's features with the grid's plants
// in view (thesis ch. 6): which blobs may be a plant's centroid at all
// (merged plants and weed-sized blobs are not), parallel validation
// (§6.2.2) of every pair by its innovation's γ² (eqs. 6.5, 6.7), one-to-one
// nearest-neighbour association (eq. 6.6), the merged blobs along one row
// taken as strips (strip_model.h) by their own 1-dof gate, and whether the
// matches observe the grid (§4.5).

#include <Eigen/Core>
#include <span>
#include <vector>

#include "engine/geometry/grid_model.h"
#include "engine/tracking/feature.h"
#include "engine/tracking/grid_tracker_internal.h"
#include "engine/tracking/kalman_filter.h"
#include "engine/tracking/observation_model.h"
#include "engine/tracking/tracker_report.h"

namespace plantscale::tracking {

// Blobs not taken for a plant's centroid: merged plants (a box holding two
// or more predictions, skip_merged_features) and weed-sized blobs, unless
// too few others are left (touching plants everywhere, as on preset A,
// where the merged blobs are what there is to track).
FeatureFlags MarkSkippedFeatures(const TrackerOptions& options, std::span<const Feature> features,
                                 const std::vector<geometry::GridPlant>& in_view);

// Parallel validation (§6.2.2): every feature within 0.4 m of a plant's
// predicted ground position whose innovation γ² passes gate_chi2, each
// gate from the one prediction.
std::vector<Candidate> Gate(const ObservationModel& h, const GridFilter& filter,
                            const geometry::GridState& s, std::span<const Feature> features,
                            const FeatureFlags& flags,
                            const std::vector<geometry::GridPlant>& in_view,
                            const Eigen::Vector3d& bounce_prior);

// Nearest neighbours among the gated pairs: one feature per plant and one
// plant per feature, the smallest γ² first.
std::vector<Candidate> Associate(std::vector<Candidate> candidates, size_t plants, size_t features);

// Merged blobs along one row (merged_row_strips) whose lateral innovation
// passes the 1-dof gate strip_gate_chi2. A plant matched by a point
// feature leaves the strip; a strip needs two plants.
std::vector<Strip> FindStrips(const ObservationModel& h, const GridFilter& filter,
                              const geometry::GridState& s, std::span<const Feature> features,
                              const FeatureFlags& flags,
                              const std::vector<geometry::GridPlant>& in_view,
                              const std::vector<Candidate>& matches,
                              const Eigen::Vector3d& bounce_prior);

// Observability (§4.5): two features fix (t_x, Y, Ψ); the spacings need a
// third that is not on the same row or the same line as the others. False,
// with the reason in `report` (whose matched and predicted it reads), when
// the matches do not suffice.
bool Observable(const TrackerOptions& options, const std::vector<Candidate>& matches,
                const std::vector<geometry::GridPlant>& in_view, FrameReport& report);

}  // namespace plantscale::tracking
