#include "engine/tracking/association.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>

#include "engine/tracking/plant_point_model.h"
#include "engine/tracking/strip_model.h"

namespace plantscale::tracking {

using geometry::GridState;

FeatureFlags MarkSkippedFeatures(const TrackerOptions& options, std::span<const Feature> features,
                                 const std::vector<geometry::GridPlant>& in_view) {
  FeatureFlags flags;
  std::vector<bool>& skipped = flags.skipped;
  std::vector<bool>& merged = flags.merged;
  skipped.assign(features.size(), false);
  merged.assign(features.size(), false);
  const double min_area_m2 = options.min_feature_area_fraction * std::numbers::pi *
                             options.crop_radius_m * options.crop_radius_m;
  size_t usable = 0;
  for (size_t j = 0; j < features.size(); ++j) {
    const Feature& f = features[j];
    merged[j] = options.skip_merged_features &&
                std::count_if(in_view.begin(), in_view.end(),
                              [&](const auto& g) { return f.BoxHolds(g.image_px); }) >= 2;
    skipped[j] = merged[j] || f.area_m2 < min_area_m2;
    usable += !skipped[j] && !f.clipped;
  }
  // Too few others left: the merged blobs are what there is to track,
  // unless strips are taken (then no merged blob is one plant's centroid).
  if (2 * usable < in_view.size()) {
    for (size_t j = 0; j < features.size(); ++j) skipped[j] = options.merged_row_strips && merged[j];
  }
  return flags;
}

std::vector<Candidate> Gate(const ObservationModel& h, const GridFilter& filter, const GridState& s,
                            std::span<const Feature> features, const FeatureFlags& flags,
                            const std::vector<geometry::GridPlant>& in_view,
                            const Eigen::Vector3d& bounce_prior) {
  const TrackerOptions& options = h.options();
  std::vector<Candidate> candidates;
  for (int i = 0; i < static_cast<int>(in_view.size()); ++i) {
    const auto& g = in_view[static_cast<size_t>(i)];
    const Prediction pred = PredictPlant(h, filter, s, g.m, g.n);
    const Eigen::Matrix2d hph =
        PredictionCovariance(options, filter, pred, filter.OffsetIndex(g.m, g.n), bounce_prior);
    for (int j = 0; j < static_cast<int>(features.size()); ++j) {
      const Feature& f = features[static_cast<size_t>(j)];
      if (f.clipped || flags.skipped[static_cast<size_t>(j)] ||
          (f.ground_m - g.ground_m).squaredNorm() > 0.16) {
        continue;
      }
      const Measurement z = h.Measure(f);
      const Eigen::Vector2d nu = z.value - pred.value;
      const Eigen::Matrix2d innovation_cov = hph + z.covariance;
      const double gamma2 = nu.dot(innovation_cov.ldlt().solve(nu));
      if (gamma2 <= options.gate_chi2) candidates.push_back({i, j, gamma2});
    }
  }
  return candidates;
}

std::vector<Candidate> Associate(std::vector<Candidate> candidates, size_t plants, size_t features) {
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.gamma2 < b.gamma2; });
  std::vector<bool> plant_taken(plants, false);
  std::vector<bool> feature_taken(features, false);
  std::vector<Candidate> matches;
  for (const Candidate& c : candidates) {
    if (plant_taken[static_cast<size_t>(c.plant)] || feature_taken[static_cast<size_t>(c.feature)]) {
      continue;
    }
    plant_taken[static_cast<size_t>(c.plant)] = true;
    feature_taken[static_cast<size_t>(c.feature)] = true;
    matches.push_back(c);
  }
  return matches;
}

std::vector<Strip> FindStrips(const ObservationModel& h, const GridFilter& filter, const GridState& s,
                              std::span<const Feature> features, const FeatureFlags& flags,
                              const std::vector<geometry::GridPlant>& in_view,
                              const std::vector<Candidate>& matches,
                              const Eigen::Vector3d& bounce_prior) {
  const TrackerOptions& options = h.options();
  std::vector<bool> matched(in_view.size(), false);
  for (const Candidate& c : matches) matched[static_cast<size_t>(c.plant)] = true;
  const bool nuisance = filter.layout().nuisance_bounce();
  std::vector<Strip> strips;
  for (size_t j = 0; j < features.size(); ++j) {
    const Feature& f = features[j];
    if (!flags.merged[j] || f.clipped) continue;
    Strip strip{static_cast<int>(j), {}};
    bool one_row = true;
    std::optional<int> row;
    for (size_t i = 0; i < in_view.size(); ++i) {
      if (!f.BoxHolds(in_view[i].image_px)) continue;
      one_row = one_row && (!row || *row == in_view[i].n);
      row = in_view[i].n;
      if (!matched[i]) strip.plants.push_back(static_cast<int>(i));
    }
    if (!one_row || strip.plants.size() < 2) continue;
    Eigen::Matrix2d prior = Eigen::Matrix2d::Zero();
    const StripPrediction sp = PredictStripAt(h, filter, s, in_view, strip, false, &prior);
    const Measurement z = h.Measure(f);
    Eigen::Matrix2d cov = sp.jacobian * filter.p() * sp.jacobian.transpose() + prior + z.covariance;
    if (nuisance) cov += sp.bounce_jacobian * bounce_prior.asDiagonal() * sp.bounce_jacobian.transpose();
    const double nu = sp.normal.dot(z.value - sp.value);
    const double var = sp.normal.dot(cov * sp.normal) + options.strip_sd_m * options.strip_sd_m;
    // Whatever the covariance allows, a strip is its row's only when its
    // centroid lies within strip_max_offset_fraction of a row spacing
    // across from it: a grid held far off (after a loss) would otherwise
    // take a neighbouring row's strips for its own.
    if (std::abs(nu) > options.strip_max_offset_fraction * s.row_spacing_m) continue;
    if (nu * nu <= options.strip_gate_chi2 * var) strips.push_back(std::move(strip));
  }
  return strips;
}

bool Observable(const TrackerOptions& options, const std::vector<Candidate>& matches,
                const std::vector<geometry::GridPlant>& in_view, FrameReport& report) {
  std::vector<int> rows;
  std::vector<int> lines;
  for (const Candidate& c : matches) {
    rows.push_back(in_view[static_cast<size_t>(c.plant)].n);
    lines.push_back(in_view[static_cast<size_t>(c.plant)].m);
  }
  std::sort(rows.begin(), rows.end());
  std::sort(lines.begin(), lines.end());
  const int distinct_rows = static_cast<int>(std::unique(rows.begin(), rows.end()) - rows.begin());
  const int distinct_lines =
      static_cast<int>(std::unique(lines.begin(), lines.end()) - lines.begin());
  const int needed = options.estimate_spacing ? 3 : 2;
  if (report.matched >= needed &&
      !(options.estimate_spacing && (distinct_rows < 2 || distinct_lines < 2))) {
    return true;
  }
  std::ostringstream out;
  out << "not observable: " << report.matched << " matched feature(s) of " << report.predicted
      << " predicted plants";
  if (options.estimate_spacing && report.matched >= needed) {
    out << ", all on one " << (distinct_rows < 2 ? "row" : "plant line");
  } else {
    out << " (" << needed << " needed)";
  }
  report.skipped_reason = out.str();
  return false;
}

}  // namespace plantscale::tracking
