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
// The soil mean μ and standard deviation σ come from the pixels more than
// `clearance_px` from the mask, on the unsmoothed plant image after a 3×3
// Gaussian (the σ = 2 image's halo would lift the soil by the plant's own
// light), sampled at every second pixel of every fourth row, summed per
// `cell_px` cell and over a square of `window_cells` cells around each
// cell (box sums of count, value and square: the cost does not depend on
// the window). With trim_z, a second pass leaves out the samples above
// the first pass's μ + trim_z·σ (bright stones and glints inflate σ). Each
// cell's threshold μ + z·max(σ, 1) is interpolated bilinearly to the
// pixels, as the local threshold's soil level is (cell_grid.h); a pixel
// outside the mask at or above it is a candidate, unless the window held
// fewer than `min_soil_samples` samples. Blobs of at least `min_area_px`
// pixels then grow into connected candidates, one 8-connected step at a
// time, at most `reach_px` steps: a candidate not reached from a blob (a
// glint, a stone) stays soil.
//
// Cost: only the pixels growth can get to (within reach_px of a blob) are
// smoothed and judged; the statistics need every cell. Bit rows (64 pixels
// a word) for the clearance, the band, the seeds and the growth, as
// holes.h; SSE2 for the samples' sums and the candidates' compare; buffers
// are kept. The soil it takes lies within reach_px of a plant.
//
// Measured (accuracy, speed, what it costs the treatment):
// docs/results/2026-11-26-segmentation.md.

#include <opencv2/core.hpp>
#include <array>
#include <cstdint>
#include <vector>

#include "engine/common/options.h"
#include "engine/vision/cell_grid.h"
#include "engine/vision/holes.h"

namespace plantscale::vision {

struct SoilGrowthOptions {
  double z = 2.0;             // candidate: value >= μ + z·max(σ, 1); 0: off
  // Samples above the first pass's μ + trim_z·max(σ, 1) are left out of a
  // second (0: one pass). At the same recall it keeps more precision than
  // a lower z.
  double trim_z = 2.5;
  int reach_px = 6;           // growth steps from a blob (pixels)
  int cell_px = 8;            // soil statistics grid (a power of two, 8–64)
  int window_cells = 7;       // soil statistics box, cells (odd)
  int clearance_px = 4;       // soil samples lie further than this from the mask
  int min_soil_samples = 12;  // fewer samples in the box: no candidate
  int min_area_px = 30;       // blobs that grow
  // Growth may join blobs only when each of them has at least this many
  // pixels, specks included (0: any join; larger than any blob: none).
  // Shade splits a plant into parts that should join again; but a weed beside a
  // crop should not join it in spray-weed mode, where the crop's blob would
  // take it (treatment::SegmenterOptionsFor). The tracker measures the
  // blobs from before any growth either way.
  int join_min_area_px = 0;

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

  // The candidates over the whole image by the last Grow's thresholds
  // (CV_8UC1, 255 candidate; all 0 when that Grow had no blob to grow), for
  // tests and figures, while that Grow's plant image is unchanged. Grow
  // itself judges only the pixels within reach_px of a blob, the only ones
  // growth can get to.
  cv::Mat Candidates();
  const SoilGrowthOptions& options() const { return options_; }
  // The mask's runs and blobs as they were before the last Grow (its
  // labelling, for BlobExtractor::ExtractLabelled).
  const std::vector<detail::RowRun>& mask_runs() const { return keep_.runs(); }
  const std::vector<int>& mask_parent() const { return keep_.parent(); }

 private:
  // The steps of Grow(): label the mask's blobs (mask_bits_, keep_); mark the
  // blobs of min_area_px as seeds (false when there are none); model the
  // soil around them and grow; write the growth into the mask.
  void LabelBlobs(const cv::Mat& mask);
  bool SeedBits(size_t words);
  void ModelSoilAndGrow(const cv::Mat& plant);
  int AddGrowth(cv::Mat& mask);
  void ClearanceBits(int width, int height);
  // Sums the samples (capped: those at or below their cell's cap_) per
  // cell, then box-sums them into mean_ and sd_.
  void SoilStatistics(bool capped);
  // band_: the pixels outside the mask within reach_px (a square) of a
  // seed, the only ones growth can get to.
  void Band(int width, int height);
  // smooth_ on the sampled rows and the band's 64-px words (everywhere:
  // all).
  void Smooth(const cv::Mat& plant, bool everywhere);
  void Thresholds();
  // Candidate pixels as bits, in the band (everywhere: all outside the
  // mask).
  void CandidateBits(bool everywhere, std::vector<uint64_t>& bits);
  void GrowBits(int width, int height);

  SoilGrowthOptions options_;
  int cells_w_ = 0, cells_h_ = 0;
  cv::Mat plant_;   // the last Grow's plant image (a header: Candidates() reads it)
  cv::Mat smooth_;  // 3×3 Gaussian of the plant image where needed
  // Per cell, row-major: sample sums, their box sums, soil mean and sd (−1:
  // no statistics), the second pass's caps.
  std::vector<int32_t> n_, s1_, s2_;
  std::array<std::vector<int64_t>, 3> down_;  // column sums of the boxes
  std::vector<double> box_n_, box_s1_, box_s2_, mean_, sd_;
  std::vector<uint8_t> cap_;
  cv::Mat cell_threshold_, expanded_;  // CV_8U: per cell, per cell row along u
  CellRowExpander expander_;
  std::vector<uint64_t> mask_bits_, near_bits_, scratch_, candidate_bits_, seed_bits_,
      grown_bits_, all_bits_, band_;
  std::vector<uint16_t> col_;              // vertical taps of the smoothing
  std::vector<int> area_;         // per root run of the mask
  std::vector<uint8_t> small_;    // per root run: under join_min_area_px
  detail::GrowthWithoutJoins keep_;
};

}  // namespace plantscale::vision
