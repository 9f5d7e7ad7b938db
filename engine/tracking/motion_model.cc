#include "engine/tracking/motion_model.h"

#include <cmath>

namespace plantscale::tracking {

using geometry::GridState;

MotionPrediction PredictGridMotion(const GridState& x, const WheelIncrement& u,
                                   double track_width_m) {
  const double d = 0.5 * (u.left_m + u.right_m);       // distance driven
  const double a = (u.right_m - u.left_m) / track_width_m;  // turn, CCW positive
  // Rows of the Jacobians are (P'_x, P'_y, Ψ'); columns the 5 states then u_1, u_2.
  using Row7 = Eigen::Matrix<double, 1, 7>;
  Row7 dd = Row7::Zero();
  dd(5) = 0.5;
  dd(6) = 0.5;
  Row7 da = Row7::Zero();
  da(5) = -1.0 / track_width_m;
  da(6) = 1.0 / track_width_m;

  // The grid's plant (m = 0, n = 0) in the old vehicle frame.
  const double c = std::cos(x.bearing_rad);
  const double s = std::sin(x.bearing_rad);
  const Eigen::Vector2d p0(x.offset_m + s * x.forward_m, c * x.forward_m);
  Eigen::Matrix<double, 2, 7> dp0 = Eigen::Matrix<double, 2, 7>::Zero();
  dp0(0, GridState::kOffset) = 1.0;
  dp0(0, GridState::kForward) = s;
  dp0(0, GridState::kBearing) = c * x.forward_m;
  dp0(1, GridState::kForward) = c;
  dp0(1, GridState::kBearing) = -s * x.forward_m;

  // Vehicle displacement (mid-point heading) in the old vehicle frame.
  const double ch = std::cos(0.5 * a);
  const double sh = std::sin(0.5 * a);
  const Eigen::Vector2d t(-d * sh, d * ch);
  const Eigen::Matrix<double, 2, 7> dt =
      Eigen::Vector2d(-sh, ch) * dd + Eigen::Vector2d(-0.5 * d * ch, -0.5 * d * sh) * da;

  // Into the new vehicle frame: p' = R(−a) (p0 − t).
  const Eigen::Vector2d q = p0 - t;
  const Eigen::Matrix<double, 2, 7> dq = dp0 - dt;
  const double ca = std::cos(a);
  const double sa = std::sin(a);
  Eigen::Matrix2d rot;
  rot << ca, sa, -sa, ca;
  const Eigen::Vector2d p = rot * q;
  const Eigen::Vector2d dp_da(-sa * q.x() + ca * q.y(), -ca * q.x() - sa * q.y());
  const Eigen::Matrix<double, 2, 7> dp = rot * dq + dp_da * da;

  const double psi = x.bearing_rad + a;
  Row7 dpsi = da;
  dpsi(GridState::kBearing) += 1.0;
  const double cp = std::cos(psi);
  const double tp = std::tan(psi);

  MotionPrediction out;
  out.state = x;
  out.state.bearing_rad = psi;
  out.state.forward_m = p.y() / cp;
  out.state.offset_m = p.x() - tp * p.y();
  const Row7 dforward = dp.row(1) / cp + (p.y() * tp / cp) * dpsi;
  const Row7 doffset = dp.row(0) - tp * dp.row(1) - (p.y() / (cp * cp)) * dpsi;

  Eigen::Matrix<double, 5, 7> j = Eigen::Matrix<double, 5, 7>::Zero();
  j.row(GridState::kOffset) = doffset;
  j.row(GridState::kForward) = dforward;
  j.row(GridState::kBearing) = dpsi;
  j(GridState::kRowSpacing, GridState::kRowSpacing) = 1.0;
  j(GridState::kPlantSpacing, GridState::kPlantSpacing) = 1.0;
  out.d_state = j.leftCols<5>();
  out.d_wheels = j.rightCols<2>();
  return out;
}

}  // namespace plantscale::tracking
