#include "engine/tracking/height_from_size.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace plantscale::tracking {

std::optional<double> HeightFromBlob(const TrackerOptions& options, double area_m2,
                                     double band_radius_m, double located_height_m) {
  const double ratio = (std::sqrt(area_m2 / std::numbers::pi) + options.size_edge_loss_m) /
                       (band_radius_m + options.size_edge_loss_m);
  if (!(ratio <= options.size_ratio_max && ratio * options.size_ratio_max >= 1.0)) return std::nullopt;
  return located_height_m * (ratio - 1.0);
}

HeightFromSize::HeightFromSize(const TrackerOptions& options, int image_height_px)
    : options_(options),
      image_height_px_(image_height_px),
      band_radius_m_(static_cast<size_t>(options.size_bands), 0.0),
      band_samples_(static_cast<size_t>(options.size_bands), 0) {}

size_t HeightFromSize::BandOf(const Feature& f) const {
  const int bands = options_.size_bands;
  const int b = static_cast<int>(f.image_px.y() * bands / std::max(1, image_height_px_));
  return static_cast<size_t>(std::clamp(b, 0, bands - 1));
}

PseudoObservation HeightFromSize::Observe(const GridFilter& filter,
                                          const geometry::CentroidHeights& heights,
                                          std::span<const Feature> features,
                                          std::span<const SizeMatch> matches) const {
  const double sd = options_.size_height_sd_m;
  const Eigen::VectorXd& x = filter.x();
  PseudoObservation z{Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(matches.size()), x.size()),
                      Eigen::VectorXd::Zero(static_cast<Eigen::Index>(matches.size())),
                      {}};
  Eigen::Index rows = 0;
  for (const SizeMatch& s : matches) {
    const Feature& f = features[static_cast<size_t>(s.feature)];
    const int offset = filter.OffsetIndex(s.m, s.n);
    const size_t b = BandOf(f);
    if (offset < 0 || f.clipped || !(f.area_m2 > 0.0) ||
        band_samples_[b] < options_.size_min_samples) {
      continue;
    }
    const std::optional<double> dh =
        HeightFromBlob(options_, f.area_m2, band_radius_m_[b], heights.HeightAt(f.image_px));
    if (!dh) continue;
    const int h = offset + 2;
    z.factor(rows, h) = 1.0 / sd;
    z.residual(rows) = (*dh - x(h)) / sd;
    z.support.push_back(h);
    ++rows;
  }
  z.factor.conservativeResize(rows, Eigen::NoChange);
  z.residual.conservativeResize(rows);
  std::sort(z.support.begin(), z.support.end());
  return z;
}

void HeightFromSize::Learn(std::span<const Feature> features, std::span<const SizeMatch> matches) {
  for (const SizeMatch& s : matches) {
    const Feature& f = features[static_cast<size_t>(s.feature)];
    if (f.clipped || !(f.area_m2 > 0.0)) continue;
    const size_t b = BandOf(f);
    const double rho = std::sqrt(f.area_m2 / std::numbers::pi);
    int& n = band_samples_[b];
    // The plain mean until the EMA's weight takes over.
    const double w = std::max(options_.size_mean_weight, 1.0 / (n + 1));
    band_radius_m_[b] += w * (rho - band_radius_m_[b]);
    ++n;
  }
}

}  // namespace plantscale::tracking
