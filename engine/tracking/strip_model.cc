#include "engine/tracking/strip_model.h"

#include <algorithm>
#include <stdexcept>

#include "engine/tracking/plant_point_model.h"

namespace plantscale::tracking {

StripPrediction PredictStrip(std::span<const Prediction> plants) {
  if (plants.size() < 2) throw std::invalid_argument("PredictStrip: a strip needs two plants or more");
  StripPrediction out;
  out.value.setZero();
  out.jacobian = Eigen::MatrixXd::Zero(2, plants.front().jacobian.cols());
  out.bounce_jacobian.setZero();
  const double w = 1.0 / static_cast<double>(plants.size());
  for (const Prediction& p : plants) {
    out.value += w * p.value;
    out.jacobian += w * p.jacobian;
    out.bounce_jacobian += w * p.bounce_jacobian;
  }
  const Eigen::Vector2d along = (plants.back().value - plants.front().value).normalized();
  out.normal = Eigen::Vector2d(-along.y(), along.x());
  return out;
}

StripPrediction PredictStripAt(const ObservationModel& h, const GridFilter& filter,
                               const geometry::GridState& s,
                               const std::vector<geometry::GridPlant>& in_view, const Strip& strip,
                               bool nuisance, Eigen::Matrix2d* prior_out) {
  const TrackerOptions& options = h.options();
  std::vector<int> order = strip.plants;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return in_view[static_cast<size_t>(a)].m < in_view[static_cast<size_t>(b)].m;
  });
  std::vector<Prediction> preds;
  Eigen::Matrix2d prior = Eigen::Matrix2d::Zero();
  const double w = 1.0 / static_cast<double>(order.size());
  for (const int i : order) {
    const auto& g = in_view[static_cast<size_t>(i)];
    preds.push_back(PredictPlant(h, filter, s, g.m, g.n));
    if (nuisance) preds.back().jacobian.rightCols<3>() = preds.back().bounce_jacobian;
    if (filter.OffsetIndex(g.m, g.n) < 0 && options.plant_offsets) {
      prior += w * w * NewPlantPrior(options, preds.back());
    }
  }
  StripPrediction out = PredictStrip(preds);
  if (prior_out) *prior_out = prior;
  return out;
}

}  // namespace plantscale::tracking
