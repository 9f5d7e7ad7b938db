#include "engine/rows/centre_refine.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "engine/rows/row_detector.h"

namespace plantscale::rows {

OptionErrors CentreRefineOptions::Validate() const {
  OptionErrors e;
  if (bands < 1) e.push_back({"bands", "must be >= 1"});
  RequireInRange(e, "window_fraction", window_fraction, 0.0, 1.0, false);
  if (iterations < 1) e.push_back({"iterations", "must be >= 1"});
  RequireInRange(e, "max_shift", max_shift, 0.0, 1.0);
  if (degree < 0 || degree > 4) e.push_back({"degree", "must be in [0, 4]"});
  if (spacing_degree < 0 || spacing_degree > 4) e.push_back({"spacing_degree", "must be in [0, 4]"});
  RequireInRange(e, "row_ridge", row_ridge, 0.0, 1e6);
  RequireInRange(e, "shared_ridge", shared_ridge, 0.0, 1e6);
  RequireInRange(e, "min_band_matter", min_band_matter, 0.0, 1e3);
  if (min_row_bands < 1) e.push_back({"min_row_bands", "must be >= 1"});
  RequireInRange(e, "outlier_scale", outlier_scale, 0.0, 10.0, false);
  if (robust_iterations < 0) e.push_back({"robust_iterations", "must be >= 0"});
  return e;
}

namespace {

double Poly(const std::vector<double>& coefficients, double s) {
  double y = 0.0;
  for (size_t p = coefficients.size(); p-- > 0;) y = y * s + coefficients[p];
  return y;
}

// One band's column profile (plant matter per row of the band) less its
// median, clipped at 0, with the cumulative sums a window's mass and
// centroid are read from.
class Profile {
 public:
  explicit Profile(int cols)
      : p_(static_cast<size_t>(cols)), sorted_(p_.size()), m0_(p_.size() + 1), m1_(p_.size() + 1) {}

  void Load(const cv::Mat& plant, int r0, int r1) {
    std::fill(p_.begin(), p_.end(), 0.0);
    for (int r = r0; r < r1; ++r) {
      const float* row = plant.ptr<float>(r);
      for (size_t x = 0; x < p_.size(); ++x) p_[x] += static_cast<double>(row[x]);
    }
    sorted_ = p_;
    const auto mid = sorted_.begin() + static_cast<std::ptrdiff_t>(sorted_.size() / 2);
    std::nth_element(sorted_.begin(), mid, sorted_.end());
    const double background = *mid;
    const double rows = std::max(1, r1 - r0);
    for (size_t x = 0; x < p_.size(); ++x) {
      const double q = std::max(0.0, p_[x] - background) / rows;
      m0_[x + 1] = m0_[x] + q;
      m1_[x + 1] = m1_[x] + q * (static_cast<double>(x) + 0.5);
    }
  }

  int cols() const { return static_cast<int>(p_.size()); }

  // Mass and centroid (in columns, pixel centres at +0.5) of the columns
  // whose centres lie in [x − h, x + h].
  std::pair<double, double> Window(double x, double h) const {
    const int a = std::max(0, static_cast<int>(std::ceil(x - h - 0.5)));
    const int b = std::min(cols() - 1, static_cast<int>(std::floor(x + h - 0.5)));
    if (b < a) return {0.0, x};
    const double m = m0_[static_cast<size_t>(b) + 1] - m0_[static_cast<size_t>(a)];
    if (m <= 0.0) return {0.0, x};
    return {m, (m1_[static_cast<size_t>(b) + 1] - m1_[static_cast<size_t>(a)]) / m};
  }

 private:
  std::vector<double> p_, sorted_, m0_, m1_;
};

// The mean shift from x0 (fit columns) with half-window h, held within
// `reach` of x0: {mass at the end, centre}.
std::pair<double, double> MeanShift(const Profile& profile, double x0, double h, double reach,
                                    int iterations) {
  double x = x0, mass = 0.0;
  for (int i = 0; i < iterations; ++i) {
    const auto [m, centre] = profile.Window(x, h);
    mass = m;
    if (m <= 0.0) break;
    const double next = std::clamp(centre, x0 - reach, x0 + reach);
    if (std::abs(next - x) < 1e-3) break;
    x = next;
  }
  return {mass, x};
}

}  // namespace

std::vector<CentreObservation> ObserveCentres(const cv::Mat& plant, double kfw, double kfh,
                                              const RowDetection& det, const CentreRefineOptions& o) {
  std::vector<CentreObservation> obs;
  if (det.rows.empty() || plant.empty() || plant.type() != CV_32FC1) return obs;
  const int fh = plant.rows;
  const int r_top = std::clamp(static_cast<int>(std::floor(det.top_v_px / kfh)), 0, fh - 1);
  const int span = fh - r_top;
  const int n_bands = std::min(o.bands, span);
  Profile profile(plant.cols);
  for (int k = 0; k < n_bands; ++k) {
    const int r1 = fh - k * span / n_bands, r0 = fh - (k + 1) * span / n_bands;
    const double v = 0.5 * (r0 + r1) * kfh;
    const double dx = det.SpacingAt(v) / kfw;
    if (!(dx >= 4.0)) continue;
    profile.Load(plant, r0, r1);
    const double h = o.window_fraction * dx;
    for (const DetectedRow& row : det.rows) {
      const double x0 = det.U(row.n, v) / kfw;
      if (x0 - h < 0.0 || x0 + h > plant.cols) continue;  // a clipped window pulls inwards
      const auto [mass, x] = MeanShift(profile, x0, h, o.max_shift * dx, o.iterations);
      if (mass > 0.0) obs.push_back({row.n, v, (x - x0) / dx, mass / dx});
    }
  }
  double mean = 0.0;
  for (const CentreObservation& c : obs) mean += c.weight;
  if (obs.empty() || !(mean > 0.0)) return {};
  mean /= static_cast<double>(obs.size());
  std::erase_if(obs, [&](const CentreObservation& c) { return c.weight < o.min_band_matter * mean; });
  for (CentreObservation& c : obs) c.weight /= mean;
  return obs;
}

namespace {

// The design of step 2: columns A (P), B (P), then P per row with its own R_n.
struct Design {
  int P = 1;
  int PB = 1;            // B's terms (the rest of its P columns stay 0)
  std::vector<int> own;  // rows with their own R_n
  double v_bottom = 0.0, height = 1.0, t_max = 1.0;

  int Columns() const { return P * (2 + static_cast<int>(own.size())); }
  int Slot(int n) const {
    const auto it = std::find(own.begin(), own.end(), n);
    return it == own.end() ? -1 : static_cast<int>(it - own.begin());
  }
  double S(double v) const { return std::clamp((v_bottom - v) / height / t_max, 0.0, 1.0); }
  // The row of the design matrix of an observation.
  Eigen::VectorXd Row(const CentreObservation& c) const {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(Columns());
    const int slot = Slot(c.n);
    double power = 1.0;
    const double s = S(c.v_px);
    for (int p = 0; p < P; ++p, power *= s) {
      x[p] = power;
      if (p < PB) x[P + p] = c.n * power;
      if (slot >= 0) x[P * (2 + slot) + p] = power;
    }
    return x;
  }
};

Design MakeDesign(const std::vector<CentreObservation>& obs, const RowDetection& det,
                  const CentreRefineOptions& o) {
  Design d;
  d.P = o.degree + 1;
  d.PB = std::min(o.degree, o.spacing_degree) + 1;
  d.v_bottom = det.height_px - 0.5;
  d.height = det.height_px;
  double t_max = 0.0;
  for (const CentreObservation& c : obs) t_max = std::max(t_max, (d.v_bottom - c.v_px) / d.height);
  d.t_max = std::max(t_max, 1e-3);
  for (const DetectedRow& row : det.rows) {
    const auto bands = std::count_if(obs.begin(), obs.end(), [&](const CentreObservation& c) { return c.n == row.n; });
    if (bands >= o.min_row_bands) d.own.push_back(row.n);
  }
  return d;
}

// Tukey's biweight of a residual r (spacings) at scale c.
double Tukey(double r, double c) {
  const double q = r / c;
  return std::abs(q) >= 1.0 ? 0.0 : (1.0 - q * q) * (1.0 - q * q);
}

}  // namespace

CentreRefinement FitCentres(const std::vector<CentreObservation>& obs, const RowDetection& det,
                            const CentreRefineOptions& o) {
  CentreRefinement out;
  if (obs.empty()) return out;
  const Design design = MakeDesign(obs, det, o);
  const int P = design.P, cols = design.Columns();
  std::vector<Eigen::VectorXd> rows;
  rows.reserve(obs.size());
  for (const CentreObservation& c : obs) rows.push_back(design.Row(c));
  std::vector<double> robust(obs.size(), 1.0);
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(cols);
  for (int it = 0; it <= o.robust_iterations; ++it) {
    Eigen::MatrixXd N = Eigen::MatrixXd::Zero(cols, cols);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(cols);
    for (size_t i = 0; i < obs.size(); ++i) {
      const double w = obs[i].weight * robust[i];
      N.selfadjointView<Eigen::Lower>().rankUpdate(rows[i], w);
      b += w * obs[i].offset * rows[i];
    }
    N = N.selfadjointView<Eigen::Lower>();
    for (int j = 0; j < cols; ++j) N(j, j) += j < 2 * P ? o.shared_ridge : o.row_ridge;
    beta = N.ldlt().solve(b);
    for (size_t i = 0; i < obs.size(); ++i) {
      robust[i] = Tukey(obs[i].offset - rows[i].dot(beta), o.outlier_scale);
    }
  }
  const auto coefficients = [&](int first) {
    return std::vector<double>(beta.data() + first, beta.data() + first + P);
  };
  out.shared_a = coefficients(0);
  out.shared_b = coefficients(P);
  out.rows = design.own;
  for (size_t r = 0; r < design.own.size(); ++r) {
    out.row_r.push_back(coefficients(P * (2 + static_cast<int>(r))));
    out.row_s.emplace_back(1.0, 0.0);
  }
  for (const CentreObservation& c : obs) {
    const int slot = design.Slot(c.n);
    if (slot < 0) continue;
    auto& [lo, hi] = out.row_s[static_cast<size_t>(slot)];
    lo = std::min(lo, design.S(c.v_px));
    hi = std::max(hi, design.S(c.v_px));
  }
  out.v_bottom = design.v_bottom;
  out.height = design.height;
  out.t_max = design.t_max;
  return out;
}

double CentreRefinement::Offset(int n, double v_px) const {
  if (empty()) return 0.0;
  const double s = std::clamp((v_bottom - v_px) / height / t_max, 0.0, 1.0);
  double e = Poly(shared_a, s) + n * Poly(shared_b, s);
  const auto it = std::find(rows.begin(), rows.end(), n);
  if (it != rows.end()) {
    const size_t i = static_cast<size_t>(it - rows.begin());
    e += Poly(row_r[i], std::clamp(s, row_s[i].first, row_s[i].second));
  }
  return e;
}

}  // namespace plantscale::rows
