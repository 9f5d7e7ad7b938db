#pragma once
// Receiver operating characteristic tools (thesis §2.3.2, §2.3.6).
//
// A classifier scores every pixel; a pixel is plant when its score is at
// least a threshold. Scores are binned into a histogram per class, which
// gives the whole ROC curve at every bin edge at once; the area under it by
// the trapezium rule equals the Wilcoxon statistic (eqs. 2.9–2.11), ties
// within a bin counting one half. Border ("doubt") pixels of the ground truth
// are excluded, as the thesis does (§2.3.4), and only pixels inside a region
// of interest (the trapezoid between the wheels) count.

#include <opencv2/core.hpp>
#include <cstdint>
#include <vector>

namespace plantscale::vision {

struct RocPoint {
  double threshold = 0.0;  // score >= threshold is plant
  double tpr = 0.0;        // eq. 2.12
  double fpr = 0.0;        // eq. 2.13
  uint64_t tp = 0, fp = 0;
};

struct RocCurve {
  std::vector<RocPoint> points;  // from (1, 1) at the lowest threshold to (0, 0)
  uint64_t positives = 0, negatives = 0;

  double Auc() const;  // trapezium rule (= Wilcoxon statistic)
  // The point minimising the Bayes risk for costs ratio Φ (eqs. 2.16–2.23):
  // risk ∝ Φ·P_N·FPR − P_P·TPR ∝ Φ·FP − TP; where the curve is smooth this is
  // where its slope dTPR/dFPR equals Φ·P_N/P_P (eq. 2.22).
  RocPoint OperatingPoint(double costs_ratio) const;
  // TPR/FPR at a given threshold (the first point at or above it).
  RocPoint At(double threshold) const;
};

class RocAccumulator {
 public:
  // Scores are binned uniformly over [low, high); outside values clamp to
  // the end bins.
  RocAccumulator(double low, double high, int bins);

  void Add(double score, bool plant);
  // Every pixel with valid != 0: score image (CV_8UC1 or CV_32FC1), plant
  // where truth != 0.
  void AddImage(const cv::Mat& score, const cv::Mat& truth, const cv::Mat& valid);
  RocCurve Curve() const;
  void Merge(const RocAccumulator& other);

 private:
  int Bin(double score) const;
  double low_, high_;
  std::vector<uint64_t> plant_, soil_;
};

// Pixels on the border between plant matter and soil in a label image (any
// non-zero label is plant): within `band_px` of a pixel of the other class
// (chessboard distance). 255 where in doubt.
void DoubtBand(const cv::Mat& labels, int band_px, cv::Mat& doubt);

// Ground-truth mask of evaluated pixels: inside `roi` and not in the doubt band.
void EvaluationMask(const cv::Mat& labels, const cv::Mat& roi, int band_px, cv::Mat& valid);

}  // namespace plantscale::vision
