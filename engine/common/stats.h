#pragma once
// Small order statistics shared by the evaluations and benchmarks.

#include <vector>

namespace plantscale {

// The q-quantile (q in [0, 1]) of `values`, linearly interpolated between
// the order statistics (q = 0.5 of {1, 2, 3, 4} is 2.5); 0 when empty.
double Percentile(std::vector<double> values, double q);

}  // namespace plantscale
