#include "evaluation/segmentation_eval.h"

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "engine/pipeline/pipeline.h"
#include "engine/vision/threshold.h"
#include "evaluation/seeds.h"

namespace plantscale::app {

cv::Mat WheelTrapezoid(const geometry::CameraModel& camera, double track_width_m) {
  const auto& c = camera.options();
  cv::Mat roi(c.image_height_px, c.image_width_px, CV_8UC1, cv::Scalar(0));
  for (int v = 0; v < roi.rows; ++v) {
    for (int u = 0; u < roi.cols; ++u) {
      const auto g = camera.ImageToPlane({u + 0.5, v + 0.5}, 0.0);
      if (g && std::abs(g->x()) <= track_width_m / 2.0) roi.at<uint8_t>(v, u) = 255;
    }
  }
  return roi;
}

namespace {

// The ground depth the camera sees between the wheels: frames further apart
// than this share no soil (thesis §2.3.3 chose non-overlapping images).
double ViewDepth(const geometry::CameraModel& camera) {
  const auto& c = camera.options();
  const auto near = camera.ImageToPlane({c.image_width_px / 2.0, c.image_height_px - 0.5}, 0.0);
  const auto far = camera.ImageToPlane({c.image_width_px / 2.0, 0.5}, 0.0);
  if (!near || !far) return 8.0;
  return std::min(far->y() - near->y(), 8.0);
}

struct Confusion {
  uint64_t tp = 0, fp = 0, tn = 0, fn = 0;
  void Add(const cv::Mat& mask, const cv::Mat& labels, const cv::Mat& valid) {
    for (int v = 0; v < mask.rows; ++v) {
      const auto* m = mask.ptr<uint8_t>(v);
      const auto* l = labels.ptr<uint8_t>(v);
      const auto* ok = valid.ptr<uint8_t>(v);
      for (int u = 0; u < mask.cols; ++u) {
        if (ok[u] == 0) continue;
        const bool plant = l[u] != 0, said = m[u] != 0;
        (plant ? (said ? tp : fn) : (said ? fp : tn))++;
      }
    }
  }
  PixelRates Rates() const {
    const auto d = [](uint64_t a, uint64_t b) {
      return a + b == 0 ? 0.0 : static_cast<double>(a) / static_cast<double>(a + b);
    };
    return {d(tp, fn), d(tp, fp), d(tn, fp), d(fp, tn)};
  }
};

// Pixel rates at a point of the curve, from the same counts as Confusion.
PixelRates RatesAt(const vision::RocPoint& p, const vision::RocCurve& c) {
  return Confusion{p.tp, p.fp, c.negatives - p.fp, c.positives - p.tp}.Rates();
}

struct Accumulators {
  vision::RocAccumulator fixed{0.0, 256.0, 256};
  vision::RocAccumulator adaptive{0.0, 4.0, 4000};
  vision::RocAccumulator ours_curve{0.0, 8.0, 8000};
  Confusion ours;
  double ours_threshold = 0.0;
  uint64_t plant = 0, evaluated = 0;
};

void ScoreFrame(const cv::Mat& image, const cv::Mat& labels, const cv::Mat& valid,
                const pipeline::FrameResult& frame, vision::Segmenter& segmenter,
                Accumulators& acc) {
  acc.ours.Add(frame.mask, labels, valid);
  // The thesis's baselines see the plant image as it is (no smoothing).
  cv::Mat raw = image;
  if (image.channels() == 3) {
    vision::ComputeColourIndex(image, segmenter.options().colour_index, raw);
  }
  acc.fixed.AddImage(raw, labels, valid);
  cv::Mat score;
  vision::AdaptiveScore(raw, vision::ComputeInterpolatedMean(raw), score);
  acc.adaptive.AddImage(score, labels, valid);
  acc.ours_threshold = segmenter.Score(score);
  if (segmenter.used_method() == vision::ThresholdMethod::kFixed ||
      segmenter.used_method() == vision::ThresholdMethod::kOtsu) {
    score *= 1.0 / 32.0;  // grey levels into the histogram's range
    acc.ours_threshold /= 32.0;
  }
  acc.ours_curve.AddImage(score, labels, valid);
}

MethodEvaluation Baseline(const char* method, const char* parameter,
                          const vision::RocAccumulator& acc, double costs_ratio) {
  MethodEvaluation m{method, parameter, acc.Curve(), 0.0, 0.0, {}};
  m.auc = m.curve.Auc();
  const vision::RocPoint p = m.curve.OperatingPoint(costs_ratio);
  m.parameter = p.threshold;
  m.rates = RatesAt(p, m.curve);
  return m;
}

// The frame's errors as an image (SegmentationEvalOptions::errors_dir).
void WriteErrors(const std::string& path, const cv::Mat& image, const cv::Mat& mask,
                 const cv::Mat& labels, const cv::Mat& valid) {
  cv::Mat grey, out;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else {
    grey = image;
  }
  cv::cvtColor(grey, out, cv::COLOR_GRAY2BGR);
  for (int v = 0; v < out.rows; ++v) {
    for (int u = 0; u < out.cols; ++u) {
      const uint8_t l = labels.at<uint8_t>(v, u);
      if (!valid.at<uint8_t>(v, u) || l > 2) continue;
      const bool plant = l != 0, found = mask.at<uint8_t>(v, u) != 0;
      if (plant && !found) out.at<cv::Vec3b>(v, u) = {0, 0, 255};
      if (!plant && found) out.at<cv::Vec3b>(v, u) = {255, 64, 0};
      if (plant && found) {
        const auto g = static_cast<uint8_t>(grey.at<uint8_t>(v, u) / 3);
        out.at<cv::Vec3b>(v, u) = {g, 255, g};
      }
    }
  }
  if (!cv::imwrite(path, out)) throw std::runtime_error("cannot write " + path);
}

}  // namespace

OptionErrors SegmentationEvalOptions::Validate() const {
  OptionErrors e = Prefixed("sim", sim.Validate());
  if (seeds < 1) e.push_back({"seeds", "must be >= 1"});
  if (frames_per_seed < 1) e.push_back({"frames_per_seed", "must be >= 1"});
  if (doubt_band_px < 0) e.push_back({"doubt_band_px", "must be >= 0"});
  RequirePositive(e, "costs_ratio", costs_ratio);
  for (OptionError& s : Prefixed("segmenter", segmenter.Validate())) e.push_back(std::move(s));
  return e;
}

SegmentationEvaluation EvaluateSegmentation(const SegmentationEvalOptions& options) {
  ThrowIfInvalid("segmentation evaluation", options.Validate());
  const geometry::CameraModel camera(options.sim.camera);
  const cv::Mat roi = WheelTrapezoid(camera, options.sim.vehicle.track_width_m);
  const double spacing = ViewDepth(camera) + 0.1;
  const double step = options.sim.vehicle.speed_m_s / options.sim.vehicle.frame_rate_hz;
  Accumulators acc;
  // The vehicle's pipeline, segmentation only: the sampled frames are far
  // apart, with no odometry between them.
  pipeline::PipelineOptions po;
  po.segmenter = options.segmenter;
  po.treat = false;
  po.track = false;
  pipeline::Pipeline pipe(camera, po);
  SegmentationEvaluation result;
  ForEachSeed(options.sim, options.seeds, [&](int k, sim::SimulatorOptions& so) {
    so.length_m = 0.5 + spacing * options.frames_per_seed;
    sim::Simulator simulator(so);
    sim::SimFrame frame;
    double next_sample = 0.5, last_distance = 0.0;
    while (simulator.Next(frame, last_distance + 2.0 * step >= next_sample)) {
      last_distance = frame.truth.distance_m;
      if (frame.rendered.image.empty() || frame.truth.distance_m < next_sample) continue;
      next_sample = frame.truth.distance_m + spacing;
      cv::Mat valid;
      vision::EvaluationMask(frame.rendered.labels, roi, options.doubt_band_px, valid);
      const pipeline::FrameResult& r =
          pipe.ProcessFrame(frame.truth.utime, frame.truth.index, frame.rendered.image);
      if (!r.accepted) throw std::runtime_error("segmentation evaluation: " + r.faults.front());
      ScoreFrame(frame.rendered.image, frame.rendered.labels, valid, r, pipe.segmenter(), acc);
      if (!options.errors_dir.empty()) {
        std::filesystem::create_directories(options.errors_dir);
        WriteErrors(options.errors_dir + "/seed" + std::to_string(k) + "_frame" +
                        std::to_string(result.frames) + "_errors.png",
                    frame.rendered.image, r.mask, frame.rendered.labels, valid);
      }
      ++result.frames;
    }
  });
  result.preset = options.sim.preset;
  result.crop = options.crop;
  result.vehicle = options.vehicle;
  result.published_thesis = options.published_thesis;
  result.image_kind = options.sim.render.kind == sim::ImageKind::kRgb ? "rgb" : "nir";
  result.colour_index = vision::Name(options.segmenter.colour_index);
  result.seeds = options.seeds;
  result.thesis_fixed = Baseline("fixed", "tau", acc.fixed, options.costs_ratio);
  result.thesis_adaptive = Baseline("adaptive", "alpha", acc.adaptive, options.costs_ratio);
  const vision::RocCurve& c = result.thesis_fixed.curve;
  result.plant_fraction =
      static_cast<double>(c.positives) / static_cast<double>(c.positives + c.negatives);
  result.ours = {vision::Name(options.segmenter.method), "", acc.ours_curve.Curve(), 0.0,
                 acc.ours_threshold, acc.ours.Rates()};
  result.ours.auc = result.ours.curve.Auc();
  return result;
}

}  // namespace plantscale::app
