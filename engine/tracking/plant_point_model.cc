#include "engine/tracking/plant_point_model.h"

#include <vector>

namespace plantscale::tracking {

using geometry::GridState;

Prediction PredictPlant(const ObservationModel& h, const StateLayout& layout, const Eigen::VectorXd& x,
                        const GridState& s, int m, int n, int offset_index) {
  Prediction pred = h.Predict(x, s, m, n, offset_index);
  if (layout.persistent_bounce()) {
    const int b = layout.bounce_index();
    pred.value += pred.bounce_jacobian * x.segment<3>(b);
    pred.jacobian.middleCols<3>(b) = pred.bounce_jacobian;
  }
  if (layout.calibration()) {
    const int c = layout.calibration_index();
    pred.value += pred.bounce_jacobian * x.segment<3>(c) + pred.focal_jacobian * x(c + 3);
    pred.jacobian.middleCols<3>(c) = pred.bounce_jacobian;
    pred.jacobian.col(c + 3) = pred.focal_jacobian;
  }
  return pred;
}

Prediction PredictPlant(const ObservationModel& h, const GridFilter& filter, const GridState& s,
                        int m, int n) {
  return PredictPlant(h, filter.layout(), filter.x(), s, m, n, filter.OffsetIndex(m, n));
}

Eigen::Matrix2d NewPlantPrior(const TrackerOptions& options, const Prediction& pred) {
  return pred.offset_jacobian * ObservationModel::PlantPrior(options).asDiagonal() *
         pred.offset_jacobian.transpose();
}

// H touches only the grid states, the bounce and this plant's own states,
// so only that block of P is needed.
Eigen::Matrix2d PredictionCovariance(const TrackerOptions& options, const GridFilter& filter,
                                     const Prediction& pred, int offset,
                                     const Eigen::Vector3d& bounce_prior) {
  const StateLayout& layout = filter.layout();
  std::vector<int> used;
  for (int i = 0; i < layout.core(); ++i) used.push_back(i);
  for (int i = layout.bounce_index(); i < layout.head(); ++i) used.push_back(i);
  if (offset >= 0) {
    for (int i = 0; i < layout.plant_states(); ++i) used.push_back(offset + i);
  }
  const Eigen::MatrixXd hs = pred.jacobian(Eigen::all, used);
  Eigen::Matrix2d hph = hs * filter.p()(used, used) * hs.transpose();
  if (offset < 0 && options.plant_offsets) hph += NewPlantPrior(options, pred);
  if (layout.nuisance_bounce()) {
    hph += pred.bounce_jacobian * bounce_prior.asDiagonal() * pred.bounce_jacobian.transpose();
  }
  return hph;
}

}  // namespace plantscale::tracking
