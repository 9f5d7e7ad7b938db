#pragma once
// Plant-matter segmentation of one camera frame: plant image (NIR grey or a
// colour index), threshold, blobs. One object per camera stream; it keeps its
// buffers, so frames after the first allocate nothing.

#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <string_view>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/vision/blobs.h"
#include "engine/vision/colour_index.h"
#include "engine/vision/holes.h"
#include "engine/vision/local_threshold.h"
#include "engine/vision/pixel_classes.h"
#include "engine/vision/smoothing.h"
#include "engine/vision/soil_growth.h"

namespace plantscale::vision {

enum class ThresholdMethod {
  kFixed,     // eq. 2.14 at fixed_threshold
  kOtsu,      // Otsu's threshold per frame
  kAdaptive,  // Hague's adaptive interpolating threshold, eq. 2.15, gain α
  kLocal,     // ours: gain times a local soil level (local_threshold.h)
};
std::optional<ThresholdMethod> ParseThresholdMethod(std::string_view name);
const char* Name(ThresholdMethod method);

struct SegmenterOptions {
  ThresholdMethod method = ThresholdMethod::kLocal;
  double fixed_threshold = 128.0;  // τ, grey levels (kFixed)
  // Lowest threshold Otsu may pick (grey levels). With a colour index, a
  // pixel that is not greener than neutral (index 0 = 127.5) is never plant,
  // however the histogram splits (evening light, purple soil, haze).
  double otsu_floor = 0.0;
  double adaptive_gain = 1.64;     // α (kAdaptive); the thesis's hand-tuned value (§2.3.6)
  LocalThresholdOptions local;     // kLocal
  // Gaussian smoothing of the plant image before thresholding (sigma,
  // pixels; 0: none; σ = 2 runs as the equal-variance tent, smoothing.h). Lifts shaded leaf patches that bright leaf surrounds
  // and averages sensor noise away.
  double smoothing_px = 2.0;
  // Colour input (CV_8UC3, BGR) is turned into this index first; grey
  // input (CV_8UC1) is used as it is.
  ColourIndex colour_index = ColourIndex::kExG;
  // Holes the plant mask encloses (holes.h: shaded leaves inside a plant)
  // up to this fraction of the image are filled; 0: none. At 640×480,
  // 0.005 is 1536 pixels, a disc 44 px across. The largest holes are
  // mostly soil ringed by touching plants (preset A), and filling them
  // moves the merged blobs' centroids; too small a bound leaves big
  // plants' shaded leaves unfilled (docs/results/2026-11-27-option-choices.md).
  double fill_holes_max_fraction = 0.005;
  // Notches a shaded leaf cuts into a blob's edge narrower than a disk of
  // this radius (pixels) are closed where that joins no two blobs
  // (holes.h, NotchCloser); 0: none. It raises plant pixel recall at no
  // cost in precision (it also fills soil between a plant's lobes, which
  // the doubt band mostly covers).
  int close_notches_px = 4;
  // Local method only, after notches and holes: inside the convex hull of
  // every blob of at least hull_min_area_px pixels, plant where
  // I >= hull_gain·B (holes.h, HullGrower), for shaded leaf at a plant's
  // edge wider than a notch. 0: off; at most local.gain. It trades a little
  // precision for recall. The tracker measures the blobs before it
  // (Segmentation::track_blobs).
  double hull_gain = 1.8;
  int hull_min_area_px = 30;
  // Local method only, last: blobs grow into the shaded rim that stands
  // out of the soil around them (soil_growth.h, with its pixel figures;
  // z 0: off; treatment figures in docs/results/). The tracker measures the
  // blobs before it, as before hull growth.
  SoilGrowthOptions soil_growth;
  BlobOptions blobs;

  OptionErrors Validate() const;
};

struct Segmentation {
  cv::Mat plant_image;  // CV_8UC1, plants bright (the grey input or the colour index), smoothed
  cv::Mat mask;         // CV_8UC1, 255 plant, 0 soil
  double threshold_at_top = 0.0;     // grey-level threshold used at the top row
  double threshold_at_bottom = 0.0;  // ... and at the bottom row (differ for kAdaptive)
  std::span<const Blob> blobs;  // with their cores (Blob::core_area_px) when grown
  // The blobs before hull and soil growth (SegmenterOptions::hull_gain,
  // soil_growth; the same as `blobs` without them): what the grid tracker
  // measures: grown blobs of touching plants (preset A) pull the tracker's
  // measurements apart and lose the grid more often. The classifier and
  // the pixel labels take the grown ones.
  std::span<const Blob> track_blobs;
};

class Segmenter {
 public:
  explicit Segmenter(const SegmenterOptions& options);

  // Throws DataError for an empty image or one that is not CV_8UC1 / CV_8UC3.
  // The result stays valid until the next call.
  const Segmentation& Process(const cv::Mat& image);
  // The same, with blobs projected onto the camera's virtual ground plane.
  const Segmentation& Process(const cv::Mat& image, const geometry::CameraModel& camera);
  // The same, with a learned model's classes of the image (its size): the
  // mask is cut where crop meets weed (ClassCut), before and after growth,
  // so that a weed touching a crop is a blob of its own, and every blob
  // (and tracker blob) carries its learned class and confidence.
  // Throws DataError when the classes are not of the image's size.
  const Segmentation& Process(const cv::Mat& image, const geometry::CameraModel& camera,
                              const ClassMaps& classes);

  // The continuous score behind the last mask (CV_32FC1) and the score
  // level the mask is cut at: grey level (fixed, Otsu), I/μ(v) (adaptive) or
  // I/B (local). Sweeping a threshold over it gives the method's ROC curve.
  double Score(cv::Mat& score);

  const SegmenterOptions& options() const { return options_; }

  // The method the last frame was thresholded with: options().method, except
  // that a colour frame under kLocal takes kOtsu (see segmenter.cc).
  ThresholdMethod used_method() const { return used_; }

 private:
  const Segmentation& Process(const cv::Mat& image, const geometry::CameraModel* camera,
                              const ClassMaps* classes = nullptr);
  void Threshold(const cv::Mat& image);
  bool GrowsInHulls() const;
  void GrowInHulls();
  bool GrowsIntoSoil() const;

  SegmenterOptions options_;
  BlobExtractor blobs_;
  BlobExtractor track_blobs_;  // before hull and soil growth
  LocalThreshold local_;
  std::optional<Smoother> smoother_;  // when smoothing_px > 0
  cv::Mat index_;
  ThresholdMethod used_ = ThresholdMethod::kLocal;  // by the last frame
  HoleFiller holes_;
  NotchCloser notches_;
  HullGrower hull_;
  SoilGrower soil_;
  cv::Mat raw_;  // the plant image before smoothing (a header on the input or index_)
  cv::Mat low_mask_;
  cv::Mat cut_;  // ClassCut of the classes given
  Segmentation result_;
};

// The thesis's own segmentation (§2.3.6, the baseline of the evaluations):
// Hague's adaptive threshold at the hand-tuned gain, no hole filling or
// notch closing.
SegmenterOptions ThesisSegmenterOptions();

// Lowest Otsu threshold on a colour index for a colour frame under the local
// method: ExG ≥ 0.05, visibly greener than neutral grey (127.5).
inline constexpr double kColourIndexFloor = 127.5 + 127.5 * 0.05;

}  // namespace plantscale::vision
