#pragma once
// Growth of plant blobs into the shaded rim around them, judged against the
// soil next to them. A plant's lower or shaded leaves (under its own upper
// leaves, or beyond a band of shade that splits it) reflect about half what
// its lit leaves do: below the local threshold's gain over the soil level B,
// and B is the soil's lower envelope, which bright soil texture itself
// reaches 1.5 times. So no ratio to B tells shaded leaf from bright soil.
// The soil right around the plant does: shaded leaf stands several standard
// deviations above that soil's mean, bright clods and stones mostly do not.
//
// Per pixel, the soil mean μ and standard deviation σ come from a
// `window_px` square box over the pixels more than `clearance_px` from the
// mask (box sums of value, square and count, so the cost does not depend
// on the window), on the unsmoothed plant image after a 3×3 Gaussian (the
// σ = 2 image's halo would lift the soil by the plant's own light). A
// pixel outside the mask is a candidate where its value is at least
// μ + z·max(σ, 1) and the box held at least `min_soil_samples` soil pixels.
// Blobs of at least `min_area_px` pixels then grow into connected
// candidates, one 8-connected step at a time, at most `reach_px` steps: a
// candidate not reached from a blob (a glint, a stone) stays soil.
//
// Measured (5 seeds × 20 frames, `evaluate segmentation`, after notches,
// holes and hull growth), plant pixel recall / precision, off → z 3:
// B 0.922 / 0.975 → 0.962 / 0.963, D 0.930 / 0.825 → 0.947 / 0.803,
// C 0.968 / 0.985 → 0.978 / 0.983, A 0.959 / 0.994 → 0.962 / 0.992.

#include <opencv2/core.hpp>
#include <cstdint>
#include <vector>

#include "engine/common/options.h"
#include "engine/vision/holes.h"

namespace plantscale::vision {

struct SoilGrowthOptions {
  double z = 3.0;             // candidate: value >= μ + z·max(σ, 1); 0: off
  int reach_px = 6;           // growth steps from a blob (pixels)
  int window_px = 63;         // soil statistics box (odd, pixels)
  int clearance_px = 4;       // soil samples lie further than this from the mask
  int min_soil_samples = 50;  // fewer soil pixels in the box: no candidate
  int min_area_px = 30;       // blobs that grow
  // Growth that joins two blobs of at least min_area_px is refused
  // (holes.h, GrowthWithoutJoins). Off by default: most joins it refuses
  // are the two halves of one plant that a band of shade split (preset B
  // recall 0.946 with it, 0.962 without, at the same precision), and the
  // tracker measures the blobs from before any growth.
  bool refuse_joins = false;

  bool enabled() const { return z > 0.0; }
  OptionErrors Validate() const;
};

class SoilGrower {
 public:
  explicit SoilGrower(const SoilGrowthOptions& options = {});

  // `plant`: the unsmoothed plant image (CV_8UC1, plants bright); `mask`:
  // CV_8UC1 of the same size, 0 soil, 255 plant. Sets grown pixels to 255
  // and returns how many. Throws DataError on a type or size mismatch.
  int Grow(const cv::Mat& plant, cv::Mat& mask);

  // The candidates of the last Grow (CV_8UC1, 255 candidate), for tests and
  // figures.
  const cv::Mat& candidates() const { return candidate_; }
  const SoilGrowthOptions& options() const { return options_; }
  // The mask's runs and blobs as they were before the last Grow (its
  // labelling, for BlobExtractor::ExtractLabelled).
  const std::vector<detail::RowRun>& mask_runs() const { return keep_.runs(); }
  const std::vector<int>& mask_parent() const { return keep_.parent(); }

 private:
  void SoilStatistics(const cv::Mat& mask);
  void Candidates(const cv::Mat& mask);
  int AddRefusingJoins(cv::Mat& mask);

  SoilGrowthOptions options_;
  cv::Mat kernel_;
  cv::Mat smooth_, near_, weight_, value_, square_, count_, sum_, sum_sq_;
  cv::Mat candidate_, labels_, stats_, centroids_, seeds_, allowed_, grown_, step_;
  std::vector<uint64_t> mask_bits_, grown_bits_;
  std::vector<int> area_;         // per root run of the mask
  std::vector<uint8_t> counted_;  // per root run: the blob grows
  detail::GrowthWithoutJoins keep_;
};

}  // namespace plantscale::vision
