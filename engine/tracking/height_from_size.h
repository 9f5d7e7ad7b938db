#pragma once
// Height from size (TrackerOptions::height_from_size): a plant's blob
// scales with its leaf span, and its centroid height with it (the inverted
// hemisphere of thesis §2.3.8), so a blob of equivalent radius ρ = √(A/π)
// against the running mean ρ̄ of the crop's matched blobs in its band of
// image rows says the plant's own centroid height δh = h_l·(s − 1), s =
// (ρ + e)/(ρ̄ + e). A pseudo-observation of each matched plant's δh state
// with σ size_height_sd_m: the model is h(x) = δh, its Jacobian the unit
// row at δh (over σ once whitened). Beyond the thesis. Its tests:
// height_from_size_test.cc.

#include <optional>
#include <span>
#include <vector>

#include "engine/geometry/centroid_height.h"
#include "engine/tracking/feature.h"
#include "engine/tracking/grid_tracker_internal.h"
#include "engine/tracking/kalman_filter.h"

namespace plantscale::tracking {

// A blob of `area_m2` in a band of mean equivalent radius `band_radius_m`,
// located at height `located_height_m` (h_l): the plant's δh, or none when
// its size ratio is outside [1/size_ratio_max, size_ratio_max] (a merged
// or cut blob says nothing of its plant's size).
std::optional<double> HeightFromBlob(const TrackerOptions& options, double area_m2,
                                     double band_radius_m, double located_height_m);

class HeightFromSize {
 public:
  // image_height_px: the camera's, cut into options.size_bands bands.
  HeightFromSize(const TrackerOptions& options, int image_height_px);

  // The whitened pseudo-observation (kalman_filter.h) of the δh of the
  // plants matched to `features`, at the filter's state: one row per plant
  // with states, an unclipped blob and a band of size_min_samples blobs.
  // No rows when none qualifies.
  PseudoObservation Observe(const GridFilter& filter, const geometry::CentroidHeights& heights,
                            std::span<const Feature> features,
                            std::span<const SizeMatch> matches) const;
  // Adds the matched blobs to their bands' means (after Observe, so that
  // no blob is compared with a mean it is part of).
  void Learn(std::span<const Feature> features, std::span<const SizeMatch> matches);
  int band_samples(int band) const { return band_samples_[static_cast<size_t>(band)]; }
  double band_radius_m(int band) const { return band_radius_m_[static_cast<size_t>(band)]; }

 private:
  size_t BandOf(const Feature& f) const;

  TrackerOptions options_;
  int image_height_px_;
  // Per band of image rows: running mean equivalent radius √(A/π) of
  // matched crop blobs, and how many went in.
  std::vector<double> band_radius_m_;
  std::vector<int> band_samples_;
};

}  // namespace plantscale::tracking
