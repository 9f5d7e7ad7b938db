#include "engine/motion/row_heading.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace plantscale::motion {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Rows `spacing_m` apart through the origin, running along a vehicle heading
// of `heading_rad` (forward (−sin H, cos H)), plants every 0.3 m for
// `length_m` with `jitter_m` scatter, and `weeds` scattered anywhere.
std::vector<Eigen::Vector3d> Field(double heading_rad, double length_m, double jitter_m, int weeds,
                                   unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> jitter(0.0, jitter_m);
  std::uniform_real_distribution<double> across(-0.6, 0.6), along(0.0, length_m);
  const Eigen::Vector2d forward(-std::sin(heading_rad), std::cos(heading_rad));
  const Eigen::Vector2d right(std::cos(heading_rad), std::sin(heading_rad));
  std::vector<Eigen::Vector3d> p;
  for (int row = -1; row <= 1; ++row) {
    for (double s = 0.0; s < length_m; s += 0.3) {
      const Eigen::Vector2d q = (0.4 * row + jitter(rng)) * right + (s + jitter(rng)) * forward;
      p.emplace_back(q.x(), q.y(), 1.0);
    }
  }
  for (int k = 0; k < weeds; ++k) {
    const Eigen::Vector2d q = across(rng) * right + along(rng) * forward;
    p.emplace_back(q.x(), q.y(), 1.0);
  }
  return p;
}

// Three rows 0.6° off the first frame's heading over 6 m, 12 mm planting
// scatter and a weed for every two plants: the Hough and the pooled fit find
// the rows' heading to within 0.15° (the planting scatter alone allows
// 0.05° rms; weeds inside a row's gate add to it) and say how sure they are.
TEST(RowHeading, FitFindsTheRowsHeadingAmongWeeds) {
  const RowHeadingOptions o;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const RowHeadingFit fit = FitRowHeading(Field(0.6 * kDeg, 6.0, 0.012, 30, seed), o);
    EXPECT_NEAR(fit.heading_rad, 0.6 * kDeg, 0.15 * kDeg) << "seed " << seed;
    EXPECT_EQ(fit.rows, 3) << "seed " << seed;
    // σ = 2 cm / sqrt(Σ (y − ȳ)²) with 3 rows × 20 plants over 6 m: 0.04°.
    EXPECT_NEAR(fit.sigma_rad, 0.02 / std::sqrt(3 * 20 * 36.0 / 12.0), 0.01 * kDeg);
  }
  // Rows at the far side of the search range are found as well.
  EXPECT_NEAR(FitRowHeading(Field(-2.5 * kDeg, 6.0, 0.012, 30, 9), o).heading_rad, -2.5 * kDeg,
              0.1 * kDeg);
}

// A NaN and a point a kilometre away (a pixel projected near the horizon)
// change nothing.
TEST(RowHeading, NonFiniteAndFarPointsAreIgnored) {
  std::vector<Eigen::Vector3d> p = Field(0.6 * kDeg, 6.0, 0.012, 0, 4);
  const double clean = FitRowHeading(p, RowHeadingOptions{}).heading_rad;
  p.emplace_back(std::numeric_limits<double>::quiet_NaN(), 1.0, 1.0);
  p.emplace_back(1000.0, 2.0, 1.0);
  p.emplace_back(0.0, std::numeric_limits<double>::infinity(), 1.0);
  EXPECT_EQ(FitRowHeading(p, RowHeadingOptions{}).heading_rad, clean);
  EXPECT_NEAR(clean, 0.6 * kDeg, 0.15 * kDeg);
}

TEST(RowHeading, PointsWithoutSpreadAlongTheRowsSayNothing) {
  std::vector<Eigen::Vector3d> p{{0.0, 0.5, 1.0}, {0.4, 0.5, 1.0}, {-0.4, 0.5, 1.0}};
  EXPECT_TRUE(std::isinf(FitRowHeading(p, RowHeadingOptions{}).sigma_rad));
  RowHeading rows{RowHeadingOptions{}};
  for (const Eigen::Vector3d& q : p) rows.Add(q.head<2>(), q.z());
  EXPECT_EQ(rows.heading_rad(), 0.0);  // the first frame's heading
}

// The heading the vehicle returns to is the fit weighted against the first
// frame's by precision: a metre of one row barely moves it, six metres of
// three rows set it; once driven past the memory the plants are forgotten.
TEST(RowHeading, FusesTheFitWithTheFirstFramesHeadingAndForgets) {
  RowHeadingOptions o;
  o.memory_m = 10.0;
  const double truth = 0.8 * kDeg;
  RowHeading short_run(o);
  for (const Eigen::Vector3d& q : Field(truth, 0.7, 0.012, 0, 3)) {
    if (std::abs(q.x()) < 0.2) short_run.Add(q.head<2>(), q.z());  // the middle row's 3 plants
  }
  const double sigma = short_run.fit().sigma_rad;
  EXPECT_GT(sigma, 1.0 * kDeg);
  const double w = 1.0 / (sigma * sigma) / (1.0 / (sigma * sigma) + 1.0 / std::pow(o.initial_sigma_rad, 2));
  EXPECT_NEAR(short_run.heading_rad(), w * short_run.fit().heading_rad, 1e-12);
  EXPECT_LT(std::abs(short_run.heading_rad()), 0.5 * truth);

  RowHeading long_run(o);
  for (const Eigen::Vector3d& q : Field(truth, 6.0, 0.012, 0, 3)) long_run.Add(q.head<2>(), q.z());
  EXPECT_NEAR(long_run.heading_rad(), truth, 0.1 * kDeg);
  long_run.Drive(10.5);
  EXPECT_EQ(long_run.fit().rows, 0);
  EXPECT_EQ(long_run.heading_rad(), 0.0);
}

TEST(RowHeading, RejectsBadOptions) {
  RowHeadingOptions o;
  o.gate_m = 0.0;
  o.memory_m = -1.0;
  try {
    RowHeading rows(o);
    FAIL() << "accepted bad options";
  } catch (const InvalidOptionsError& e) {
    EXPECT_NE(std::string(e.what()).find("gate_m"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("memory_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace plantscale::motion
