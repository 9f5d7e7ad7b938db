#include "engine/motion/planar_motion.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

namespace plantscale::motion {
namespace {

TEST(PlanarMotion, InverseAndCompositionRoundTrip) {
  const PlanarMotion m{0.1, {0.02, -0.25}}, n{-0.03, {0.01, -0.2}};
  const Eigen::Vector2d p(0.3, 0.6);
  EXPECT_LT((m.ApplyInverse(m.Apply(p)) - p).norm(), 1e-12);
  EXPECT_LT((m.Inverse().Apply(m.Apply(p)) - p).norm(), 1e-12);
  EXPECT_LT((n.After(m).Apply(p) - n.Apply(m.Apply(p))).norm(), 1e-12);
}

TEST(PlanarMotion, WrapAngleStaysInHalfOpenInterval) {
  EXPECT_NEAR(WrapAngle(3.0 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle(-M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle(0.5 - 4.0 * M_PI), 0.5, 1e-12);
}

// Eq. 4: a world point seen at frame k−1 and moved by r, t is where frame k
// sees it; driving forward 0.25 m moves the scene back by 0.25 m.
TEST(PlanarMotion, ComposeFollowsEquationFour) {
  VehiclePose2 pose;
  const PlanarMotion forward{0.0, {0.0, -0.25}};
  pose = Compose(pose, forward);
  EXPECT_NEAR(pose.position_m.y(), 0.25, 1e-12);
  EXPECT_NEAR(pose.position_m.x(), 0.0, 1e-12);
  const PlanarMotion turn{-0.02, {0.004, -0.25}};
  const VehiclePose2 next = Compose(pose, turn);
  EXPECT_NEAR(next.heading_rad, 0.02, 1e-12);  // the scene turns right: the vehicle left
  for (const Eigen::Vector2d& world : {Eigen::Vector2d(0.3, 1.0), Eigen::Vector2d(-0.2, 0.7)}) {
    const Eigen::Vector2d seen = turn.Apply(pose.FromWorld(world));
    EXPECT_LT((seen - next.FromWorld(world)).norm(), 1e-12);
  }
}

TEST(PlanarMotion, FitRigidMotionRecoversAKnownMotionFromNoisyPoints) {
  const PlanarMotion truth{0.012, {0.006, -0.248}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::normal_distribution<double> noise(0.0, 0.001);
  std::vector<Eigen::Vector2d> from, to;
  for (int i = 0; i < 60; ++i) {
    from.emplace_back(u(rng), 0.6 + u(rng));
    to.push_back(truth.Apply(from.back()) + Eigen::Vector2d(noise(rng), noise(rng)));
  }
  const PlanarMotion fit = FitRigidMotion(from, to);
  EXPECT_NEAR(fit.psi_rad, truth.psi_rad, 0.002);  // 1 mm noise over ±0.3 m
  EXPECT_LT((fit.t_m - truth.t_m).norm(), 0.001);
  // A zero weight removes a gross outlier's influence entirely.
  to.push_back({5.0, 5.0});
  from.push_back({0.0, 0.0});
  std::vector<double> w(from.size(), 1.0);
  w.back() = 0.0;
  EXPECT_NEAR(FitRigidMotion(from, to, w).psi_rad, fit.psi_rad, 1e-12);
}

TEST(PlanarMotion, FitRigidMotionWithOnePairIsATranslation) {
  const std::vector<Eigen::Vector2d> from{{0.1, 0.5}}, to{{0.12, 0.25}};
  const PlanarMotion fit = FitRigidMotion(from, to);
  EXPECT_EQ(fit.psi_rad, 0.0);
  EXPECT_LT((fit.t_m - Eigen::Vector2d(0.02, -0.25)).norm(), 1e-12);
}

TEST(PlanarMotion, TriangulationGivesDepthRatioAndDirection) {
  const PlanarMotion m{0.01, {0.0, -0.25}};
  const Eigen::Vector2d p(0.2, 0.7);
  const MatchTriangulation exact = Triangulate(m, p, m.Apply(p));
  EXPECT_NEAR(exact.depth_ratio, 1.0, 1e-12);
  EXPECT_NEAR(exact.direction_error_rad, 0.0, 1e-12);
  // A feature at 1/1.25 of the depth moves 1.25 times as far (eq. 10).
  const MatchTriangulation near = Triangulate(m, p, m.R() * p + 1.25 * m.t_m);
  EXPECT_NEAR(near.depth_ratio, 0.8, 1e-12);
  // Translation turned by 10° (eq. 11).
  const Eigen::Vector2d turned = Eigen::Rotation2Dd(0.1745329) * m.t_m;
  EXPECT_NEAR(Triangulate(m, p, m.R() * p + turned).direction_error_rad, 0.1745329, 1e-9);
}

}  // namespace
}  // namespace plantscale::motion
