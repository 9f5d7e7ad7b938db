#include "engine/motion/row_heading.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace plantscale::motion {
namespace {

// Histogram of x + tan H·y over [lo, lo + bins·bin).
std::vector<double> Histogram(const std::vector<Eigen::Vector3d>& p, double tan_h, double lo,
                              double bin, int bins) {
  std::vector<double> h(static_cast<size_t>(bins), 0.0);
  for (const Eigen::Vector3d& q : p) {
    const int i = static_cast<int>(std::floor((q.x() + tan_h * q.y() - lo) / bin));
    if (i >= 0 && i < bins) h[static_cast<size_t>(i)] += q.z();
  }
  return h;
}

// Sum of squares of the histogram smoothed by (1, 2, 1) / 4: how sharp the rows are.
double Sharpness(const std::vector<double>& h) {
  double s = 0.0;
  for (size_t i = 0; i < h.size(); ++i) {
    const double l = i > 0 ? h[i - 1] : 0.0, r = i + 1 < h.size() ? h[i + 1] : 0.0;
    const double v = 0.25 * (l + 2.0 * h[i] + r);
    s += v * v;
  }
  return s;
}

}  // namespace

OptionErrors RowHeadingOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "bin_m", bin_m);
  RequireInRange(e, "max_angle_rad", max_angle_rad, 0.0, 0.5 * M_PI, false, false);
  RequirePositive(e, "coarse_step_rad", coarse_step_rad);
  RequirePositive(e, "fine_step_rad", fine_step_rad);
  RequireInRange(e, "peak_fraction", peak_fraction, 0.0, 1.0);
  RequirePositive(e, "gate_m", gate_m);
  RequirePositive(e, "scatter_m", scatter_m);
  RequirePositive(e, "initial_sigma_rad", initial_sigma_rad);
  RequirePositive(e, "memory_m", memory_m);
  RequireNonNegative(e, "refit_every_m", refit_every_m);
  RequirePositive(e, "max_half_width_m", max_half_width_m);
  return e;
}

namespace {

// The finite, positively weighted points near the median x: a stray far
// point must not stretch the histogram over kilometres.
std::vector<Eigen::Vector3d> UsablePoints(const std::vector<Eigen::Vector3d>& points,
                                          const RowHeadingOptions& o) {
  std::vector<Eigen::Vector3d> p;
  p.reserve(points.size());
  for (const Eigen::Vector3d& q : points) {
    if (q.allFinite() && q.z() > 0.0) p.push_back(q);
  }
  if (p.size() < 2) return p;
  std::vector<double> xs;
  xs.reserve(p.size());
  for (const Eigen::Vector3d& q : p) xs.push_back(q.x());
  std::nth_element(xs.begin(), xs.begin() + static_cast<long>(xs.size() / 2), xs.end());
  const double median = xs[xs.size() / 2];
  std::erase_if(p, [&](const Eigen::Vector3d& q) {
    return std::abs(q.x() - median) > o.max_half_width_m || std::abs(q.y()) > 1e6;
  });
  return p;
}

// The histogram's span: x + tan H·y stays within the points' x range widened
// by the largest |y| times tan(max angle).
struct HistogramSpan {
  double lo = 0.0;
  int bins = 0;
};

HistogramSpan SpanOf(const std::vector<Eigen::Vector3d>& p, const RowHeadingOptions& o) {
  double x_lo = p[0].x(), x_hi = x_lo, y_abs = 0.0;
  for (const Eigen::Vector3d& q : p) {
    x_lo = std::min(x_lo, q.x()), x_hi = std::max(x_hi, q.x()), y_abs = std::max(y_abs, std::abs(q.y()));
  }
  const double reach = y_abs * std::tan(o.max_angle_rad) + 2.0 * o.bin_m;
  const double lo = x_lo - reach;
  return {lo, static_cast<int>(std::ceil((x_hi + reach - lo) / o.bin_m)) + 1};
}

// Step 1: the heading whose histogram is sharpest, coarse then fine.
double SharpestHeading(const std::vector<Eigen::Vector3d>& p, const HistogramSpan& span,
                       const RowHeadingOptions& o) {
  auto best_in = [&](double from, double to, double step, double start) {
    double best = start, best_score = -1.0;
    for (double h = from; h <= to + 1e-12; h += step) {
      const double s = Sharpness(Histogram(p, std::tan(h), span.lo, o.bin_m, span.bins));
      if (s > best_score) best_score = s, best = h;
    }
    return best;
  };
  const double h = best_in(-o.max_angle_rad, o.max_angle_rad, o.coarse_step_rad, 0.0);
  return best_in(h - o.coarse_step_rad, h + o.coarse_step_rad, o.fine_step_rad, h);
}

// Step 2: rows at the peaks of the 2-bin-wide histogram at heading h, as
// values of x + tan H·y.
std::vector<double> RowPeaks(const std::vector<Eigen::Vector3d>& p, double h,
                             const HistogramSpan& span, const RowHeadingOptions& o) {
  const std::vector<double> hist =
      Histogram(p, std::tan(h), span.lo, 2.0 * o.bin_m, (span.bins + 1) / 2);
  const double top = *std::max_element(hist.begin(), hist.end());
  std::vector<double> row_x;
  for (size_t i = 0; i < hist.size(); ++i) {
    const double l = i > 0 ? hist[i - 1] : 0.0, r = i + 1 < hist.size() ? hist[i + 1] : 0.0;
    if (hist[i] > 0.0 && hist[i] >= l && hist[i] > r && hist[i] >= o.peak_fraction * top)
      row_x.push_back(span.lo + (static_cast<double>(i) + 0.5) * 2.0 * o.bin_m);
  }
  return row_x;
}

// Weighted sums of the points each row gathers (its nearest line within the gate).
struct RowSums {
  std::vector<double> w, x, y, xy, yy;
};

RowSums GatherRows(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& row_x,
                   double slope, double gate_m) {
  const size_t n = row_x.size();
  RowSums s{std::vector<double>(n), std::vector<double>(n), std::vector<double>(n),
            std::vector<double>(n), std::vector<double>(n)};
  for (const Eigen::Vector3d& q : p) {
    size_t best = n;
    double nearest = gate_m;
    for (size_t r = 0; r < n; ++r) {
      const double d = std::abs(q.x() - slope * q.y() - row_x[r]);
      if (d <= nearest) nearest = d, best = r;
    }
    if (best == n) continue;
    const double w = q.z();
    s.w[best] += w, s.x[best] += w * q.x(), s.y[best] += w * q.y();
    s.xy[best] += w * q.x() * q.y(), s.yy[best] += w * q.y() * q.y();
  }
  return s;
}

}  // namespace

RowHeadingFit FitRowHeading(const std::vector<Eigen::Vector3d>& points, const RowHeadingOptions& o) {
  RowHeadingFit fit;
  fit.sigma_rad = std::numeric_limits<double>::infinity();
  const std::vector<Eigen::Vector3d> p = UsablePoints(points, o);
  if (p.size() < 2) return fit;
  const HistogramSpan span = SpanOf(p, o);
  const double h = SharpestHeading(p, span, o);
  std::vector<double> row_x = RowPeaks(p, h, span, o);
  // Step 3: one slope pooled over the rows (each its own intercept), the
  // rows' points gathered again about it, three times.
  double slope = -std::tan(h);
  RowSums s;
  for (int iteration = 0; iteration < 3; ++iteration) {
    s = GatherRows(p, row_x, slope, o.gate_m);
    double num = 0.0, den = 0.0;
    for (size_t r = 0; r < row_x.size(); ++r) {
      if (s.w[r] <= 0.0) continue;
      num += s.xy[r] - s.x[r] * s.y[r] / s.w[r];
      den += s.yy[r] - s.y[r] * s.y[r] / s.w[r];
    }
    if (den <= 1e-12) return fit;
    slope = num / den;
    fit.sigma_rad = o.scatter_m / std::sqrt(den);
    for (size_t r = 0; r < row_x.size(); ++r) {
      if (s.w[r] > 0.0) row_x[r] = (s.x[r] - slope * s.y[r]) / s.w[r];
    }
  }
  fit.heading_rad = -std::atan(slope);
  fit.rows = 0;
  fit.weight = 0.0;
  for (double w : s.w) fit.rows += w > 0.0 ? 1 : 0, fit.weight += w;
  return fit;
}

RowHeading::RowHeading(const RowHeadingOptions& options) : options_(options) {
  ThrowIfInvalid("RowHeadingOptions", options.Validate());
  fit_.sigma_rad = std::numeric_limits<double>::infinity();
}

void RowHeading::Drive(double distance_m) {
  odometer_m_ += std::abs(distance_m);
  while (!points_.empty() && odometer_m_ - points_.front().odometer_m > options_.memory_m) {
    points_.pop_front();
    changed_ = true;
  }
}

void RowHeading::Add(const Eigen::Vector2d& world_m, double weight) {
  points_.push_back({Eigen::Vector3d(world_m.x(), world_m.y(), weight), odometer_m_});
  changed_ = true;
}

const RowHeadingFit& RowHeading::fit() {
  if (changed_ && (fitted_at_m_ < 0.0 || odometer_m_ - fitted_at_m_ >= options_.refit_every_m)) {
    std::vector<Eigen::Vector3d> p;
    p.reserve(points_.size());
    for (const Point& q : points_) p.push_back(q.xyw);
    fit_ = FitRowHeading(p, options_);
    fitted_at_m_ = odometer_m_;
    changed_ = false;
  }
  return fit_;
}

double RowHeading::heading_rad() {
  const RowHeadingFit& f = fit();
  if (!std::isfinite(f.sigma_rad) || f.sigma_rad <= 0.0) return 0.0;
  const double p_fit = 1.0 / (f.sigma_rad * f.sigma_rad);
  const double p0 = 1.0 / (options_.initial_sigma_rad * options_.initial_sigma_rad);
  return p_fit * f.heading_rad / (p_fit + p0);
}

}  // namespace plantscale::motion
