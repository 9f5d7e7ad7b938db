#include "evaluation/roc.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"

namespace plantscale::vision {

double RocCurve::Auc() const {
  double area = 0.0;
  for (size_t i = 1; i < points.size(); ++i) {
    const RocPoint& a = points[i - 1];
    const RocPoint& b = points[i];
    area += (a.fpr - b.fpr) * (a.tpr + b.tpr) / 2.0;
  }
  return area;
}

RocPoint RocCurve::OperatingPoint(double costs_ratio) const {
  PLANTSCALE_CHECK(!points.empty(), "empty ROC curve");
  const RocPoint* best = &points.front();
  double best_risk = 0.0;
  for (const RocPoint& p : points) {
    const double risk = costs_ratio * static_cast<double>(p.fp) - static_cast<double>(p.tp);
    if (&p == &points.front() || risk < best_risk) {
      best = &p;
      best_risk = risk;
    }
  }
  return *best;
}

RocPoint RocCurve::At(double threshold) const {
  PLANTSCALE_CHECK(!points.empty(), "empty ROC curve");
  for (const RocPoint& p : points) {
    if (p.threshold >= threshold) return p;
  }
  return points.back();
}

RocAccumulator::RocAccumulator(double low, double high, int bins)
    : low_(low), high_(high), plant_(static_cast<size_t>(bins), 0), soil_(plant_) {
  PLANTSCALE_CHECK(bins > 0 && high > low, "bad ROC histogram range");
}

int RocAccumulator::Bin(double score) const {
  const auto n = static_cast<int>(plant_.size());
  const double x = (score - low_) / (high_ - low_) * n;
  if (!(x >= 0.0)) return 0;
  return std::min(static_cast<int>(x), n - 1);
}

void RocAccumulator::Add(double score, bool plant) {
  ++(plant ? plant_ : soil_)[static_cast<size_t>(Bin(score))];
}

void RocAccumulator::AddImage(const cv::Mat& score, const cv::Mat& truth, const cv::Mat& valid) {
  PLANTSCALE_CHECK(score.size() == truth.size() && score.size() == valid.size(),
                   "score, truth and valid images must have one size");
  PLANTSCALE_CHECK(score.type() == CV_8UC1 || score.type() == CV_32FC1, "score type");
  PLANTSCALE_CHECK(truth.type() == CV_8UC1 && valid.type() == CV_8UC1, "truth/valid type");
  const bool bytes = score.type() == CV_8UC1;
  for (int v = 0; v < score.rows; ++v) {
    const auto* t = truth.ptr<uint8_t>(v);
    const auto* ok = valid.ptr<uint8_t>(v);
    for (int u = 0; u < score.cols; ++u) {
      if (ok[u] == 0) continue;
      const double s = bytes ? score.ptr<uint8_t>(v)[u] : score.ptr<float>(v)[u];
      Add(s, t[u] != 0);
    }
  }
}

void RocAccumulator::Merge(const RocAccumulator& other) {
  PLANTSCALE_CHECK(other.plant_.size() == plant_.size() && other.low_ == low_ &&
                       other.high_ == high_,
                   "merging ROC accumulators with different bins");
  for (size_t i = 0; i < plant_.size(); ++i) {
    plant_[i] += other.plant_[i];
    soil_[i] += other.soil_[i];
  }
}

RocCurve RocAccumulator::Curve() const {
  RocCurve c;
  for (size_t i = 0; i < plant_.size(); ++i) {
    c.positives += plant_[i];
    c.negatives += soil_[i];
  }
  const double p = std::max<double>(1.0, static_cast<double>(c.positives));
  const double n = std::max<double>(1.0, static_cast<double>(c.negatives));
  uint64_t tp = c.positives, fp = c.negatives;
  const double width = (high_ - low_) / static_cast<double>(plant_.size());
  // Threshold at the lower edge of bin k: bins k.. are plant. k = bins: nothing.
  for (size_t k = 0; k <= plant_.size(); ++k) {
    c.points.push_back({low_ + width * static_cast<double>(k), static_cast<double>(tp) / p,
                        static_cast<double>(fp) / n, tp, fp});
    if (k < plant_.size()) {
      tp -= plant_[k];
      fp -= soil_[k];
    }
  }
  return c;
}

void DoubtBand(const cv::Mat& labels, int band_px, cv::Mat& doubt) {
  PLANTSCALE_CHECK(labels.type() == CV_8UC1, "labels must be CV_8UC1");
  cv::Mat plant = labels != 0;
  if (band_px <= 0) {
    doubt = cv::Mat::zeros(labels.size(), CV_8UC1);
    return;
  }
  const cv::Mat kernel = cv::getStructuringElement(
      cv::MORPH_RECT, cv::Size(2 * band_px + 1, 2 * band_px + 1));
  cv::Mat grown, shrunk;
  cv::dilate(plant, grown, kernel);
  cv::erode(plant, shrunk, kernel, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  doubt = grown & ~shrunk;
}

void EvaluationMask(const cv::Mat& labels, const cv::Mat& roi, int band_px, cv::Mat& valid) {
  cv::Mat doubt;
  DoubtBand(labels, band_px, doubt);
  valid = roi & ~doubt;
}

}  // namespace plantscale::vision
