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
#include <cstdint>
#include <vector>

#include "engine/vision/row_bits.h"

namespace plantscale::vision {

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
  std::vector<detail::RowRun> mask_runs_, closed_runs_;
  std::vector<int> mask_parent_, closed_parent_, mask_row_start_, closed_row_start_;
  std::vector<int> first_blob_;   // per closed root: a mask blob root inside it, −1 before
  std::vector<uint8_t> joins_;    // per closed root: holds two or more mask blobs
  std::vector<int> half_;         // DiskHalfWidth per row offset
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
// its pixels as they were. Hull of each blob
// from its runs' end points (run-length union-find as BlobExtractor's),
// filled with cv::fillConvexPoly; buffers are kept.
class HullGrower {
 public:
  // Sets to 255 the pixels of `mask` (CV_8UC1, 0 soil) that are set in
  // `low` (CV_8UC1, same size) and lie inside the convex hull of a blob of
  // `mask` (8-connected) of at least `min_area_px` pixels, unless the grown
  // region joins two such blobs. Returns the number of pixels added.
  int Grow(cv::Mat& mask, const cv::Mat& low, int min_area_px);

 private:
  std::vector<uint64_t> bits_;
  std::vector<detail::RowRun> runs_, grown_runs_;
  std::vector<int> parent_, area_, first_point_, next_point_;
  std::vector<int> grown_parent_, grown_row_start_, first_blob_;
  std::vector<uint8_t> joins_;  // per grown root: holds two or more blobs
  std::vector<cv::Point> ends_, points_, hull_points_;
  cv::Mat hull_, grown_;
};

}  // namespace plantscale::vision
