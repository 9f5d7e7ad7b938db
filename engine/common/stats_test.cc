#include "engine/common/stats.h"

#include <gtest/gtest.h>

namespace plantscale {
namespace {

TEST(Percentile, InterpolatesBetweenOrderStatistics) {
  EXPECT_DOUBLE_EQ(Percentile({4, 1, 3, 2}, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(Percentile({4, 1, 3, 2}, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(Percentile({4, 1, 3, 2}, 1.0), 4.0);
  EXPECT_NEAR(Percentile({10, 20}, 0.95), 19.5, 1e-12);
  EXPECT_DOUBLE_EQ(Percentile({7}, 0.3), 7.0);
  EXPECT_DOUBLE_EQ(Percentile({}, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(Percentile({1, 2}, 1.5), 2.0);  // q clamped to [0, 1]
}

}  // namespace
}  // namespace plantscale
