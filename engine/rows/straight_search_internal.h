#pragma once
// What the straight-row search's two files (straight_search.cc: bands,
// Hough, combs and local search; straight_search_fit.cc: the least-squares
// refit and the result) share: a threshold and two factors of a
// hypothesis's score. Private to engine/rows.

#include <vector>

#include "engine/rows/row_detector.h"

namespace plantscale::rows::straight_internal {

// Below this factor 1 − g·Δv the rows are too compressed to use.
constexpr double kMinShrink = 0.25;

inline double MeanOccupancy(const std::vector<DetectedRow>& rows) {
  if (rows.empty()) return 0.0;
  double sum = 0.0;
  for (const DetectedRow& r : rows) sum += r.occupancy;
  return sum / static_cast<double>(rows.size());
}

// Two rows fix a vanishing point whatever it is; every further row is a
// test of the perspective constraint, so hypotheses with more rows found
// are trusted more: n / (n + 1).
inline double RowCountFactor(const std::vector<DetectedRow>& rows) {
  const double n = static_cast<double>(rows.size());
  return n / (n + 1.0);
}

}  // namespace plantscale::rows::straight_internal
