#include "engine/tracking/kalman_filter.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>

#include "engine/tracking/observation_model.h"

namespace plantscale::tracking {

using geometry::GridState;
using geometry::Matrix5d;

GridFilter::GridFilter(const TrackerOptions& options) : options_(options), layout_(options) {
  Reset();
}

void GridFilter::Reset() {
  const int h = layout_.head();
  x_ = Eigen::VectorXd::Zero(h);
  x_(GridState::kForward) = options_.plant_spacing_m;
  if (options_.estimate_spacing) {
    x_(GridState::kRowSpacing) = options_.row_spacing_m;
    x_(GridState::kPlantSpacing) = options_.plant_spacing_m;
  }
  p_ = Eigen::MatrixXd::Zero(h, h);
  if (options_.estimate_odometry_scale) {
    const int k = layout_.scale_index();
    p_(k, k) = options_.odometry_scale_sd * options_.odometry_scale_sd;
  }
  ResetBounce();
  ResetCalibration();
  offsets_.clear();
}

void GridFilter::Restart(const GridState& s, const Matrix5d& covariance) {
  const int core = layout_.core();
  const int h = layout_.head();
  offsets_.clear();
  // What was learnt of the wheels' scale outlives a loss of the grid.
  const int ki = layout_.scale_index();
  const double scale_k = options_.estimate_odometry_scale ? x_(ki) : 0.0;
  const double scale_var = options_.estimate_odometry_scale ? p_(ki, ki) : 0.0;
  // So does what was learnt of the calibration.
  const int cal = layout_.calibration_index();
  const bool calibrated = layout_.calibration();
  const Eigen::Vector4d cal_x = calibrated ? Eigen::Vector4d(x_.segment<4>(cal)) : Eigen::Vector4d::Zero();
  const Eigen::Matrix4d cal_p = calibrated ? Eigen::Matrix4d(p_.block<4, 4>(cal, cal)) : Eigen::Matrix4d::Zero();
  x_ = Eigen::VectorXd::Zero(h);
  x_(GridState::kOffset) = s.offset_m;
  x_(GridState::kForward) = s.forward_m;
  x_(GridState::kBearing) = s.bearing_rad;
  if (options_.estimate_spacing) {
    x_(GridState::kRowSpacing) = s.row_spacing_m;
    x_(GridState::kPlantSpacing) = s.plant_spacing_m;
  }
  p_ = Eigen::MatrixXd::Zero(h, h);
  p_.topLeftCorner(core, core) = covariance.topLeftCorner(core, core);
  if (options_.estimate_odometry_scale) {
    x_(ki) = scale_k;
    p_(ki, ki) = scale_var;
  }
  if (calibrated) {
    x_.segment<4>(cal) = cal_x;
    p_.block<4, 4>(cal, cal) = cal_p;
  }
  ResetBounce();
}

GridState GridFilter::state() const {
  GridState s;
  s.offset_m = x_(GridState::kOffset);
  s.forward_m = x_(GridState::kForward);
  s.bearing_rad = x_(GridState::kBearing);
  s.row_spacing_m = options_.estimate_spacing ? x_(GridState::kRowSpacing) : options_.row_spacing_m;
  s.plant_spacing_m =
      options_.estimate_spacing ? x_(GridState::kPlantSpacing) : options_.plant_spacing_m;
  return s;
}

Matrix5d GridFilter::covariance() const {
  const int core = layout_.core();
  Matrix5d c = Matrix5d::Zero();
  c.topLeftCorner(core, core) = p_.topLeftCorner(core, core);
  return c;
}

double GridFilter::OdometryScale() const {
  return options_.estimate_odometry_scale ? 1.0 + x_(layout_.scale_index()) : 1.0;
}

void GridFilter::ResetBounce() {
  if (!layout_.persistent_bounce()) return;
  const int b = layout_.bounce_index();
  x_.segment<3>(b).setZero();
  p_.middleRows(b, 3).setZero();
  p_.middleCols(b, 3).setZero();
  p_.block<3, 3>(b, b) = BouncePrior(options_).asDiagonal();
}

void GridFilter::ResetCalibration() {
  if (!layout_.calibration()) return;
  const int c = layout_.calibration_index();
  x_.segment<4>(c).setZero();
  p_.middleRows(c, 4).setZero();
  p_.middleCols(c, 4).setZero();
  p_.block<4, 4>(c, c) = CalibrationPrior(options_).asDiagonal();
}

void GridFilter::Predict(const Transition& t, double distance) {
  const int h = layout_.head();
  if (layout_.persistent_bounce()) x_.segment<3>(layout_.bounce_index()) *= t.bounce_decay;
  x_(GridState::kOffset) = t.f.state.offset_m;
  x_(GridState::kForward) = t.f.state.forward_m;
  x_(GridState::kBearing) = t.f.state.bearing_rad;
  const int n = static_cast<int>(x_.size());
  const Eigen::MatrixXd phh = p_.topLeftCorner(h, h);
  p_.topLeftCorner(h, h) = t.a * phh * t.a.transpose() + t.q;
  if (n > h) {
    const Eigen::MatrixXd phl = t.a * p_.topRightCorner(h, n - h);
    p_.topRightCorner(h, n - h) = phl;
    p_.bottomLeftCorner(n - h, h) = phl.transpose();
  }
  // Each plant's located centroid wanders as the view of it changes.
  const double across = options_.plant_offset_walk_across_sd_per_sqrt_m *
                        options_.plant_offset_walk_across_sd_per_sqrt_m * distance;
  const double along = options_.plant_offset_walk_along_sd_per_sqrt_m *
                       options_.plant_offset_walk_along_sd_per_sqrt_m * distance;
  for (const PlantOffset& o : offsets_) {
    p_(o.index, o.index) += across;
    p_(o.index + 1, o.index + 1) += along;
  }
}

void GridFilter::AddFrameNoise() {
  p_(GridState::kOffset, GridState::kOffset) += std::pow(options_.frame_offset_sd_m, 2);
  p_(GridState::kForward, GridState::kForward) += std::pow(options_.frame_forward_sd_m, 2);
  p_(GridState::kBearing, GridState::kBearing) += std::pow(options_.frame_bearing_sd_rad, 2);
}

double GridFilter::AddSpacingNoise(int lines_changed) {
  if (!options_.estimate_spacing || lines_changed <= 0) return 0.0;
  const double q = options_.spacing_step_sd_m * options_.spacing_step_sd_m * lines_changed;
  p_(GridState::kRowSpacing, GridState::kRowSpacing) += q;
  p_(GridState::kPlantSpacing, GridState::kPlantSpacing) += q;
  return q;
}

void GridFilter::ShiftLines(int k, const GridState& shifted) {
  if (options_.estimate_spacing) {
    const int n = static_cast<int>(x_.size());
    Eigen::MatrixXd a = Eigen::MatrixXd::Identity(n, n);
    a(GridState::kForward, GridState::kPlantSpacing) = k;  // eq. 4.8
    x_ = a * x_;
    p_ = a * p_ * a.transpose();
  } else {
    x_(GridState::kForward) = shifted.forward_m;  // eq. 4.7: a control input
  }
  for (PlantOffset& o : offsets_) o.m -= k;
}

int GridFilter::OffsetIndex(int m, int n) const {
  for (const PlantOffset& o : offsets_) {
    if (o.m == m && o.n == n) return o.index;
  }
  return -1;
}

int GridFilter::AddPlant(int m, int n) {
  const int old = static_cast<int>(x_.size());
  const int k = layout_.plant_states();
  x_.conservativeResize(old + k);
  x_.tail(k).setZero();
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(old + k, old + k);
  p.topLeftCorner(old, old) = p_;
  p.bottomRightCorner(k, k) = ObservationModel::PlantPrior(options_).asDiagonal();
  p_ = std::move(p);
  offsets_.push_back({m, n, old});
  return old;
}

void GridFilter::Marginalise(const std::vector<geometry::GridPlant>& in_view, PlantSpread& spread) {
  const double prior = options_.plant_offset_sd_m * options_.plant_offset_sd_m;
  std::vector<int> keep;
  for (int i = 0; i < layout_.head(); ++i) keep.push_back(i);
  std::vector<PlantOffset> kept;
  for (const PlantOffset& o : offsets_) {
    const bool visible = std::any_of(in_view.begin(), in_view.end(), [&](const auto& g) {
      return g.m == o.m && g.n == o.n;
    });
    if (!visible) {  // marginalised: its rows and columns go
      const int i = o.index;
      spread.AddPlant(x_(i), p_(i, i), x_(i + 1), p_(i + 1, i + 1), prior);
      continue;
    }
    kept.push_back({o.m, o.n, static_cast<int>(keep.size())});
    for (int i = 0; i < layout_.plant_states(); ++i) keep.push_back(o.index + i);
  }
  if (kept.size() == offsets_.size()) return;
  x_ = Eigen::VectorXd(x_(keep));
  p_ = Eigen::MatrixXd(p_(keep, keep));
  offsets_ = std::move(kept);
}

int GridFilter::AppendNuisance(const Eigen::Vector3d& bounce_prior) {
  const int persistent = static_cast<int>(x_.size());
  x_.conservativeResize(persistent + 3);
  x_.tail<3>().setZero();
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(persistent + 3, persistent + 3);
  p.topLeftCorner(persistent, persistent) = p_;
  p.bottomRightCorner<3, 3>() = bounce_prior.asDiagonal();
  p_ = std::move(p);
  return persistent;
}

void GridFilter::DropNuisance(int persistent_size) {
  x_.conservativeResize(persistent_size);
  p_.conservativeResize(persistent_size, persistent_size);
}

double GridFilter::Apply(const PseudoObservation& z) {
  // Eqs. 4.73–4.74, P⁺ = (P⁻¹ + LᵀL)⁻¹ and x⁺ = x⁻ + P⁺ Lᵀ r, by the
  // matrix inversion lemma so that only a (2 × features)² matrix is
  // inverted: with S = I + L P Lᵀ and K = P Lᵀ S⁻¹, P⁺ = P − K (P Lᵀ)ᵀ and
  // P⁺ Lᵀ = K. L is zero outside z.support, so P Lᵀ = P(:, support) L(:, support)ᵀ.
  // S is also the whitened innovation covariance: NIS = rᵀ S⁻¹ r.
  const Eigen::MatrixXd l = z.factor(Eigen::all, z.support);
  const Eigen::MatrixXd plt = p_(Eigen::all, z.support) * l.transpose();
  Eigen::MatrixXd s = l * plt(z.support, Eigen::all);
  s.diagonal().array() += 1.0;
  const Eigen::LLT<Eigen::MatrixXd> s_llt(s);
  Eigen::MatrixXd k = s_llt.solve(plt.transpose()).transpose();
  if (!layout_.consider()) {
    x_ += k * z.residual;
    p_.noalias() -= k * plt.transpose();
  } else {
    // Schmidt: the consider states' gain rows are zero; for that gain K̃,
    // P⁺ = P − K̃ Mᵀ − M K̃ᵀ + K̃ S K̃ᵀ (M = P Lᵀ), which leaves their own
    // block unchanged and updates the rest as the full gain would.
    const int c = layout_.calibration_index();
    for (const int i : {c, c + 2, c + 3}) k.row(i).setZero();
    x_ += k * z.residual;
    const Eigen::MatrixXd kmt = k * plt.transpose();
    p_ += k * s * k.transpose() - kmt - kmt.transpose();
  }
  p_ = 0.5 * (p_ + p_.transpose());
  return z.residual.dot(s_llt.solve(z.residual));
}

void GridFilter::Lose() {
  const int h = layout_.head();
  offsets_.clear();
  x_.conservativeResize(h);
  p_.conservativeResize(h, h);
  if (!x_.allFinite() || !p_.allFinite()) {
    x_.setZero();
    p_.setZero();
    if (options_.estimate_odometry_scale) {
      const int k = layout_.scale_index();
      p_(k, k) = options_.odometry_scale_sd * options_.odometry_scale_sd;
    }
  }
}

}  // namespace plantscale::tracking
