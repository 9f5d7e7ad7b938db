#include "engine/rows/comb.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace plantscale::rows {
namespace {

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
