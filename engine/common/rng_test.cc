#include "engine/common/rng.h"

#include <gtest/gtest.h>

#include <cmath>

namespace plantscale {
namespace {

TEST(Rng, SameSeedSameSequence) {
  Rng a(42);
  Rng b(42);
  for (int i = 0; i < 1000; ++i) EXPECT_EQ(a.NextU64(), b.NextU64());
}

TEST(Rng, DifferentSeedsDiffer) {
  Rng a(1);
  Rng b(2);
  int equal = 0;
  for (int i = 0; i < 100; ++i) equal += a.NextU64() == b.NextU64() ? 1 : 0;
  EXPECT_EQ(equal, 0);
}

TEST(Rng, NormalMomentsWithinSamplingError) {
  Rng rng(7);
  const int n = 200000;
  double sum = 0.0;
  double sum_sq = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = rng.Normal(3.0, 2.0);
    sum += x;
    sum_sq += x * x;
  }
  const double mean = sum / n;
  const double sd = std::sqrt(sum_sq / n - mean * mean);
  EXPECT_NEAR(mean, 3.0, 0.02);  // standard error 2/sqrt(n) = 0.0045
  EXPECT_NEAR(sd, 2.0, 0.02);
}

TEST(Rng, UniformInUnitInterval) {
  Rng rng(9);
  double low = 1.0;
  double high = 0.0;
  for (int i = 0; i < 100000; ++i) {
    const double u = rng.Uniform();
    low = std::min(low, u);
    high = std::max(high, u);
  }
  EXPECT_GE(low, 0.0);
  EXPECT_LT(high, 1.0);
  EXPECT_LT(low, 1e-3);
  EXPECT_GT(high, 1.0 - 1e-3);
}

TEST(Rng, PoissonMeanWithinSamplingError) {
  Rng rng(11);
  const int n = 50000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) sum += rng.Poisson(4.0);
  EXPECT_NEAR(sum / n, 4.0, 0.05);  // standard error sqrt(4/n) = 0.009
}

TEST(Rng, DerivedStreamsAreIndependentOfEachOther) {
  Rng a = Rng::Derived(5, 1);
  Rng b = Rng::Derived(5, 2);
  EXPECT_NE(a.NextU64(), b.NextU64());
  Rng a2 = Rng::Derived(5, 1);
  Rng a3 = Rng::Derived(5, 1);
  EXPECT_EQ(a2.NextU64(), a3.NextU64());
}

}  // namespace
}  // namespace plantscale
