#include "engine/rows/comb.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace plantscale::rows {

namespace {

// Two lanes of doubles (GCC and Clang vector extension: SSE2 on x86-64,
// NEON on AArch64, plain scalars elsewhere).
typedef double V2 __attribute__((vector_size(16)));

template <typename T>
Phasor PhasorSumOf(std::span<const T> w, double a0, double da) {
  const double c1 = std::cos(da), s1 = std::sin(da);
  double pr[4], pi[4];
  pr[0] = std::cos(a0);
  pi[0] = std::sin(a0);
  for (int q = 1; q < 4; ++q) {
    pr[q] = pr[q - 1] * c1 - pi[q - 1] * s1;
    pi[q] = pr[q - 1] * s1 + pi[q - 1] * c1;
  }
  const double c2 = c1 * c1 - s1 * s1, s2 = 2.0 * c1 * s1;
  const V2 sr = {c2 * c2 - s2 * s2, c2 * c2 - s2 * s2}, si = {2.0 * c2 * s2, 2.0 * c2 * s2};
  V2 ra = {pr[0], pr[1]}, ia = {pi[0], pi[1]}, rb = {pr[2], pr[3]}, ib = {pi[2], pi[3]};
  V2 zra = {0.0, 0.0}, zia = zra, zrb = zra, zib = zra, ma = zra, mb = zra;
  const size_t n = w.size();
  size_t b = 0;
  for (size_t step = 0; b + 4 <= n; b += 4, ++step) {
    const V2 wa = {static_cast<double>(w[b]), static_cast<double>(w[b + 1])};
    const V2 wb = {static_cast<double>(w[b + 2]), static_cast<double>(w[b + 3])};
    zra += wa * ra;
    zia += wa * ia;
    zrb += wb * rb;
    zib += wb * ib;
    ma += wa;
    mb += wb;
    const V2 na = ra * sr - ia * si, nb = rb * sr - ib * si;
    ia = ra * si + ia * sr;
    ib = rb * si + ib * sr;
    ra = na;
    rb = nb;
    if ((step & 15U) == 15U) {  // keep the rotations on the unit circle
      const V2 one = {1.0, 1.0};
      V2 ka = ra * ra + ia * ia, kb = rb * rb + ib * ib;
      ka = V2{std::sqrt(ka[0]), std::sqrt(ka[1])};
      kb = V2{std::sqrt(kb[0]), std::sqrt(kb[1])};
      ka = one / ka;
      kb = one / kb;
      ra *= ka;
      ia *= ka;
      rb *= kb;
      ib *= kb;
    }
  }
  double zr[4] = {zra[0], zra[1], zrb[0], zrb[1]}, zi[4] = {zia[0], zia[1], zib[0], zib[1]};
  double mass[4] = {ma[0], ma[1], mb[0], mb[1]};
  const double rr[4] = {ra[0], ra[1], rb[0], rb[1]}, ii[4] = {ia[0], ia[1], ib[0], ib[1]};
  for (size_t q = 0; b < n; ++b, ++q) {  // the last weights, fewer than four
    const double x = static_cast<double>(w[b]);
    zr[q] += x * rr[q];
    zi[q] += x * ii[q];
    mass[q] += x;
  }
  return {zr[0] + zr[1] + zr[2] + zr[3], zi[0] + zi[1] + zi[2] + zi[3], mass[0] + mass[1] + mass[2] + mass[3]};
}

}  // namespace

Phasor PhasorSum(std::span<const double> w, double a0, double da) { return PhasorSumOf(w, a0, da); }
Phasor PhasorSum(std::span<const float> w, double a0, double da) { return PhasorSumOf(w, a0, da); }

CombFit CombAt(std::span<const double> histogram, double x0, double bin_width, double period) {
  // Only the span that holds weight.
  size_t first = 0;
  size_t last = histogram.size();
  while (first < last && histogram[first] == 0.0) ++first;
  while (last > first && histogram[last - 1] == 0.0) --last;
  const double da = -2.0 * std::numbers::pi * bin_width / period;
  const double a0 =
      -2.0 * std::numbers::pi * (x0 + static_cast<double>(first) * bin_width) / period;
  const Phasor z = PhasorSum(histogram.subspan(first, last - first), a0, da);
  const double total = z.mass;
  const std::complex<double> sum(z.re, z.im);
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
