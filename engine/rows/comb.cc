#include "engine/rows/comb.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace plantscale::rows {

CombFit CombAt(std::span<const double> histogram, double x0, double bin_width, double period) {
  // Only the span that holds weight.
  size_t first = 0;
  size_t last = histogram.size();
  while (first < last && histogram[first] == 0.0) ++first;
  while (last > first && histogram[last - 1] == 0.0) --last;
  // e^{−2πi x_b / period}, advanced by a fixed rotation from bin to bin
  // (written out: std::complex's product checks for NaN at every step).
  const double omega = -2.0 * std::numbers::pi * bin_width / period;
  const double sr = std::cos(omega), si = std::sin(omega);
  const double a0 =
      -2.0 * std::numbers::pi * (x0 + static_cast<double>(first) * bin_width) / period;
  double pr = std::cos(a0), pi = std::sin(a0);
  double zr = 0.0, zi = 0.0;
  double total = 0.0;
  for (size_t b = first; b < last; ++b) {
    const double w = histogram[b];
    zr += w * pr;
    zi += w * pi;
    total += w;
    const double next_r = pr * sr - pi * si;
    pi = pr * si + pi * sr;
    pr = next_r;
    if (((b - first) & 63U) == 63U) {  // keep the rotation on the unit circle
      const double norm = std::hypot(pr, pi);
      pr /= norm;
      pi /= norm;
    }
  }
  const std::complex<double> sum(zr, zi);
  CombFit fit;
  fit.period = period;
  if (total <= 0.0) return fit;
  fit.coherence = std::abs(sum) / total;
  double phase = -std::arg(sum) * period / (2.0 * std::numbers::pi);
  phase = std::fmod(phase, period);
  if (phase < 0.0) phase += period;
  fit.phase = phase;
  return fit;
}

std::vector<CombFit> BestCombs(std::span<const double> histogram, double x0, double bin_width,
                               double min_period, double max_period, double step, int max_fits) {
  std::vector<CombFit> all;
  for (double p = min_period; p <= max_period * (1.0 + 1e-9); p *= 1.0 + step) {
    all.push_back(CombAt(histogram, x0, bin_width, p));
  }
  std::vector<CombFit> peaks;
  for (size_t i = 0; i < all.size(); ++i) {
    const double left = i > 0 ? all[i - 1].coherence : -1.0;
    const double right = i + 1 < all.size() ? all[i + 1].coherence : -1.0;
    if (all[i].coherence >= left && all[i].coherence > right) peaks.push_back(all[i]);
  }
  std::sort(peaks.begin(), peaks.end(),
            [](const CombFit& a, const CombFit& b) { return a.coherence > b.coherence; });
  if (static_cast<int>(peaks.size()) > max_fits) peaks.resize(static_cast<size_t>(max_fits));
  return peaks;
}

void VoteComb(std::span<double> line, int half, double bin_width, double position, double period,
              int teeth, int spread, double w) {
  const int size = static_cast<int>(line.size());
  for (int n = -teeth; n <= teeth; ++n) {
    const double t = (position - n * period) / bin_width + half;
    const int centre = static_cast<int>(std::floor(t));
    for (int k = centre - spread + 1; k <= centre + spread; ++k) {
      if (k < 0 || k >= size) continue;
      const double vote = 1.0 - std::abs(t - k) / spread;
      if (vote > 0.0) line[static_cast<size_t>(k)] += w * vote;
    }
  }
}

}  // namespace plantscale::rows
