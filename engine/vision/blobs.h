#pragma once
// Blobs: connected plant-matter regions of a binary mask (thesis §2.3.7).
//
// The thesis chain-codes each blob's outline (Freeman) and reads centroid and
// area from it; we label 8-connected runs with a union-find over run-length
// segments, which gives the same blobs, centroids and areas in one pass over
// the mask, and trace the outer contour (Moore neighbour, in Freeman chain
// order) only when asked. Everything reuses its buffers: after the first
// frame of a given size no memory is allocated unless a frame has more runs
// or blobs than any before it.

#include <opencv2/core.hpp>
#include <Eigen/Core>
#include <Eigen/LU>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/vision/row_bits.h"

namespace plantscale::vision {

struct BlobOptions {
  int min_area_px = 1;          // blobs smaller than this are dropped
  bool trace_contours = false;  // fill Blob::contour (outer boundary)

  OptionErrors Validate() const;
};

struct Blob {
  int id = 0;  // 1..n in raster order of each blob's first pixel
  int area_px = 0;
  // Pixel coordinates: origin top-left, the first pixel's centre is (0.5, 0.5).
  Eigen::Vector2d centroid_px{0.0, 0.0};
  Eigen::Matrix2d covariance_px2 = Eigen::Matrix2d::Zero();  // second central moments
  cv::Rect bbox_px;
  std::vector<cv::Point> contour;  // outer boundary pixels, clockwise from the top-left one
  // Projected through the CameraModel onto the virtual ground plane (vehicle
  // frame, metres); on_ground is false when the centroid's ray misses it.
  bool on_ground = false;
  Eigen::Vector2d ground_m{0.0, 0.0};
  double ground_area_m2 = 0.0;  // area_px × the pixel's footprint at the centroid
  // The part of it the mask held before the segmenter grew it (hull and
  // soil growth, segmenter.h; BlobExtractor::SetCores): its pixel count, centroid and
  // second central moments. Growth adds the shaded rim and a ring of soil
  // lit by the smoothing; a plant's size is read on the core. core_area_px
  // < 0: no growth known, the core is the blob itself (CoreOf).
  int core_area_px = -1;
  Eigen::Vector2d core_centroid_px{0.0, 0.0};
  Eigen::Matrix2d core_covariance_px2 = Eigen::Matrix2d::Zero();
  // A learned model's class of the blob (BlobExtractor::SetClasses): the
  // class (0 soil, 1 crop, 2 weed, as vision::PixelClass) most of its pixels
  // take, and the mean over all its pixels of the probability of that class
  // where a pixel chose it (0 where it chose another): agreement and
  // certainty in one number. −1: no model ran.
  int learned_class = -1;
  double learned_confidence = 0.0;
};

// A blob's core (above): its pixel count, centroid and covariance.
struct BlobCore {
  double area_px = 0.0;
  Eigen::Vector2d centroid_px{0.0, 0.0};
  Eigen::Matrix2d covariance_px2 = Eigen::Matrix2d::Zero();
};
BlobCore CoreOf(const Blob& blob);

class BlobExtractor {
 public:
  explicit BlobExtractor(const BlobOptions& options = {});

  // Labels the non-zero pixels of `mask` (CV_8UC1). The span stays valid
  // until the next call.
  std::span<const Blob> Extract(const cv::Mat& mask);
  // Extract, then project every blob onto the camera's virtual ground plane.
  std::span<const Blob> Extract(const cv::Mat& mask, const geometry::CameraModel& camera);
  // The same from runs already labelled (detail::LabelRuns, 8-connected,
  // each run's parent its set's root) of a mask of `size`: HullGrower's
  // labelling of the mask before growth. No contours (the mask they were
  // found in may have changed since).
  // Throws InternalError when the options trace contours.
  std::span<const Blob> ExtractLabelled(std::span<const detail::RowRun> runs,
                                        std::span<const int> parent,
                                        const geometry::CameraModel* camera = nullptr);

  // The last extraction's runs (raster order).
  std::span<const detail::RowRun> runs() const { return runs_; }
  // Sets every blob's core (Blob::core_area_px...) from `core`, the runs of
  // the mask before growth in raster order, each inside a run of the last
  // extraction's mask (growth only adds pixels).
  void SetCores(std::span<const detail::RowRun> core);
  // Sets every blob's learned class and confidence (Blob::learned_class)
  // from per-pixel classes (CV_8UC1, 0…2) and the probability of each
  // pixel's class (CV_32FC1), both of the last extraction's mask's size.
  // Throws DataError when they do not fit.
  void SetClasses(const cv::Mat& classes, const cv::Mat& confidence);

  const BlobOptions& options() const { return options_; }

 private:
  using Run = detail::RowRun;  // pixels [u_begin, u_end) of image row v
  void FindRuns(const cv::Mat& mask);
  void Accumulate(const cv::Mat& mask);
  void Project(const geometry::CameraModel& camera);

  BlobOptions options_;
  std::vector<Run> runs_;
  std::vector<uint64_t> row_bits_;  // one mask row, a bit a pixel
  std::vector<int> parent_;
  std::vector<int> run_blob_;     // blob slot per root run, -1 before assignment
  std::vector<double> moments_;   // per blob: n, Σu, Σv, Σu², Σv², Σuv (6 each)
  std::vector<cv::Rect> boxes_;
  std::vector<int> first_run_;
  std::vector<int> slot_blob_;    // per blob slot: its index in pool_, -1 when dropped
  std::vector<double> core_moments_;  // SetCores' sums, per blob
  std::vector<double> class_sums_;    // SetClasses' sums, per blob
  std::vector<Blob> pool_;        // blob storage kept across frames
  int count_ = 0;
};

// Outer boundary of the 8-connected blob containing `start` (its top-left
// pixel), traced by Moore-neighbour search; clockwise in image coordinates.
void TraceOuterContour(const cv::Mat& mask, cv::Point start, std::vector<cv::Point>& contour);

// Freeman chain code of a closed 8-connected contour (0 = +u, counting
// anticlockwise on screen: 1 = up-right, 2 = up, ...), thesis fig. 2.16.
void FreemanChainCode(std::span<const cv::Point> contour, std::vector<uint8_t>& codes);

}  // namespace plantscale::vision
