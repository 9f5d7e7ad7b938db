#pragma once
// Holes in a plant mask: soil regions that plant matter encloses on every
// side. In near-infrared, a leaf shaded by the leaves above it (or a gap
// between overlapping leaves) can fall below the plant threshold; it then
// shows as a hole in the plant's blob, which takes its pixels from the crop's
// footprint and moves its centroid off the plant's (thesis fig. 2.18; our
// presets lose 3–8 % of crop pixels this way). Filling them is a
// topological step, not a threshold one: only soil that the plant surrounds
// is touched, so no soil beside a plant is ever added.
//
// Soil is 4-connected (the complement of 8-connected plant blobs, blobs.h):
// soil runs of adjacent rows join when they share a column. A region is a
// hole when none of its runs reaches the image border. Run-length union-find
// as BlobExtractor's; buffers are kept, so frames after the first allocate
// nothing.

#include <opencv2/core.hpp>
#include <array>
#include <cstdint>
#include <vector>

#include "engine/vision/row_bits.h"

namespace plantscale::vision {

namespace detail {

// The step NotchCloser and HullGrower share: a grown mask (a superset of
// the mask, both as bit rows of `words` words, row_bits.h) is kept only in
// its 8-connected regions that hold at most one of the mask's blobs.
class GrowthWithoutJoins {
 public:
  // Labels the mask's bits (8-connected); runs() and parent() then hold its
  // runs, each pointing at its blob's root run, and row_start() row v's
  // first run.
  void LabelMask(const std::vector<uint64_t>& mask_bits, int width, int height);
  const std::vector<RowRun>& runs() const { return mask_runs_; }
  const std::vector<int>& parent() const { return mask_parent_; }
  // Sets to 255 the pixels of `mask` (the image of the labelled bits) that
  // are in `grown_bits` but not the mask's bits, in regions of the grown
  // bits holding at most one counted blob; `counted` (per mask root run,
  // null: all) says which blobs count. With `small` (per mask root run), a
  // region holding two or more counted blobs is still kept unless one of
  // them is small. Returns the number of pixels set.
  int Add(const std::vector<uint64_t>& mask_bits, const std::vector<uint64_t>& grown_bits,
          const std::vector<uint8_t>* counted, cv::Mat& mask,
          const std::vector<uint8_t>* small = nullptr);

 private:
  void FindJoins(const std::vector<uint8_t>* counted, const std::vector<uint8_t>* small);
  static int PaintFresh(const RowRun& run, const std::vector<uint64_t>& mask_bits,
                        const std::vector<uint64_t>& grown_bits, size_t words, cv::Mat& mask);

  int width_ = 0, height_ = 0;
  std::vector<RowRun> mask_runs_, grown_runs_;
  std::vector<int> mask_parent_, grown_parent_, mask_row_start_, grown_row_start_;
  std::vector<int> first_blob_;  // per grown root: a counted blob's root inside it, −1 before
  std::vector<uint8_t> joins_;   // per grown root: holds two or more counted blobs
  std::vector<uint8_t> small_;   // per grown root: holds a small counted blob
};

}  // namespace detail

class HoleFiller {
 public:
  // Sets every hole of `mask` (CV_8UC1, 0 soil, non-zero plant) of at most
  // `max_area_px` pixels to 255. Returns the number of pixels filled.
  int Fill(cv::Mat& mask, int max_area_px);

 private:
  std::vector<detail::RowRun> runs_;  // soil runs
  std::vector<int> parent_;
  std::vector<uint64_t> bits_;
  std::vector<int> area_;        // per root run
  std::vector<uint8_t> border_;  // per root run: reaches the image border
};

// Notches: a shaded leaf at a plant's edge cuts a notch into its blob rather
// than a hole. The mask is closed (dilation, then erosion, by a disk of
// `radius_px`), which fills notches narrower than the disk, and the closing
// is kept only where it joins no two blobs: a closed region holding two or
// more of the mask's blobs (touching plants, a weed beside a crop) keeps
// its pixels as they were. Pixels within `radius_px` of the image border are
// never added. Bit-packed rows (64 pixels a word), so the morphology costs
// a few operations per word, and run-length union-find for the blobs;
// buffers are kept.
class NotchCloser {
 public:
  // Returns the number of pixels added to `mask` (CV_8UC1, 0 soil).
  int Close(cv::Mat& mask, int radius_px);
  // The disk: pixels (du, dv) with |du| <= DiskHalfWidth(r, dv), |dv| <= r.
  static int DiskHalfWidth(int radius_px, int dv);

 private:
  std::vector<uint64_t> mask_bits_, closed_bits_, scratch_;
  std::vector<std::vector<uint64_t>> steps_;  // a row set dilated / eroded by 0..r pixels along u
  std::vector<int> half_;                     // DiskHalfWidth per row offset
  detail::GrowthWithoutJoins keep_;
};

// Shaded leaf at a plant's edge, wider than a notch the closing fills: it
// lies inside the plant's outline, so inside the convex hull of the blob
// its bright leaves make, at a brightness (about half a lit leaf's) that
// soil away from plants does not reach but the global gain misses. Inside
// the hull of every blob of at least `min_area_px` pixels, the pixels of a
// second, lower-gain mask are added. Soil outside every hull is never
// touched, so a glint or the smoothing's halo beside a plant stays soil;
// soil between a plant's lobes that the hull takes in is added only where
// it is brighter than the lower gain (the halo's core). As with notches,
// growth that would join two blobs (touching plants, preset A) is not kept:
// a grown region holding two or more of the mask's blobs of that size keeps
// its pixels as they were. All in bit rows (64 pixels a word, as
// NotchCloser): each blob's hull from its rows' extreme pixels, its spans
// set as bits and ANDed with the low mask's; buffers are kept.
class HullGrower {
 public:
  // Sets to 255 the pixels of `mask` (CV_8UC1, 0 soil) that are set in
  // `low` (CV_8UC1, same size) and lie inside the convex hull of a blob of
  // `mask` (8-connected) of at least `min_area_px` pixels, unless the grown
  // region joins two such blobs. Returns the number of pixels added.
  int Grow(cv::Mat& mask, const cv::Mat& low, int min_area_px);
  // The mask's runs and blobs as they were before the last Grow (its
  // labelling, for BlobExtractor::ExtractLabelled).
  const std::vector<detail::RowRun>& mask_runs() const { return keep_.runs(); }
  const std::vector<int>& mask_parent() const { return keep_.parent(); }

 private:
  std::vector<uint64_t> mask_bits_, hull_bits_, grown_bits_, low_bits_;
  std::vector<int> area_, first_run_, next_run_;
  std::vector<uint8_t> counted_;          // per root run: the blob gets a hull
  std::vector<std::array<int, 3>> rows_;  // a blob's rows: v, first u, last u
  std::vector<cv::Point> left_, right_;   // its hull's sides, (v, u) vertices
  std::vector<double> left_u_, right_u_;  // and their u per row
  detail::GrowthWithoutJoins keep_;
};

}  // namespace plantscale::vision
