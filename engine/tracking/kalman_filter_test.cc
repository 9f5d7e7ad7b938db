#include "engine/tracking/kalman_filter.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

#include "engine/tracking/process_model.h"

// The filter's arithmetic against the textbook: the update by the matrix
// inversion lemma against the Kalman gain and the Joseph form, Schmidt's
// consider states, the prediction, and the plants' states in and out.

namespace plantscale::tracking {
namespace {

using geometry::GridState;
using geometry::Matrix5d;

Matrix5d Coupled() {
  Eigen::Matrix<double, 5, 5> a;
  a << 0.01, 0.002, 0.0, 0.001, 0.0,  //
      0.0, 0.02, 0.001, 0.0, 0.002,   //
      0.0, 0.0, 0.015, 0.0, 0.0,      //
      0.0, 0.0, 0.0, 0.02, 0.001,     //
      0.0, 0.0, 0.0, 0.0, 0.02;
  return a * a.transpose();
}

// A whitened observation of `rows` rows over `support` (zero elsewhere).
PseudoObservation Random(int rows, int n, const std::vector<int>& support, std::mt19937& rng) {
  std::normal_distribution<double> normal;
  PseudoObservation z{Eigen::MatrixXd::Zero(rows, n), Eigen::VectorXd(rows), support};
  for (int r = 0; r < rows; ++r) {
    for (const int c : support) z.factor(r, c) = 20.0 * normal(rng);
    z.residual(r) = normal(rng);
  }
  return z;
}

std::vector<int> All(int n) {
  std::vector<int> v;
  for (int i = 0; i < n; ++i) v.push_back(i);
  return v;
}

// A filter with two plants and every state coupled by one update.
GridFilter Coupled(const TrackerOptions& o, std::mt19937& rng) {
  GridFilter f(o);
  f.Restart(GridState{0.01, 0.2, 0.02, 0.475, 0.45}, Coupled());
  f.AddPlant(0, 0);
  f.AddPlant(1, -1);
  const int n = static_cast<int>(f.x().size());
  f.Apply(Random(3, n, All(n), rng));
  return f;
}

// The Joseph form's covariance after an update with gain K on the whitened
// observation L (R = I): (I − K L) P (I − K L)ᵀ + K Kᵀ, right for any K.
Eigen::MatrixXd Joseph(const Eigen::MatrixXd& p, const Eigen::MatrixXd& l, const Eigen::MatrixXd& k) {
  const Eigen::MatrixXd i_kl = Eigen::MatrixXd::Identity(p.rows(), p.cols()) - k * l;
  return i_kl * p * i_kl.transpose() + k * k.transpose();
}

TEST(KalmanFilter, UpdateIsTheKalmanGainsAndTheJosephForms) {
  std::mt19937 rng(7);
  const TrackerOptions o;
  GridFilter f = Coupled(o, rng);
  const int n = static_cast<int>(f.x().size());
  ASSERT_EQ(n, f.layout().head() + 2 * f.layout().plant_states());
  // Support: everything but the second plant's states.
  std::vector<int> support = All(n - f.layout().plant_states());
  const PseudoObservation z = Random(4, n, support, rng);
  const Eigen::VectorXd x0 = f.x();
  const Eigen::MatrixXd p0 = f.p();
  const double nis = f.Apply(z);

  const Eigen::MatrixXd s = z.factor * p0 * z.factor.transpose() + Eigen::MatrixXd::Identity(4, 4);
  const Eigen::MatrixXd k = p0 * z.factor.transpose() * s.inverse();
  const Eigen::VectorXd x1 = x0 + k * z.residual;
  const Eigen::MatrixXd p1 = Joseph(p0, z.factor, k);
  EXPECT_LT((f.x() - x1).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((f.p() - p1).cwiseAbs().maxCoeff(), 1e-12 * p0.cwiseAbs().maxCoeff());
  EXPECT_NEAR(nis, z.residual.dot(s.inverse() * z.residual), 1e-9 * nis);
  // The second plant is not observed, yet correlated: it moves too.
  EXPECT_GT((f.x() - x0).tail(f.layout().plant_states()).norm(), 0.0);
  EXPECT_LT((f.p() - f.p().transpose()).cwiseAbs().maxCoeff(), 1e-18);
}

// Schmidt: pitch, height and focal of the calibration are consider states.
TEST(KalmanFilter, ConsiderStatesKeepTheirEstimateAndTheirCovariance) {
  std::mt19937 rng(11);
  TrackerOptions o;
  o.calibration_pitch_sd_rad = 0.004;
  o.calibration_roll_sd_rad = 0.004;
  o.calibration_height_sd_m = 0.01;
  o.calibration_focal_sd = 0.01;
  GridFilter f = Coupled(o, rng);
  ASSERT_TRUE(f.layout().consider());
  const int n = static_cast<int>(f.x().size());
  const int c = f.layout().calibration_index();
  const PseudoObservation z = Random(4, n, All(n), rng);
  const Eigen::VectorXd x0 = f.x();
  const Eigen::MatrixXd p0 = f.p();
  f.Apply(z);

  const Eigen::MatrixXd s = z.factor * p0 * z.factor.transpose() + Eigen::MatrixXd::Identity(4, 4);
  Eigen::MatrixXd k = p0 * z.factor.transpose() * s.inverse();
  for (const int i : {c, c + 2, c + 3}) {
    k.row(i).setZero();
    EXPECT_EQ(f.x()(i), x0(i)) << "consider state " << i;
    for (const int j : {c, c + 2, c + 3}) EXPECT_NEAR(f.p()(i, j), p0(i, j), 1e-18);
  }
  EXPECT_NE(f.x()(c + 1), x0(c + 1)) << "the roll is estimated";
  EXPECT_LT((f.x() - (x0 + k * z.residual)).cwiseAbs().maxCoeff(), 1e-12);
  // The Joseph form with the consider gain: the covariance of that estimate.
  EXPECT_LT((f.p() - Joseph(p0, z.factor, k)).cwiseAbs().maxCoeff(), 1e-12 * p0.cwiseAbs().maxCoeff());
}

TEST(KalmanFilter, PredictionIsAPAtPlusQWithThePlantsWalk) {
  std::mt19937 rng(13);
  const TrackerOptions o;
  GridFilter f = Coupled(o, rng);
  const int h = f.layout().head();
  const int n = static_cast<int>(f.x().size());
  const Eigen::MatrixXd p0 = f.p();
  const double distance = 0.05;
  const Transition t = TransitionFrom(f.layout(), o, f.state(), f.OdometryScale(), {0.048, 0.052},
                                      0.0015, 0.0016, 0.07);
  f.Predict(t, distance);
  EXPECT_EQ(f.x()(GridState::kForward), t.f.state.forward_m);
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(n, n);
  a.topLeftCorner(h, h) = t.a;
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(n, n);
  q.topLeftCorner(h, h) = t.q;
  for (const PlantOffset& plant : f.plants()) {
    q(plant.index, plant.index) = std::pow(o.plant_offset_walk_across_sd_per_sqrt_m, 2) * distance;
    q(plant.index + 1, plant.index + 1) = std::pow(o.plant_offset_walk_along_sd_per_sqrt_m, 2) * distance;
  }
  EXPECT_LT((f.p() - (a * p0 * a.transpose() + q)).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(KalmanFilter, APlantEntersAtItsPriorAndLeavesMarginalised) {
  std::mt19937 rng(17);
  const TrackerOptions o;
  GridFilter f = Coupled(o, rng);  // plants (0, 0) and (1, −1)
  const int k = f.layout().plant_states();
  const int third = f.AddPlant(2, 1);
  EXPECT_EQ(f.OffsetIndex(2, 1), third);
  EXPECT_EQ(f.OffsetIndex(5, 5), -1);
  EXPECT_NEAR(f.p()(third, third), o.plant_offset_sd_m * o.plant_offset_sd_m, 1e-18);
  EXPECT_NEAR(f.p()(third + 2, third + 2), o.plant_height_sd_m * o.plant_height_sd_m, 1e-18);
  EXPECT_EQ(f.p().row(third).head(third).norm(), 0.0);
  const int n = static_cast<int>(f.x().size());
  f.Apply(Random(3, n, All(n), rng));
  const Eigen::VectorXd x0 = f.x();
  const Eigen::MatrixXd p0 = f.p();
  // (1, −1) leaves the view: its rows and columns go, the rest is as it was.
  std::vector<geometry::GridPlant> in_view(2);
  in_view[0].m = 0, in_view[0].n = 0;
  in_view[1].m = 2, in_view[1].n = 1;
  PlantSpread spread;
  f.Marginalise(in_view, spread);
  ASSERT_EQ(f.plants().size(), 2u);
  const int second = f.layout().head() + k;
  EXPECT_EQ(f.OffsetIndex(1, -1), -1);
  EXPECT_EQ(f.OffsetIndex(2, 1), second);
  std::vector<int> kept = All(second);
  for (int i = 0; i < k; ++i) kept.push_back(third + i);
  EXPECT_EQ(f.x(), Eigen::VectorXd(x0(kept)));
  EXPECT_EQ(f.p(), Eigen::MatrixXd(p0(kept, kept)));
  // A plant counts in the spread only when the frames pinned it.
  const double prior = o.plant_offset_sd_m * o.plant_offset_sd_m;
  const bool pinned_across = p0(third - k, third - k) < 0.5 * prior;
  EXPECT_EQ(spread.across, pinned_across ? 1 : 0);
}

TEST(KalmanFilter, ThePlantSpreadCountsOnlyPinnedOffsets) {
  PlantSpread spread;
  const double prior = 0.015 * 0.015;
  spread.AddPlant(0.006, 0.1 * prior, -0.01, 0.6 * prior, prior);  // along not pinned
  spread.AddPlant(-0.008, 0.2 * prior, 0.004, 0.1 * prior, prior);
  spread.AddPlant(std::nan(""), 0.1 * prior, 0.0, 0.1 * prior, prior);  // across not finite
  EXPECT_EQ(spread.across, 2);
  EXPECT_EQ(spread.along, 2);
  EXPECT_NEAR(spread.across_sd_m(), std::sqrt((0.006 * 0.006 + 0.008 * 0.008) / 2), 1e-15);
  EXPECT_NEAR(spread.along_sd_m(), std::sqrt(0.004 * 0.004 / 2), 1e-15);
  EXPECT_TRUE(std::isnan(PlantSpread{}.across_sd_m()));
}

}  // namespace
}  // namespace plantscale::tracking
