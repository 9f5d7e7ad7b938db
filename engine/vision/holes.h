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

namespace plantscale::vision {

class HoleFiller {
 public:
  // Sets every hole of `mask` (CV_8UC1, 0 soil, non-zero plant) of at most
  // `max_area_px` pixels to 255. Returns the number of pixels filled.
  int Fill(cv::Mat& mask, int max_area_px);

 private:
  struct Run {
    int v, u_begin, u_end;  // soil pixels [u_begin, u_end) of image row v
  };
  int Find(int i);

  std::vector<Run> runs_;
  std::vector<int> parent_;
  std::vector<uint64_t> bits_;
  std::vector<int> area_;        // per root run
  std::vector<uint8_t> border_;  // per root run: reaches the image border
};

}  // namespace plantscale::vision
