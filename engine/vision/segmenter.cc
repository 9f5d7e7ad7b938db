#include "engine/vision/segmenter.h"

#include <string>

#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"

#include "engine/vision/threshold.h"

namespace plantscale::vision {

std::optional<ThresholdMethod> ParseThresholdMethod(std::string_view name) {
  if (name == "fixed") return ThresholdMethod::kFixed;
  if (name == "otsu") return ThresholdMethod::kOtsu;
  if (name == "adaptive") return ThresholdMethod::kAdaptive;
  if (name == "local") return ThresholdMethod::kLocal;
  return std::nullopt;
}

const char* Name(ThresholdMethod method) {
  switch (method) {
    case ThresholdMethod::kFixed: return "fixed";
    case ThresholdMethod::kOtsu: return "otsu";
    case ThresholdMethod::kAdaptive: return "adaptive";
    case ThresholdMethod::kLocal: return "local";
  }
  return "?";
}

OptionErrors SegmenterOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "fixed_threshold", fixed_threshold, 0.0, 256.0);
  RequireInRange(e, "otsu_floor", otsu_floor, 0.0, 256.0);
  RequirePositive(e, "adaptive_gain", adaptive_gain);
  RequireInRange(e, "smoothing_px", smoothing_px, 0.0, 20.0);
  RequireInRange(e, "fill_holes_max_fraction", fill_holes_max_fraction, 0.0, 1.0);
  if (hull_gain < 0.0 || hull_gain > local.gain) {
    e.push_back({"hull_gain", "must be 0 (off) or in (0, local.gain]"});
  }
  if (hull_min_area_px < 1) e.push_back({"hull_min_area_px", "must be >= 1"});
  if (close_notches_px < 0 || close_notches_px > 30) {
    e.push_back({"close_notches_px", "must be in [0, 30]"});
  }
  for (OptionError& g : Prefixed("soil_growth", soil_growth.Validate())) e.push_back(std::move(g));
  for (OptionError& b : Prefixed("blobs", blobs.Validate())) e.push_back(std::move(b));
  for (OptionError& l : Prefixed("local", local.Validate())) e.push_back(std::move(l));
  return e;
}

SegmenterOptions ThesisSegmenterOptions() {
  SegmenterOptions o;
  o.method = ThresholdMethod::kAdaptive;
  o.fill_holes_max_fraction = 0.0;
  o.close_notches_px = 0;
  o.hull_gain = 0.0;
  o.soil_growth.z = 0.0;
  return o;
}

namespace {
// Validated before any member is built, so every error is reported at once.
const SegmenterOptions& Validated(const SegmenterOptions& options) {
  ThrowIfInvalid("segmenter options", options.Validate());
  return options;
}
}  // namespace

Segmenter::Segmenter(const SegmenterOptions& options)
    : options_(Validated(options)),
      blobs_(options.blobs),
      track_blobs_(options.blobs),
      local_(options.local),
      soil_(options.soil_growth) {
  if (options_.smoothing_px > 0.0) smoother_.emplace(options_.smoothing_px);
}

void Segmenter::Threshold(const cv::Mat& image) {
  if (image.empty() || (image.type() != CV_8UC1 && image.type() != CV_8UC3)) {
    throw DataError("segmentation needs an 8-bit grey or BGR image (got " +
                    std::to_string(image.cols) + "x" + std::to_string(image.rows) + ", " +
                    std::to_string(image.channels()) + " channels, depth " +
                    std::to_string(image.depth()) + ")");
  }
  const cv::Mat* plant = &image;
  if (image.type() == CV_8UC3) {
    ComputeColourIndex(image, options_.colour_index, index_);
    plant = &index_;
  }
  raw_ = *plant;  // a header: no copy
  if (options_.smoothing_px > 0.0) {
    // σ = 2 (the default) is the tent of two 5×5 boxes, under a quarter of
    // cv::GaussianBlur's time at the same AUC (smoothing.h). Truncating the
    // Gaussian to 5×5 instead dropped preset D's AUC from 0.9905 to 0.9889.
    smoother_->Apply(*plant, result_.plant_image);
  } else {
    result_.plant_image = *plant;  // a header: no copy
  }
  const cv::Mat& grey = result_.plant_image;
  ThresholdMethod method = options_.method;
  double otsu_floor = options_.otsu_floor;
  if (plant == &index_ && method == ThresholdMethod::kLocal) {
    // The local soil level is a reflectance ratio (plant ≥ α × soil), made
    // for near-infrared. A colour index is a difference about neutral grey
    // (127.5): soil sits there, so α × soil is past white and nothing would
    // be plant. Colour frames take Otsu on the index above a neutral floor.
    method = ThresholdMethod::kOtsu;
    otsu_floor = std::max(otsu_floor, kColourIndexFloor);
  }
  used_ = method;
  switch (method) {
    case ThresholdMethod::kFixed:
      FixedThreshold(grey, options_.fixed_threshold, result_.mask);
      result_.threshold_at_top = result_.threshold_at_bottom = options_.fixed_threshold;
      break;
    case ThresholdMethod::kOtsu:
      result_.threshold_at_top = result_.threshold_at_bottom = OtsuThreshold(grey, result_.mask);
      if (result_.threshold_at_top < otsu_floor) {
        FixedThreshold(grey, otsu_floor, result_.mask);
        result_.threshold_at_top = result_.threshold_at_bottom = otsu_floor;
      }
      break;
    case ThresholdMethod::kAdaptive: {
      const InterpolatedMean mean = ComputeInterpolatedMean(grey);
      AdaptiveInterpolatingThreshold(grey, mean, options_.adaptive_gain, result_.mask);
      result_.threshold_at_top = options_.adaptive_gain * mean.At(0);
      result_.threshold_at_bottom = options_.adaptive_gain * mean.At(grey.rows - 1);
      break;
    }
    case ThresholdMethod::kLocal: {
      local_.Apply(grey, result_.mask);
      const cv::Mat& t = local_.cell_thresholds();
      result_.threshold_at_top = cv::mean(t.row(0))[0];
      result_.threshold_at_bottom = cv::mean(t.row(t.rows - 1))[0];
      break;
    }
  }
  if (options_.close_notches_px > 0) notches_.Close(result_.mask, options_.close_notches_px);
  if (options_.fill_holes_max_fraction > 0.0) {
    holes_.Fill(result_.mask, static_cast<int>(options_.fill_holes_max_fraction *
                                               static_cast<double>(result_.mask.total())));
  }
}

double Segmenter::Score(cv::Mat& score) {
  const cv::Mat& grey = result_.plant_image;
  PLANTSCALE_CHECK(!grey.empty(), "Score() before Process()");
  switch (used_) {
    case ThresholdMethod::kFixed:
    case ThresholdMethod::kOtsu:
      grey.convertTo(score, CV_32F);
      return result_.threshold_at_top;
    case ThresholdMethod::kAdaptive:
      AdaptiveScore(grey, ComputeInterpolatedMean(grey), score);
      return options_.adaptive_gain;
    case ThresholdMethod::kLocal:
      local_.Score(grey, score);
      return options_.local.gain;
  }
  return 0.0;
}

bool Segmenter::GrowsInHulls() const {
  return options_.hull_gain > 0.0 && used_ == ThresholdMethod::kLocal;
}

bool Segmenter::GrowsIntoSoil() const {
  return options_.soil_growth.enabled() && used_ == ThresholdMethod::kLocal;
}

void Segmenter::GrowInHulls() {
  local_.ApplyAtGain(result_.plant_image, options_.hull_gain, low_mask_);
  hull_.Grow(result_.mask, low_mask_, options_.hull_min_area_px);
}

const Segmentation& Segmenter::Process(const cv::Mat& image) {
  return Process(image, nullptr);
}

const Segmentation& Segmenter::Process(const cv::Mat& image,
                                       const geometry::CameraModel& camera) {
  return Process(image, &camera);
}

const Segmentation& Segmenter::Process(const cv::Mat& image, const geometry::CameraModel& camera,
                                       const ClassMaps& classes) {
  return Process(image, &camera, &classes);
}

const Segmentation& Segmenter::Process(const cv::Mat& image,
                                       const geometry::CameraModel* camera,
                                       const ClassMaps* classes) {
  if (classes && (classes->classes.size() != image.size() || classes->confidence.size() != image.size())) {
    throw DataError("learned classes of " + std::to_string(classes->classes.cols) + "x" +
                    std::to_string(classes->classes.rows) + " px for an image of " +
                    std::to_string(image.cols) + "x" + std::to_string(image.rows) + " px");
  }
  Threshold(image);
  // Cut before growth (the tracker's blobs) and again after it (growth may
  // join the parts again); the pixels kept before growth stay inside the
  // grown mask, as SetCores needs.
  if (classes) {
    ClassCut(classes->classes, cut_);
    result_.mask.setTo(0, cut_);
  }
  const auto extract = [&](BlobExtractor& e) {
    return camera ? e.Extract(result_.mask, *camera) : e.Extract(result_.mask);
  };
  const bool grows = GrowsInHulls() || GrowsIntoSoil();
  if (grows) {
    // The tracker's blobs are the mask's before growth: from the first
    // grower's own labelling of it, unless contours need that mask.
    const bool contours = options_.blobs.trace_contours;
    if (contours) result_.track_blobs = extract(track_blobs_);
    if (GrowsInHulls()) GrowInHulls();
    if (GrowsIntoSoil()) soil_.Grow(raw_, result_.mask);
    if (!contours) {
      result_.track_blobs =
          GrowsInHulls()
              ? track_blobs_.ExtractLabelled(hull_.mask_runs(), hull_.mask_parent(), camera)
              : track_blobs_.ExtractLabelled(soil_.mask_runs(), soil_.mask_parent(), camera);
    }
  }
  if (classes && grows) result_.mask.setTo(0, cut_);
  result_.blobs = extract(blobs_);
  if (grows) blobs_.SetCores(track_blobs_.runs());  // what the mask held before growth
  if (classes) {
    blobs_.SetClasses(classes->classes, classes->confidence);
    if (grows) track_blobs_.SetClasses(classes->classes, classes->confidence);
  }
  if (!grows) result_.track_blobs = result_.blobs;
  return result_;
}

}  // namespace plantscale::vision
