#include "evaluation/mrroc.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "engine/classify/crop_classifier.h"

namespace plantscale::classify {

namespace {

// z-component of (b − a) × (c − a) in ROC space (fpr, tpr).
double Cross(const MrrocPoint& a, const MrrocPoint& b, const MrrocPoint& c) {
  return (b.fpr - a.fpr) * (c.tpr - a.tpr) - (b.tpr - a.tpr) * (c.fpr - a.fpr);
}

}  // namespace

std::vector<MrrocPoint> UpperHull(std::vector<MrrocPoint> points) {
  MrrocPoint origin;
  MrrocPoint all;
  all.tpr = all.fpr = 1.0;
  all.min_crop_area_m2 = 0.0;
  all.assoc_chi2 = std::numeric_limits<double>::infinity();
  origin.min_crop_area_m2 = std::numeric_limits<double>::infinity();
  points.push_back(origin);
  points.push_back(all);
  std::sort(points.begin(), points.end(), [](const MrrocPoint& a, const MrrocPoint& b) {
    return a.fpr != b.fpr ? a.fpr < b.fpr : a.tpr > b.tpr;
  });
  // Monotone chain, upper part: keep right turns only.
  std::vector<MrrocPoint> hull;
  for (const MrrocPoint& p : points) {
    if (!hull.empty() && hull.back().fpr == p.fpr) continue;  // lower tpr at the same fpr
    while (hull.size() >= 2 && Cross(hull[hull.size() - 2], hull.back(), p) >= 0.0) {
      hull.pop_back();
    }
    hull.push_back(p);
  }
  return hull;
}

double Mrroc::Auc() const {
  double area = 0.0;
  for (size_t i = 1; i < hull.size(); ++i) {
    area += (hull[i].fpr - hull[i - 1].fpr) * 0.5 * (hull[i].tpr + hull[i - 1].tpr);
  }
  return area;
}

MrrocPoint Mrroc::OperatingPoint(double costs_ratio) const {
  if (hull.empty()) throw std::invalid_argument("MRROC operating point: empty hull");
  if (!(costs_ratio > 0.0)) throw std::invalid_argument("MRROC operating point: cost ratio must be > 0");
  // Risk ∝ Φ·N·FPR − P·TPR (eq. 2.22 with counts).
  const auto risk = [&](const MrrocPoint& p) {
    return costs_ratio * negatives * p.fpr - positives * p.tpr;
  };
  return *std::min_element(hull.begin(), hull.end(),
                           [&](const auto& a, const auto& b) { return risk(a) < risk(b); });
}

MrrocPoint Mrroc::NearestToCorner() const {
  if (hull.empty()) throw std::invalid_argument("MRROC nearest to (0, 1): empty hull");
  const auto d2 = [](const MrrocPoint& p) { return p.fpr * p.fpr + (1 - p.tpr) * (1 - p.tpr); };
  return *std::min_element(hull.begin(), hull.end(),
                           [&](const auto& a, const auto& b) { return d2(a) < d2(b); });
}

Mrroc SweepClassifier(std::span<const ClassifierSample> samples,
                      std::span<const double> min_areas_m2, std::span<const double> assoc_chi2s,
                      double positives, double negatives) {
  Mrroc r;
  double crop_total = 0.0, weed_total = 0.0;
  for (const ClassifierSample& s : samples) {
    crop_total += s.crop_pixels;
    weed_total += s.weed_pixels;
  }
  r.positives = positives > 0.0 ? positives : crop_total;
  r.negatives = negatives > 0.0 ? negatives : weed_total;
  for (double area : min_areas_m2) {
    for (double chi2 : assoc_chi2s) {
      MrrocPoint p;
      p.min_crop_area_m2 = area;
      p.assoc_chi2 = chi2;
      for (const ClassifierSample& s : samples) {
        if (!IsCrop(s.area_m2, s.clipped, s.gamma2, area, chi2)) continue;
        p.tp += s.crop_pixels;
        p.fp += s.weed_pixels;
      }
      p.tpr = r.positives > 0.0 ? p.tp / r.positives : 0.0;
      p.fpr = r.negatives > 0.0 ? p.fp / r.negatives : 0.0;
      r.classifiers.push_back(p);
    }
  }
  r.hull = UpperHull(r.classifiers);
  return r;
}

}  // namespace plantscale::classify
