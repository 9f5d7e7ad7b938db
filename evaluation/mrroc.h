#pragma once
// The maximum realisable ROC (thesis §7.3, [SNP98]): every setting of the
// classifier's two parameters (size threshold ς and association region
// χ²) is one point in ROC space; their upper convex hull with (0, 0) and
// (1, 1) is the MRROC. Crop pixels are the positives, weed pixels the
// negatives. The operating point for a cost ratio Φ is the hull vertex
// minimising the Bayes risk Φ·FP − TP (as vision::RocCurve, eqs. 2.16–2.23);
// the thesis's own choice (table 7.2) is the vertex nearest (0, 1).

#include <span>
#include <vector>

namespace plantscale::classify {

// One blob as the sweep sees it: what the classifier decides from, and how
// many of its pixels are truly crop and truly weed.
struct ClassifierSample {
  double area_m2 = 0.0;
  bool clipped = false;
  double gamma2 = 0.0;
  double crop_pixels = 0.0;
  double weed_pixels = 0.0;
};

struct MrrocPoint {
  double min_crop_area_m2 = 0.0;
  double assoc_chi2 = 0.0;
  double tpr = 0.0;
  double fpr = 0.0;
  double tp = 0.0, fp = 0.0;
};

struct Mrroc {
  std::vector<MrrocPoint> classifiers;  // every parameter pair swept
  std::vector<MrrocPoint> hull;         // from (0, 0) to (1, 1), fpr increasing
  double positives = 0.0, negatives = 0.0;

  double Auc() const;  // area under the hull (trapezium rule)
  // Throws std::invalid_argument when the hull is empty or Φ is not positive.
  MrrocPoint OperatingPoint(double costs_ratio) const;
  MrrocPoint NearestToCorner() const;  // thesis table 7.2
};

// Sweeps every pair of `min_areas_m2` × `assoc_chi2s` over the samples.
// positives/negatives default (≤ 0) to the samples' crop/weed pixel totals;
// pass the truth totals to count pixels that no blob holds as missed.
Mrroc SweepClassifier(std::span<const ClassifierSample> samples,
                      std::span<const double> min_areas_m2, std::span<const double> assoc_chi2s,
                      double positives = 0.0, double negatives = 0.0);

// Upper convex hull of ROC points with (0, 0) and (1, 1) added.
std::vector<MrrocPoint> UpperHull(std::vector<MrrocPoint> points);

}  // namespace plantscale::classify
