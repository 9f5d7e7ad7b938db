// The row spacing's check against the crop profile (spacing_check.h): on a
// scalar filter, one measurement z of r̄ with variance R, the statistic is
// the measurement's own innovation test and the spacing it names is z.
#include "engine/tracking/spacing_check.h"

#include <gtest/gtest.h>

#include <cmath>

namespace plantscale::tracking {
namespace {

struct Posterior {
  double mean, var;
};

Posterior Update(double prior_m, double prior_var, double z, double r) {
  const double k = prior_var / (prior_var + r);
  return {prior_m + k * (z - prior_m), (1.0 - k) * prior_var};
}

TEST(SpacingCheck, IsTheInnovationTestAndNamesWhatTheFramesMeasured) {
  const double r0 = 0.45, v0 = 0.005 * 0.005 + 0.004 * 0.004;  // prior with a walk
  SpacingCheck check(10.83);
  check.Start(r0, 0.005 * 0.005);
  check.AddNoise(0.004 * 0.004);
  EXPECT_NEAR(check.prior_var(), v0, 1e-15);
  const double z = 0.50, r = 0.002 * 0.002;
  const Posterior p = Update(r0, v0, z, r);
  const auto m = check.Check(p.mean, p.var);
  ASSERT_TRUE(m.has_value());
  // d² = (z − r₀)²/(V₀ + R): the innovation's test.
  EXPECT_NEAR(m->chi2, (z - r0) * (z - r0) / (v0 + r), 1e-6 * m->chi2);
  EXPECT_NEAR(m->measured_m, z, 1e-9);
  EXPECT_NEAR(m->measured_sd_m, std::sqrt(r), 1e-9);
  EXPECT_NEAR(m->estimate_m, p.mean, 1e-15);
  EXPECT_NEAR(m->profile_m, r0, 1e-15);
  EXPECT_TRUE(check.current().has_value());
  EXPECT_NE(m->Text().find("measured 0.500 m"), std::string::npos) << m->Text();
  EXPECT_NE(m->Text().find("profile says 0.450 m"), std::string::npos) << m->Text();
}

TEST(SpacingCheck, QuietWithinThePriorAndBeforeTheFramesKnowTheSpacing) {
  const double r0 = 0.475, v0 = 0.005 * 0.005, r = 0.002 * 0.002;
  SpacingCheck check(10.83);
  check.Start(r0, v0);
  // 2.5 σ of the innovation off: d² 6.25, not a mismatch.
  const double z_ok = r0 + 2.5 * std::sqrt(v0 + r);
  const Posterior ok = Update(r0, v0, z_ok, r);
  EXPECT_FALSE(check.Check(ok.mean, ok.var).has_value());
  EXPECT_FALSE(check.current().has_value());
  // Far off but measured no better than the prior (P > V₀/2): not tested.
  const Posterior weak = Update(r0, v0, r0 + 0.05, 2.0 * v0);
  EXPECT_GT(weak.var, 0.5 * v0);
  EXPECT_FALSE(check.Check(weak.mean, weak.var).has_value());
  // Off by 4 σ of the innovation: a mismatch; a restart forgets it.
  const double z_bad = r0 + 4.0 * std::sqrt(v0 + r);
  const Posterior bad = Update(r0, v0, z_bad, r);
  EXPECT_TRUE(check.Check(bad.mean, bad.var).has_value());
  check.Start(r0, v0);
  EXPECT_FALSE(check.current().has_value());
  // Off: never checked.
  SpacingCheck off(0.0);
  off.Start(r0, v0);
  EXPECT_FALSE(off.Check(bad.mean, bad.var).has_value());
}

// The camera's scale error (not in the filter) moves r̂ as well: its
// variance widens the test and the measured spacing's sd.
TEST(SpacingCheck, AllowsTheCamerasScaleError) {
  const double r0 = 0.475, v0 = 0.005 * 0.005, r = 0.002 * 0.002;
  const double vs = std::pow(0.015 * r0, 2);  // a 1.5 % scale
  const double z = r0 + 3.0 * std::sqrt(v0 + r);  // d² 9 without the scale
  const Posterior p = Update(r0, v0, z, r);
  SpacingCheck tight(4.0);
  tight.Start(r0, v0);
  const auto without = tight.Check(p.mean, p.var);
  ASSERT_TRUE(without.has_value());
  SpacingCheck wide(4.0);
  wide.Start(r0, v0, vs);
  EXPECT_FALSE(wide.Check(p.mean, p.var).has_value());  // d² 9·(V₀+R)/(V₀+R+Vs) ≈ 3.3
  const Posterior far = Update(r0, v0, r0 + 0.05, r);
  const auto m = wide.Check(far.mean, far.var);
  ASSERT_TRUE(m.has_value());
  // The move from the prior against its own variance plus the scale's.
  const double moved = far.mean - r0;
  EXPECT_NEAR(m->chi2, moved * moved / (v0 - far.var + vs), 1e-6 * m->chi2);
  EXPECT_NEAR(m->measured_m, r0 + 0.05, 1e-9);
  EXPECT_NEAR(m->measured_sd_m, std::sqrt(r + vs), 1e-9);
  EXPECT_NEAR(m->profile_sd_m, std::sqrt(v0 + vs), 1e-12);
}

}  // namespace
}  // namespace plantscale::tracking
