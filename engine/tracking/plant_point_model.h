#pragma once
// The plant point model on the filter's state: a plant's centroid as the
// camera sees it (observation_model.h: thesis §4.2, eqs. 2.1–2.6 and A.1,
// its Jacobian PlantWithOffsetJacobian), here with the columns of the
// states the filter carries beside the grid: a persistent camera bounce
// (BounceJacobian) and the calibration's error (BounceJacobian and
// FocalJacobian), and the covariance of its predicted measurement for
// gating (eq. 6.5). Its finite-difference tests: observation_model_test.cc.

#include <Eigen/Core>

#include "engine/geometry/grid_model.h"
#include "engine/tracking/kalman_filter.h"
#include "engine/tracking/observation_model.h"

namespace plantscale::tracking {

// The ObservationModel's prediction of plant (m, n) at the state x laid
// out as `layout` (the grid `s`, the plant's own states at offset_index or
// none when −1), with the persistent bounce's and the calibration's effect
// and columns added.
Prediction PredictPlant(const ObservationModel& h, const StateLayout& layout,
                        const Eigen::VectorXd& x, const geometry::GridState& s, int m, int n,
                        int offset_index);
// The same at the filter's state.
Prediction PredictPlant(const ObservationModel& h, const GridFilter& filter,
                        const geometry::GridState& s, int m, int n);

// What the prior of a plant's own states (not yet in the filter) adds to
// the covariance of its predicted measurement.
Eigen::Matrix2d NewPlantPrior(const TrackerOptions& options, const Prediction& pred);

// Covariance of a plant's predicted measurement H P Hᵀ: the filter's, plus
// the prior of a new plant's offset (offset < 0) and of a bounce that does
// not persist.
Eigen::Matrix2d PredictionCovariance(const TrackerOptions& options, const GridFilter& filter,
                                     const Prediction& pred, int offset,
                                     const Eigen::Vector3d& bounce_prior);

}  // namespace plantscale::tracking
