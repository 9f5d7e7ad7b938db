#include "engine/tracking/process_model.h"

#include <gtest/gtest.h>

#include <cmath>

// The process model's transition A against finite differences of the
// motion (the grid's states and the wheels' scale k), and a persistent
// bounce's Gauss–Markov step keeping its stationary variance.

namespace plantscale::tracking {
namespace {

using geometry::GridState;

TEST(ProcessModel, TransitionMatchesFiniteDifferencesOfTheMotion) {
  TrackerOptions o;
  o.camera_bounce_correlation_s = 0.2;
  const StateLayout layout(o);
  ASSERT_EQ(layout.head(), 9);  // core 5, k, bounce 3
  const GridState s{0.02, 0.4, 0.03, 0.475, 0.45};
  const WheelIncrement u{0.048, 0.061};
  const double scale = 1.03;
  const double dt = 0.08;
  const Transition t = TransitionFrom(layout, o, s, scale, u, 0.0015, 0.0018, dt);
  const auto moved = [&](const GridState& from, double k_scale) {
    return TransitionFrom(layout, o, from, k_scale, u, 0.0015, 0.0018, dt).f.state.AsVector();
  };
  const double h = 1e-6;
  for (int i = 0; i < 5; ++i) {
    geometry::Vector5d hi = s.AsVector(), lo = s.AsVector();
    hi(i) += h;
    lo(i) -= h;
    const geometry::Vector5d fd =
        (moved(GridState::FromVector(hi), scale) - moved(GridState::FromVector(lo), scale)) / (2 * h);
    EXPECT_LT((fd - t.a.block<5, 1>(0, i)).cwiseAbs().maxCoeff(), 1e-7) << "state " << i;
  }
  // ∂f/∂k: the increments are (1 + k) × the measured ones.
  const geometry::Vector5d fd_k = (moved(s, scale + h) - moved(s, scale - h)) / (2 * h);
  EXPECT_LT((fd_k - t.a.block<5, 1>(0, layout.scale_index())).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_EQ(t.a(layout.scale_index(), layout.scale_index()), 1.0);
  const double distance = 0.5 * (u.left_m + u.right_m);
  EXPECT_NEAR(t.q(layout.scale_index(), layout.scale_index()),
              o.odometry_scale_step_sd_per_sqrt_m * o.odometry_scale_step_sd_per_sqrt_m * distance, 1e-18);
  // The bounce: b ← a b with a = exp(−dt/τ), and its prior stays its
  // variance (a² P + Q = P).
  const int b = layout.bounce_index();
  const double a = std::exp(-dt / o.camera_bounce_correlation_s);
  EXPECT_NEAR(t.bounce_decay, a, 1e-15);
  const Eigen::Matrix3d prior = BouncePrior(o).asDiagonal();
  const Eigen::Matrix3d stationary =
      t.a.block<3, 3>(b, b) * prior * t.a.block<3, 3>(b, b).transpose() + t.q.block<3, 3>(b, b);
  EXPECT_LT((stationary - prior).cwiseAbs().maxCoeff(), 1e-18);
}

}  // namespace
}  // namespace plantscale::tracking
