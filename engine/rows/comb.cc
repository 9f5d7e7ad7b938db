#include "engine/rows/comb.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <utility>

#include "engine/common/vectorise.h"

namespace plantscale::rows {

namespace {

// Four lanes of doubles (GCC and Clang vector extension): one AVX2
// instruction in the AVX2 clone, two SSE2 instructions in the baseline
// one, NEON pairs on AArch64, plain scalars elsewhere.
typedef double V4 __attribute__((vector_size(32)));

// The body of both PhasorSum overloads, inlined into each of their clones
// (comb.h: eight rotation chains, two vectors of four lanes).
template <typename T>
[[gnu::always_inline]] inline Phasor PhasorSumOf(std::span<const T> w, double a0, double da) {
  const double c1 = std::cos(da), s1 = std::sin(da);
  double pr[8], pi[8];
  pr[0] = std::cos(a0);
  pi[0] = std::sin(a0);
  for (int q = 1; q < 8; ++q) {
    pr[q] = pr[q - 1] * c1 - pi[q - 1] * s1;
    pi[q] = pr[q - 1] * s1 + pi[q - 1] * c1;
  }
  const double c2 = c1 * c1 - s1 * s1, s2 = 2.0 * c1 * s1;
  const double c4 = c2 * c2 - s2 * s2, s4 = 2.0 * c2 * s2;
  const double c8 = c4 * c4 - s4 * s4, s8 = 2.0 * c4 * s4;
  const V4 sr = {c8, c8, c8, c8}, si = {s8, s8, s8, s8};
  V4 ra = {pr[0], pr[1], pr[2], pr[3]}, ia = {pi[0], pi[1], pi[2], pi[3]};
  V4 rb = {pr[4], pr[5], pr[6], pr[7]}, ib = {pi[4], pi[5], pi[6], pi[7]};
  V4 zra = {0.0, 0.0, 0.0, 0.0}, zia = zra, zrb = zra, zib = zra, ma = zra, mb = zra;
  const size_t n = w.size();
  size_t b = 0;
  for (size_t step = 0; b + 8 <= n; b += 8, ++step) {
    const V4 xa = {static_cast<double>(w[b]), static_cast<double>(w[b + 1]),
                   static_cast<double>(w[b + 2]), static_cast<double>(w[b + 3])};
    const V4 xb = {static_cast<double>(w[b + 4]), static_cast<double>(w[b + 5]),
                   static_cast<double>(w[b + 6]), static_cast<double>(w[b + 7])};
    zra += xa * ra;
    zia += xa * ia;
    zrb += xb * rb;
    zib += xb * ib;
    ma += xa;
    mb += xb;
    const V4 na = ra * sr - ia * si, nb = rb * sr - ib * si;
    ia = ra * si + ia * sr;
    ib = rb * si + ib * sr;
    ra = na;
    rb = nb;
    if ((step & 7U) == 7U) {  // keep the rotations on the unit circle
      const V4 one = {1.0, 1.0, 1.0, 1.0};
      V4 ka = ra * ra + ia * ia, kb = rb * rb + ib * ib;
      ka = V4{std::sqrt(ka[0]), std::sqrt(ka[1]), std::sqrt(ka[2]), std::sqrt(ka[3])};
      kb = V4{std::sqrt(kb[0]), std::sqrt(kb[1]), std::sqrt(kb[2]), std::sqrt(kb[3])};
      ka = one / ka;
      kb = one / kb;
      ra *= ka;
      ia *= ka;
      rb *= kb;
      ib *= kb;
    }
  }
  double r[8], i[8], m[8], rr[8], ii[8];
  for (int q = 0; q < 4; ++q) {
    r[q] = zra[q], r[q + 4] = zrb[q], i[q] = zia[q], i[q + 4] = zib[q];
    m[q] = ma[q], m[q + 4] = mb[q], rr[q] = ra[q], rr[q + 4] = rb[q], ii[q] = ia[q], ii[q + 4] = ib[q];
  }
  for (size_t q = 0; b < n; ++b, ++q) {  // the last weights, fewer than eight
    const double x = static_cast<double>(w[b]);
    r[q] += x * rr[q];
    i[q] += x * ii[q];
    m[q] += x;
  }
  Phasor p{0.0, 0.0, 0.0};
  for (int q = 0; q < 8; ++q) p.re += r[q], p.im += i[q], p.mass += m[q];
  return p;
}

}  // namespace

PLANTSCALE_VECTOR_CLONES Phasor PhasorSum(std::span<const double> w, double a0, double da) {
  return PhasorSumOf(w, a0, da);
}
PLANTSCALE_VECTOR_CLONES Phasor PhasorSum(std::span<const float> w, double a0, double da) {
  return PhasorSumOf(w, a0, da);
}

namespace {

// The span of `histogram` that holds weight, [first, last).
std::pair<size_t, size_t> Weighted(std::span<const double> histogram) {
  size_t first = 0;
  size_t last = histogram.size();
  while (first < last && histogram[first] == 0.0) ++first;
  while (last > first && histogram[last - 1] == 0.0) --last;
  return {first, last};
}

// CombAt on the weighted span [first, last) of `histogram`.
CombFit CombOn(std::span<const double> histogram, size_t first, size_t last, double x0,
               double bin_width, double period) {
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

}  // namespace

CombFit CombAt(std::span<const double> histogram, double x0, double bin_width, double period) {
  const auto [first, last] = Weighted(histogram);
  return CombOn(histogram, first, last, x0, bin_width, period);
}

std::vector<CombFit> BestCombs(std::span<const double> histogram, double x0, double bin_width,
                               double min_period, double max_period, double step, int max_fits) {
  std::vector<CombFit> all;
  const auto [first, last] = Weighted(histogram);  // once for every period
  for (double p = min_period; p <= max_period * (1.0 + 1e-9); p *= 1.0 + step) {
    all.push_back(CombOn(histogram, first, last, x0, bin_width, p));
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
