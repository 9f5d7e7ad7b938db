#include "engine/tracking/pseudo_observation.h"

#include <Eigen/Dense>
#include <cmath>

#include "engine/tracking/plant_point_model.h"
#include "engine/tracking/strip_model.h"

namespace plantscale::tracking {

PseudoObservation StackMeasurements(const ObservationModel& h, const GridFilter& filter,
                                    const geometry::GridState& s, std::span<const Feature> features,
                                    const std::vector<geometry::GridPlant>& in_view,
                                    const std::vector<Candidate>& matches,
                                    const std::vector<Strip>& strips, bool nuisance) {
  const TrackerOptions& options = h.options();
  const StateLayout& layout = filter.layout();
  const int n = static_cast<int>(filter.x().size());
  const int persistent = nuisance ? n - 3 : n;
  const Eigen::Index stacked =
      2 * static_cast<Eigen::Index>(matches.size()) + static_cast<Eigen::Index>(strips.size());
  PseudoObservation compressed{Eigen::MatrixXd::Zero(stacked, n), Eigen::VectorXd(stacked), {}};
  std::vector<bool> touched(static_cast<size_t>(n), false);
  for (int i = 0; i < layout.head(); ++i) touched[static_cast<size_t>(i)] = true;
  if (nuisance) {
    for (int i = persistent; i < n; ++i) touched[static_cast<size_t>(i)] = true;
  }
  for (size_t k = 0; k < matches.size(); ++k) {
    const auto& g = in_view[static_cast<size_t>(matches[k].plant)];
    Prediction pred = PredictPlant(h, filter, s, g.m, g.n);
    if (nuisance) pred.jacobian.rightCols<3>() = pred.bounce_jacobian;
    const int offset = filter.OffsetIndex(g.m, g.n);
    for (int i = 0; offset >= 0 && i < layout.plant_states(); ++i) {
      touched[static_cast<size_t>(offset + i)] = true;
    }
    const Measurement z = h.Measure(features[static_cast<size_t>(matches[k].feature)]);
    // Whitening by R's Cholesky factor C: eqs. 4.77–4.78 as LᵀL and Lᵀr.
    const Eigen::LLT<Eigen::Matrix2d> c(z.covariance);
    const Eigen::Index r = 2 * static_cast<Eigen::Index>(k);
    compressed.factor.middleRows(r, 2) = c.matrixL().solve(pred.jacobian);
    compressed.residual.segment<2>(r) = c.matrixL().solve(z.value - pred.value);
  }
  // Each strip: one row, its lateral innovation over its σ.
  for (size_t k = 0; k < strips.size(); ++k) {
    const StripPrediction sp = PredictStripAt(h, filter, s, in_view, strips[k], nuisance);
    for (const int i : strips[k].plants) {
      const auto& g = in_view[static_cast<size_t>(i)];
      const int offset = filter.OffsetIndex(g.m, g.n);
      for (int q = 0; offset >= 0 && q < layout.plant_states(); ++q) {
        touched[static_cast<size_t>(offset + q)] = true;
      }
    }
    const Measurement z = h.Measure(features[static_cast<size_t>(strips[k].feature)]);
    const double sd =
        std::sqrt(sp.normal.dot(z.covariance * sp.normal) + options.strip_sd_m * options.strip_sd_m);
    const Eigen::Index r = 2 * static_cast<Eigen::Index>(matches.size()) + static_cast<Eigen::Index>(k);
    compressed.factor.row(r) = sp.normal.transpose() * sp.jacobian / sd;
    compressed.residual(r) = sp.normal.dot(z.value - sp.value) / sd;
  }
  for (int i = 0; i < n; ++i) {
    if (touched[static_cast<size_t>(i)]) compressed.support.push_back(i);
  }
  return compressed;
}

double UpdateOnFrame(GridFilter& filter, const ObservationModel& h, const geometry::GridState& s,
                     std::span<const Feature> features,
                     const std::vector<geometry::GridPlant>& in_view,
                     const std::vector<Candidate>& matches, const std::vector<Strip>& strips,
                     const Eigen::Vector3d& bounce_prior) {
  if (h.options().plant_offsets) {
    for (const Candidate& c : matches) {
      const auto& g = in_view[static_cast<size_t>(c.plant)];
      if (filter.OffsetIndex(g.m, g.n) < 0) filter.AddPlant(g.m, g.n);
    }
    for (const Strip& strip : strips) {
      for (const int i : strip.plants) {
        const auto& g = in_view[static_cast<size_t>(i)];
        if (filter.OffsetIndex(g.m, g.n) < 0) filter.AddPlant(g.m, g.n);
      }
    }
  }
  const bool nuisance = filter.layout().nuisance_bounce();
  const int persistent = nuisance ? filter.AppendNuisance(bounce_prior) : static_cast<int>(filter.x().size());
  const PseudoObservation z = StackMeasurements(h, filter, s, features, in_view, matches, strips, nuisance);
  const double nis = filter.Apply(z);
  if (nuisance) filter.DropNuisance(persistent);
  return nis;
}

}  // namespace plantscale::tracking
