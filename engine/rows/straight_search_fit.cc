// The straight-row search's last steps (straight_search.h): the weighted
// least-squares refit of the rows' centres (step 4) and the central row,
// comb and result (step 5). Steps 1–3 are in straight_search.cc.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "engine/rows/comb.h"
#include "engine/rows/straight_search.h"
#include "engine/rows/straight_search_internal.h"

namespace plantscale::rows {

namespace {

// The lowest column of `p` in [x0, x1] (ties: the one nearest the middle),
// or −1 when the range leaves [0, fw).
int LowestColumn(const float* p, int fw, int x0, int x1) {
  if (x0 < 0 || x1 >= fw) return -1;
  int lowest = x0;
  for (int x = x0 + 1; x <= x1; ++x) {
    if (p[x] < p[lowest] ||
        (p[x] == p[lowest] && std::abs(x - 0.5 * (x0 + x1)) < std::abs(lowest - 0.5 * (x0 + x1)))) {
      lowest = x;
    }
  }
  return lowest;
}

}  // namespace

using straight_internal::kMinShrink;
using straight_internal::MeanOccupancy;
using straight_internal::RowCountFactor;

// 4. Weighted least squares on each row's centre in thin bands: the
// centroid of its plant matter between the gaps on either side (the lowest
// columns between it and its neighbours), so that rows whose plants nearly
// touch are centred by their edges, narrow rows by their mass. Linear in
// (s_c, d, c − g·s_c, g·d):
//   u = s_c + n·d + Δv·(c − g·s_c) − n·Δv·(g·d).
// With fix_vp the vanishing point stays and only (s_c, d) are fitted,
// linear as well: u − c·Δv = s_c·(1 − g·Δv) + n·d·(1 − g·Δv).
void StraightSearch::Refit(Fit& fit, bool fix_vp) const {
  for (int iteration = 0; iteration < o_.fit_iterations; ++iteration) {
    if (!RefitStep(fit, fix_vp)) break;
  }
}

// One iteration of the refit; false when it stops (too few observations,
// a degenerate or implausible solution, or one without two adjacent rows).
bool StraightSearch::RefitStep(Fit& fit, bool fix_vp) const {
  const int fw = fit_.cols;
  const double kfw = W_ / fw;
  const double kfh = H_ / fit_.rows;
  Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
  Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
  Eigen::Matrix2d a2 = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs2 = Eigen::Vector2d::Zero();
  int observations = 0;
  for (int k = 0; k < fit_bands_; ++k) {
    const Band& b = fbands_[static_cast<size_t>(k)];
    if (b.v_top + b.rows * kfh < fit.found.top_v) continue;
    const double shrink = 1.0 - fit.geo.g * b.dv;
    const double ds = fit.d * shrink;
    if (shrink < kMinShrink || ds < min_spacing_) continue;
    const float* p = &fit_profiles_[static_cast<size_t>(k) * fw];
    const auto column = [&](double u) { return static_cast<int>(std::floor(u / kfw)); };
    for (const DetectedRow& row : fit.found.rows) {
      const int n = row.n;
      const double u = (fit.sc + n * fit.d) * shrink + fit.geo.c * b.dv;
      const double f = o_.gap_search_fraction;
      const int left = LowestColumn(p, fw, column(u - (0.5 + f) * ds), column(u - (0.5 - f) * ds));
      const int right = LowestColumn(p, fw, column(u + (0.5 - f) * ds), column(u + (0.5 + f) * ds));
      if (left < 0 || right <= left + 1) continue;
      double mass = 0.0, moment = 0.0;
      for (int x = left + 1; x < right; ++x) {
        mass += static_cast<double>(p[x]);
        moment += static_cast<double>(p[x]) * (x + 0.5) * kfw;
      }
      // A band where the row has little plant matter says little.
      if (mass < 0.1 * (right - left - 1) * b.rows) continue;
      const double u_obs = moment / mass;
      // Residuals measured in s (u / shrink): a band counts as much at the
      // top of the rows as at the bottom.
      const double ws = mass / (shrink * shrink);
      if (fix_vp) {
        const Eigen::Vector2d z(shrink, n * shrink);
        a2.noalias() += ws * z * z.transpose();
        rhs2.noalias() += ws * (u_obs - fit.geo.c * b.dv) * z;
      } else {
        const Eigen::Vector4d z(1.0, n, b.dv, -n * b.dv);
        a.noalias() += ws * z * z.transpose();
        rhs.noalias() += ws * u_obs * z;
      }
      ++observations;
    }
  }
  if (observations < 6) return false;
  Fit next = fit;
  if (fix_vp) {
    const Eigen::Vector2d q = a2.ldlt().solve(rhs2);
    if (!q.allFinite() || q(1) <= 0.7 * fit.d || q(1) >= 1.3 * fit.d) return false;
    next.d = q(1);
    next.sc = q(0);
  } else {
    const Eigen::LDLT<Eigen::Matrix4d> ldlt(a);
    if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-12)) return false;
    const Eigen::Vector4d q = ldlt.solve(rhs);
    if (!q.allFinite() || q(1) <= 0.7 * fit.d || q(1) >= 1.3 * fit.d) return false;
    next.geo = Geometry{q(3) / q(1), q(2) + q(3) / q(1) * q(0)};
    next.d = q(1);
    next.sc = q(0);
  }
  next.found = FindRows(next.geo, next.d, next.sc);
  if (!next.found.adjacent) return false;
  fit = std::move(next);
  return true;
}

// A fitted comb's score, as the search scored hypotheses.
double StraightSearch::FitScore(const Fit& fit) const {
  if (!fit.found.adjacent) return -1.0;
  return CombOnBands(fit.geo, fit.d).score() * MeanOccupancy(fit.found.rows) * fit.found.contrast *
         RowCountFactor(fit.found.rows) * StreakFactor(fit.geo);
}

// Two fits compete by the score the search used: the full refit from the
// best hypothesis, and the refit of (s_c, d) on the streaks' own vanishing
// point. On photographs of tall, leafy rows the row centres between gaps
// pull the full fit's vanishing point away (the rows merge into a canopy
// towards it) where the streaks still point true; on clean rows of
// separate plants the full fit is the finer one.
StraightSearch::Fit StraightSearch::BestFit(const Fit& searched) {
  fit_bands_ = std::max(4, fit_.rows / 4);
  fbands_ = SplitIntoBands(fit_, fit_bands_, H_ / fit_.rows, v_bottom_, fit_profiles_);
  Fit chosen = searched;
  Refit(chosen, false);
  if (!locked_) return chosen;
  Fit fixed;
  fixed.geo = GeometryAt(lock_g_, lock_lean_);
  fixed.d = searched.d;
  fixed.sc = CombOnBands(fixed.geo, searched.d).phase;
  fixed.found = FindRows(fixed.geo, fixed.d, fixed.sc);
  if (!fixed.found.adjacent) return chosen;
  Refit(fixed, true);
  return FitScore(fixed) > FitScore(chosen) ? fixed : chosen;
}

// Rows are reported up to where they can no longer be told apart: the
// spacing is still min_spacing and a reported row still has plant matter in
// the band (above the bands the fit used, towards the vanishing point).
double StraightSearch::TopOfRows(const Geometry& geo, double d, double sc, const Rows& found) const {
  const double hw = o_.row_halfwidth_fraction;
  double top_v = found.top_v;
  for (int k = n_bands_ - 1; k >= 0; --k) {
    const Band& b = bands_[static_cast<size_t>(k)];
    if (b.v_top >= top_v) continue;
    const double shrink = 1.0 - geo.g * b.dv;
    if (shrink <= 0.0 || d * shrink < min_spacing_) break;
    const float* p = &profiles_[static_cast<size_t>(k) * w_];
    const double half = std::max(0.5 * kw_, hw * d * shrink);
    bool any = false;
    for (const DetectedRow& r : found.rows) {
      const double u = (sc + r.n * d) * shrink + geo.c * b.dv;
      const int x0 = std::max(0, static_cast<int>(std::ceil((u - half) / kw_ - 0.5)));
      const int x1 = std::min(w_ - 1, static_cast<int>(std::floor((u + half) / kw_ - 0.5)));
      double sum = 0.0;
      for (int x = x0; x <= x1; ++x) sum += static_cast<double>(p[x]);
      if (x1 >= x0 && sum / ((x1 - x0 + 1) * b.rows) >= 0.05) any = true;
    }
    if (!any) break;
    top_v = b.v_top;
  }
  if (geo.g > 0.0) top_v = std::max(top_v, v_bottom_ - (1.0 - min_spacing_ / d) / geo.g);
  return std::clamp(top_v, 0.0, v_bottom_);
}

// 5. The central row (nearest the image's centre at the bottom), the comb's
// coherence over every usable band, the confidence.
void StraightSearch::Finish(Fit fit, RowDetection& out) {
  const DetectedRow* central = &fit.found.rows.front();
  for (const DetectedRow& r : fit.found.rows) {
    if (std::abs(r.bottom_u_px - 0.5 * W_) < std::abs(central->bottom_u_px - 0.5 * W_)) central = &r;
  }
  const int n_central = central->n;
  const Geometry geo = fit.geo;
  const double d = fit.d;
  const double sc = fit.sc + n_central * d;
  for (DetectedRow& r : fit.found.rows) r.n -= n_central;
  BuildHistogram(geo, H_);
  const CombFit final_fit = CombAt(histogram_, s0_, kw_, d);
  const double alignment = CombOnBands(geo, d).alignment;
  const double occupancy = MeanOccupancy(fit.found.rows);

  out.centre_u_px = sc;
  out.spacing_px = d;
  out.convergence = geo.g;
  out.lean = geo.c;
  out.coherence = final_fit.coherence;
  out.alignment = alignment;
  out.top_v_px = TopOfRows(geo, d, sc, fit.found);
  out.contrast = fit.found.contrast;
  out.streak_support = use_orientation_ ? orientation_.Support(geo.g, geo.c) : 0.0;
  const bool streaks_confirm = out.streak_support >= o_.min_streak_support;
  const double min_alignment =
      streaks_confirm ? std::min(o_.min_alignment, o_.min_streak_alignment) : o_.min_alignment;
  if (final_fit.coherence < o_.min_coherence || alignment < min_alignment ||
      fit.found.contrast < o_.min_contrast) {
    out.reason = "no rows: plant matter does not follow evenly spaced rows (coherence " +
                 std::to_string(final_fit.coherence) + ", band agreement " +
                 std::to_string(alignment) + ", contrast " + std::to_string(fit.found.contrast) +
                 ", streak support " + std::to_string(out.streak_support) + ")";
    return;
  }
  out.rows = std::move(fit.found.rows);
  out.confidence = std::clamp(final_fit.coherence * occupancy, 1e-3, 1.0);
}

}  // namespace plantscale::rows
