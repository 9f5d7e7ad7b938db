#include "engine/rows/comb.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace plantscale::rows {
namespace {

// The rotated chains against Σ w e^{i(a0 + b·da)} summed term by term,
// over lengths that leave 0–3 weights after the last group of four and
// runs long enough for the chains' renormalisation (every 64 weights).
TEST(PhasorSum, EqualsTheDirectSum) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> weight(0.0, 1.0), angle(-10.0, 10.0);
  for (const size_t n : {0U, 1U, 3U, 4U, 7U, 128U, 385U, 1001U}) {
    std::vector<double> w(n);
    std::vector<float> wf(n);
    for (size_t b = 0; b < n; ++b) wf[b] = static_cast<float>(w[b] = weight(rng));
    const double a0 = angle(rng), da = 0.1 * angle(rng);
    double re = 0.0, im = 0.0, mass = 0.0;
    for (size_t b = 0; b < n; ++b) {
      re += w[b] * std::cos(a0 + static_cast<double>(b) * da);
      im += w[b] * std::sin(a0 + static_cast<double>(b) * da);
      mass += w[b];
    }
    const Phasor z = PhasorSum(std::span<const double>(w), a0, da);
    const Phasor zf = PhasorSum(std::span<const float>(wf), a0, da);
    // Rounding grows with the length of the rotation chains: 1e-12 of the
    // mass over a thousand weights.
    const double tol = 1e-12 * std::max(1.0, mass);
    EXPECT_NEAR(z.re, re, tol) << n;
    EXPECT_NEAR(z.im, im, tol) << n;
    EXPECT_NEAR(z.mass, mass, tol) << n;
    // The float weights are the double ones rounded: 1e-7 of each.
    EXPECT_NEAR(zf.re, re, 1e-6 * std::max(1.0, mass)) << n;
    EXPECT_NEAR(zf.im, im, 1e-6 * std::max(1.0, mass)) << n;
  }
}

// Teeth three bins wide every `period` bins from `first`.
std::vector<double> Teeth(int bins, int first, int period) {
  std::vector<double> h(static_cast<size_t>(bins), 0.0);
  for (int b = first; b + 1 < bins; b += period) {
    h[static_cast<size_t>(b - 1)] += 0.5;
    h[static_cast<size_t>(b)] += 1.0;
    h[static_cast<size_t>(b + 1)] += 0.5;
  }
  return h;
}

TEST(CombTest, CoherenceIsOneOnAPerfectCombAndGivesItsPhase) {
  const std::vector<double> h = Teeth(200, 7, 20);
  // Bins centred at 100 + 2·b: teeth at 114 + 40k.
  const CombFit fit = CombAt(h, 100.0, 2.0, 40.0);
  EXPECT_GT(fit.coherence, 0.95);  // three-bin teeth blur the comb a little
  EXPECT_NEAR(fit.phase, std::fmod(114.0, 40.0), 1e-6);
}

TEST(CombTest, EvenlySpreadMatterHasNoCoherence) {
  const std::vector<double> h(400, 1.0);
  EXPECT_LT(CombAt(h, 0.0, 1.0, 37.0).coherence, 0.02);
}

TEST(CombTest, BestPeriodIsTheFundamentalNotAHarmonic) {
  const std::vector<double> h = Teeth(300, 12, 25);
  const auto fits = BestCombs(h, 0.0, 1.0, 8.0, 150.0, 0.01, 3);
  ASSERT_FALSE(fits.empty());
  EXPECT_NEAR(fits.front().period, 25.0, 0.3);
  EXPECT_NEAR(CombAt(h, 0.0, 1.0, 25.0).phase, 12.0, 1e-6);  // bin b is centred at b
}

TEST(CombTest, VoteCombSpreadsTriangularVotesOnEveryTooth) {
  std::vector<double> line(41, 0.0);
  // Teeth −1, 0, 1 of period 10 through position 2: bins 20 + (2 − 10n)/1.
  VoteComb(line, 20, 1.0, 2.0, 10.0, 1, 3, 2.0);
  EXPECT_DOUBLE_EQ(line[22], 2.0);
  EXPECT_NEAR(line[23], 2.0 * 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(line[12], 2.0, 1e-12);
  EXPECT_NEAR(line[32], 2.0, 1e-12);
  double sum = 0.0;
  for (double v : line) sum += v;
  EXPECT_NEAR(sum, 3 * 2.0 * 3.0, 1e-9);  // each tooth's votes sum to spread × w
}

}  // namespace
}  // namespace plantscale::rows
