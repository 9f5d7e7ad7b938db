#include "evaluation/class_eval.h"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <ostream>

#include "app/config/learned_model.h"
#include "app/config/photo_segmentation.h"
#include "app/config/progress.h"
#include "engine/common/options.h"
#include "engine/vision/segmenter.h"

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

// The size rule's ladder of θ (share of the photograph a crop blob covers at least).
constexpr double kSizeShares[] = {1e-4, 3e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2};
constexpr int kShares = static_cast<int>(sizeof kSizeShares / sizeof kSizeShares[0]);

double Mean(const std::vector<double>& v) {
  double sum = 0;
  int n = 0;
  for (double x : v) {
    if (std::isnan(x)) continue;
    sum += x;
    ++n;
  }
  return n > 0 ? sum / n : std::nan("");
}

// The size rule's class image for every θ of the ladder at once: the
// components of the plant mask with their areas.
void SizeRule(const cv::Mat& image, const cv::Mat& label, std::vector<std::vector<int64_t>>& counts) {
  const cv::Mat mask = PlantMaskOfPhoto(image);
  cv::Mat components, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, components, stats, centroids, 8, CV_32S);
  const double total = static_cast<double>(image.total());
  for (int k = 0; k < kShares; ++k) {
    std::vector<uint8_t> cls(static_cast<size_t>(n), 0);
    for (int i = 1; i < n; ++i) {
      cls[static_cast<size_t>(i)] = stats.at<int>(i, cv::CC_STAT_AREA) >= kSizeShares[k] * total ? 1 : 2;
    }
    cv::Mat predicted(label.size(), CV_8UC1);
    for (int y = 0; y < label.rows; ++y) {
      const int* c = components.ptr<int>(y);
      uint8_t* p = predicted.ptr<uint8_t>(y);
      for (int x = 0; x < label.cols; ++x) p[x] = cls[static_cast<size_t>(c[x])];
    }
    AddConfusion(label, predicted, counts[static_cast<size_t>(k)]);
  }
}

ClassFigures Figures(std::string method, std::vector<int64_t> counts, double parameter) {
  ClassFigures f;
  f.method = std::move(method);
  f.iou = ClassIou(counts);
  f.miou = Mean(f.iou);
  f.confusion = std::move(counts);
  f.parameter = parameter;
  return f;
}

nlohmann::json Number(double v) { return std::isnan(v) ? nlohmann::json() : nlohmann::json(v); }

}  // namespace

ClassEvaluation EvaluateClasses(const ClassEvalRequest& r, std::ostream& log) {
  const std::vector<LabelledPhoto> photos = ListLabelledPhotos(r.images, r.labels);
  std::optional<vision::LearnedSegmenter> model;
  if (!r.model.empty()) model.emplace(LoadSegmenter(ReadLearnedModel(r.model)));
  ClassEvaluation e;
  e.images = r.images.string();
  e.labels = r.labels.string();
  e.model_file = r.model.string();
  std::vector<int64_t> model_counts(9, 0);
  std::vector<std::vector<int64_t>> rule_counts(kShares, std::vector<int64_t>(9, 0));
  double model_seconds = 0;
  ProgressBar bar(log, "evaluate classes", static_cast<int>(photos.size()), r.progress);
  for (const LabelledPhoto& photo : photos) {
    cv::Mat image, label;
    ReadLabelledPhoto(photo, image, label);
    if (model) {
      const auto t0 = std::chrono::steady_clock::now();
      vision::ClassMaps maps;
      try {
        maps = model->Classify(image);
      } catch (const DataError& x) {
        throw DataError(photo.image.string() + ": " + x.what());
      }
      model_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      AddConfusion(label, maps.classes, model_counts);
    }
    if (r.size_rule) SizeRule(image, label, rule_counts);
    ++e.photographs;
    e.pixels += static_cast<int64_t>(image.total());
    bar.Update(e.photographs);
  }
  bar.Finish();
  if (model) {
    e.methods.push_back(Figures("model", model_counts, 0.0));
    e.model_ms_per_megapixel = 1e3 * model_seconds / (static_cast<double>(e.pixels) / 1e6);
  }
  if (r.size_rule) {
    int best = 0;
    double best_miou = -1;
    for (int k = 0; k < kShares; ++k) {
      const double m = Mean(ClassIou(rule_counts[static_cast<size_t>(k)]));
      if (m > best_miou) {
        best_miou = m;
        best = k;
      }
    }
    e.methods.push_back(Figures("size_rule", rule_counts[static_cast<size_t>(best)], kSizeShares[best]));
  }
  return e;
}

nlohmann::json ToJson(const ClassEvaluation& e) {
  nlohmann::json j{{"photographs", e.photographs}, {"pixels", e.pixels},
                   {"images", e.images}, {"labels", e.labels}};
  if (!e.model_file.empty()) j["model_file"] = e.model_file;
  for (const ClassFigures& f : e.methods) {
    nlohmann::json m{{"iou", {{"soil", Number(f.iou[0])}, {"crop", Number(f.iou[1])}, {"weed", Number(f.iou[2])}}},
                     {"miou", Number(f.miou)},
                     {"confusion", {{f.confusion[0], f.confusion[1], f.confusion[2]},
                                    {f.confusion[3], f.confusion[4], f.confusion[5]},
                                    {f.confusion[6], f.confusion[7], f.confusion[8]}}}};
    if (f.method == "size_rule") m["crop_min_share"] = f.parameter;
    if (f.method == "model") m["ms_per_megapixel"] = e.model_ms_per_megapixel;
    j[f.method] = m;
  }
  return j;
}

nlohmann::json ClassEvaluationJsonShape() {
  ClassEvaluation e;
  for (const char* method : {"model", "size_rule"}) {
    ClassFigures f;
    f.method = method;
    f.confusion.assign(9, 0);
    f.iou.assign(3, 0.0);
    e.methods.push_back(f);
  }
  return ToJson(e);
}

void WriteTable(const ClassEvaluation& e, std::ostream& out) {
  out << std::fixed << std::setprecision(3) << "classes on " << e.photographs << " photograph(s), "
      << std::setprecision(1) << static_cast<double>(e.pixels) / 1e6 << " Mpx\n"
      << "  method      soil IoU  crop IoU  weed IoU  mIoU\n";
  for (const ClassFigures& f : e.methods) {
    out << "  " << std::left << std::setw(10) << f.method << std::right << std::setprecision(3);
    for (double v : f.iou) out << std::setw(10) << v;
    out << std::setw(7) << f.miou;
    if (f.method == "size_rule") out << "  (crop blobs ≥ " << std::setprecision(4) << f.parameter << " of the photograph, best on this set)";
    if (f.method == "model") out << "  (" << std::setprecision(1) << e.model_ms_per_megapixel << " ms per Mpx)";
    out << '\n';
  }
  out << "  confusion matrices are rows truth (soil, crop, weed), columns predicted: --json\n";
}

}  // namespace plantscale::app
