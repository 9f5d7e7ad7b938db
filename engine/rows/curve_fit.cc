#include "engine/rows/curve_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

namespace plantscale::rows {

OptionErrors CurveFitOptions::Validate() const {
  OptionErrors e;
  if (bands < 2) e.push_back({"bands", "must be >= 2"});
  if (phase_steps < 8) e.push_back({"phase_steps", "must be >= 8"});
  RequireInRange(e, "scale_step", scale_step, 0.0, 0.5, false);
  RequireInRange(e, "max_scale", max_scale, 0.0, 2.0);
  RequireInRange(e, "free_max_scale", free_max_scale, 0.0, 2.0);
  if (max_phase_jump < 1 || max_phase_jump >= phase_steps / 2) {
    e.push_back({"max_phase_jump", "must be in [1, phase_steps / 2)"});
  }
  RequireInRange(e, "phase_smoothness", phase_smoothness, 0.0, 1e6);
  RequireInRange(e, "scale_smoothness", scale_smoothness, 0.0, 1e6);
  RequireInRange(e, "scale_prior", scale_prior, 0.0, 1e6);
  RequireInRange(e, "half_comb_weight", half_comb_weight, 0.0, 2.0);
  if (curve_degree < 0 || curve_degree > 5) e.push_back({"curve_degree", "must be in [0, 5]"});
  RequireInRange(e, "min_shrink", min_shrink, 0.0, 1.0, false);
  RequirePositive(e, "min_spacing_px", min_spacing_px);
  RequireInRange(e, "min_free_spacing_fraction", min_free_spacing_fraction, 0.0, 1.0, false);
  if (!(max_free_spacing_fraction > min_free_spacing_fraction)) {
    e.push_back({"max_free_spacing_fraction", "must be > min_free_spacing_fraction"});
  }
  return e;
}

CurveFitter::CurveFitter(const CurveFitOptions& options) : options_(options) {
  ThrowIfInvalid("curve fitter", options.Validate());
}

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Σ_x P[x]·exp(2πi (s_x − ref)/period), s_x = s0 + x·ds: by a rotating phasor.
std::complex<double> Dft(const float* p, int n, double s0, double ds, double ref, double period) {
  const double a = kTwoPi * (s0 - ref) / period;
  const double b = kTwoPi * ds / period;
  std::complex<double> z(std::cos(a), std::sin(a));
  const std::complex<double> step(std::cos(b), std::sin(b));
  std::complex<double> sum = 0.0;
  for (int x = 0; x < n; ++x) {
    sum += static_cast<double>(p[x]) * z;
    z *= step;
    if ((x & 63) == 63) z /= std::abs(z);  // keep the phasor on the unit circle
  }
  return sum;
}

}  // namespace

CurveFit CurveFitter::Fit(const cv::Mat& plant, double kfw, double kfh, double W, double H,
                          const CurvePrior& given) {
  const CurveFitOptions& o = options_;
  CurveFit out;
  if (plant.empty() || plant.type() != CV_32FC1) return out;
  const int fh = plant.rows;
  const int n_bands = std::min(o.bands, fh);
  if (n_bands < 2) return out;
  Problem p;
  p.W = W;
  p.H = H;
  p.v_bottom = H - 0.5;
  p.kfw = kfw;
  p.kfh = kfh;
  // Bands from the bottom up.
  p.bands.resize(static_cast<size_t>(n_bands));
  for (int k = 0; k < n_bands; ++k) {
    Band& b = p.bands[static_cast<size_t>(k)];
    b.r1 = fh - k * fh / n_bands;
    b.r0 = fh - (k + 1) * fh / n_bands;
    b.v = 0.5 * (b.r0 + b.r1) * kfh;
    b.v_top = b.r0 * kfh;
  }
  p.prior = given;
  p.free = !given.valid;
  if (p.free) {
    const double spacing = FreeSpacing(plant, p);
    if (spacing <= 0.0) return out;
    p.prior.spacing = spacing;
  }
  out.prior = p.prior;
  const double min_scale = p.free ? -o.free_max_scale : -o.max_scale;
  const double max_scale = p.free ? 0.5 * o.free_max_scale : o.max_scale;
  p.j_lo = static_cast<int>(std::floor(min_scale / o.scale_step));
  p.J = static_cast<int>(std::ceil(max_scale / o.scale_step)) - p.j_lo + 1;
  p.M = o.phase_steps;
  // Bins: 12 per period of the closest spacing.
  Rectify(plant, p, p.prior, 12.0 * std::exp(-min_scale));
  SubtractRunningMean(p);
  double mass_sum = 0.0;
  int usable = 0;
  for (const Band& b : p.bands) {
    if (b.has_data()) {
      mass_sum += b.mass;
      ++usable;
    }
  }
  if (usable < 2 || mass_sum <= 0.0) return out;
  p.mean_mass = mass_sum / usable;
  ComputeCombs(p);
  ForwardPass(p);
  std::vector<int> js, ms;
  Backtrack(p, js, ms);
  // Unwrapped phase (spacings) and log-spacing per band, then smoothed.
  std::vector<double> phi(static_cast<size_t>(n_bands)), sigma(static_cast<size_t>(n_bands));
  for (int k = 0; k < n_bands; ++k) {
    double ph = static_cast<double>(ms[static_cast<size_t>(k)]) / p.M;
    if (k == 0) {
      if (ph > 0.5) ph -= 1.0;
    } else {
      ph += std::round(phi[static_cast<size_t>(k - 1)] - ph);
    }
    phi[static_cast<size_t>(k)] = ph;
    sigma[static_cast<size_t>(k)] = (p.j_lo + js[static_cast<size_t>(k)]) * o.scale_step;
  }
  SmoothInV(p, phi, sigma);
  out.coherence = Coherence(p, phi, sigma);
  out.prior_coherence =
      Coherence(p, std::vector<double>(phi.size(), 0.0), std::vector<double>(phi.size(), 0.0));
  MakeKnots(p, phi, sigma, out);
  return out;
}

void CurveFitter::Rectify(const cv::Mat& plant, Problem& p, const CurvePrior& pr,
                          double bins_per_period) {
  const CurveFitOptions& o = options_;
  const int fw = plant.cols;
  const int n_bands = p.n_bands();
  p.ds = std::max(p.kfw, pr.spacing / bins_per_period);
  p.s_lo = pr.centre_u - 1.5 * p.W;
  const double s_hi = pr.centre_u + 1.5 * p.W;
  p.rw = std::max(8, static_cast<int>(std::ceil((s_hi - p.s_lo) / p.ds)));
  const int rw = p.rw;
  profiles_.assign(static_cast<size_t>(n_bands) * static_cast<size_t>(rw), 0.0F);
  for (int k = 0; k < n_bands; ++k) {
    Band& b = p.bands[static_cast<size_t>(k)];
    b.shrink = 1.0 - pr.convergence * (p.v_bottom - b.v);
    b.mass = 0.0;
    b.usable = b.shrink >= o.min_shrink && pr.spacing * b.shrink >= o.min_spacing_px;
    if (!b.usable) continue;
    float* prof = &profiles_[static_cast<size_t>(k) * static_cast<size_t>(rw)];
    for (int r = b.r0; r < b.r1; ++r) {
      const double dv = p.v_bottom - (r + 0.5) * p.kfh;
      const double shrink = 1.0 - pr.convergence * dv;
      if (shrink <= 0.0) continue;
      const double m = 1.0 / shrink;
      // bin coordinate t = (s − s_lo)/ds − 0.5 of column x's centre
      const double t0 = ((0.5 * p.kfw - pr.lean * dv) * m - p.s_lo) / p.ds - 0.5;
      const double dt = p.kfw * m / p.ds;
      const float* row = plant.ptr<float>(r);
      for (int x = 0; x < fw; ++x) {
        const float f = row[x];
        if (f <= 0.0F) continue;
        const double t = t0 + x * dt;
        if (!(t >= 0.0 && t < rw - 1.0)) continue;
        const int i = static_cast<int>(t);
        const float frac = static_cast<float>(t - i);
        prof[i] += f * (1.0F - frac);
        prof[i + 1] += f * frac;
        b.mass += static_cast<double>(f);
      }
    }
  }
}

// Parallel vertical rows; the spacing is the best comb of the lower half of
// the bands, less its half-spacing comb.
double CurveFitter::FreeSpacing(const cv::Mat& plant, Problem& p) {
  const CurveFitOptions& o = options_;
  p.prior.centre_u = 0.5 * p.W;
  p.prior.convergence = 0.0;
  p.prior.lean = 0.0;
  p.prior.spacing = o.min_free_spacing_fraction * p.W;
  Rectify(plant, p, p.prior, 1e9);  // bins of one column
  const double d_lo = std::max(o.min_free_spacing_fraction * p.W, o.min_spacing_px);
  const double d_hi = o.max_free_spacing_fraction * p.W;
  double best = 0.0, best_d = 0.0;
  for (double d = d_lo; d <= d_hi; d *= 1.03) {
    double score = 0.0;
    for (int k = 0; k < (p.n_bands() + 1) / 2; ++k) {
      const float* prof = &profiles_[static_cast<size_t>(k) * static_cast<size_t>(p.rw)];
      score += std::abs(Dft(prof, p.rw, p.s_first(), p.ds, p.prior.centre_u, d)) -
               o.half_comb_weight * std::abs(Dft(prof, p.rw, p.s_first(), p.ds, p.prior.centre_u, 2.0 * d));
    }
    if (score > best) {
      best = score;
      best_d = d;
    }
  }
  return best_d;
}

// Each band's profile less its running mean over one prior spacing: the
// mean's transfer is zero at the comb's frequency, so the comb keeps all of
// its signal while the band's broad envelope (a bed of a few wide rows on
// bare soil, light falling off) leaks none into it.
void CurveFitter::SubtractRunningMean(Problem& p) {
  const int rw = p.rw;
  const int width = std::max(1, static_cast<int>(std::lround(p.prior.spacing / p.ds)));
  std::vector<double>& cum = next_;  // reused below by the programme
  cum.assign(static_cast<size_t>(rw) + 1, 0.0);
  for (int k = 0; k < p.n_bands(); ++k) {
    if (!p.bands[static_cast<size_t>(k)].usable) continue;
    float* prof = &profiles_[static_cast<size_t>(k) * static_cast<size_t>(rw)];
    for (int x = 0; x < rw; ++x) cum[static_cast<size_t>(x) + 1] = cum[static_cast<size_t>(x)] + static_cast<double>(prof[x]);
    for (int x = 0; x < rw; ++x) {
      const int x0 = std::max(0, x - width / 2), x1 = std::min(rw, x0 + width);
      const double mean = (cum[static_cast<size_t>(x1)] - cum[static_cast<size_t>(x0)]) / (x1 - x0);
      prof[x] = static_cast<float>(static_cast<double>(prof[x]) - mean);
    }
  }
}

// The comb's DFT per band and spacing, for the unary cost.
void CurveFitter::ComputeCombs(Problem& p) const {
  const int n_bands = p.n_bands();
  const int J = p.J, M = p.M;
  p.z.assign(static_cast<size_t>(n_bands) * J, {});
  p.half.assign(static_cast<size_t>(n_bands) * J, 0.0);
  for (int k = 0; k < n_bands; ++k) {
    if (!p.bands[static_cast<size_t>(k)].has_data()) continue;
    const float* prof = &profiles_[static_cast<size_t>(k) * static_cast<size_t>(p.rw)];
    for (int j = 0; j < J; ++j) {
      const double period = p.prior.spacing * std::exp((p.j_lo + j) * options_.scale_step);
      const size_t i = static_cast<size_t>(k) * J + static_cast<size_t>(j);
      p.z[i] = Dft(prof, p.rw, p.s_first(), p.ds, p.prior.centre_u, period) / p.mean_mass;
      p.half[i] = std::abs(Dft(prof, p.rw, p.s_first(), p.ds, p.prior.centre_u, 2.0 * period)) / p.mean_mass;
    }
  }
  p.cos_m.resize(static_cast<size_t>(M));
  p.sin_m.resize(static_cast<size_t>(M));
  for (int m = 0; m < M; ++m) {
    p.cos_m[static_cast<size_t>(m)] = std::cos(kTwoPi * m / M);
    p.sin_m[static_cast<size_t>(m)] = std::sin(kTwoPi * m / M);
  }
}

// The cost of band k's central row at phase m/M of spacing j: minus the
// plant matter on the comb, less the half-spacing comb's, plus the spacing
// prior.
double CurveFitter::Unary(const Problem& p, int k, int j, int m) const {
  const CurveFitOptions& o = options_;
  const double sigma = (p.j_lo + j) * o.scale_step;
  const size_t i = static_cast<size_t>(k) * p.J + static_cast<size_t>(j);
  const double data = p.z[i].real() * p.cos_m[static_cast<size_t>(m)] +
                      p.z[i].imag() * p.sin_m[static_cast<size_t>(m)] - o.half_comb_weight * p.half[i];
  return -data + o.scale_prior * sigma * sigma;
}

// Dynamic programme, bottom band first. Transition: phase by up to
// max_phase_jump steps (circular), spacing by one step.
void CurveFitter::ForwardPass(const Problem& p) {
  const CurveFitOptions& o = options_;
  const int J = p.J, M = p.M;
  const size_t S = static_cast<size_t>(J) * static_cast<size_t>(M);
  cost_.assign(S, 0.0);
  for (int j = 0; j < J; ++j) {
    for (int m = 0; m < M; ++m) cost_[static_cast<size_t>(j) * M + m] = Unary(p, 0, j, m);
  }
  back_m_.assign(S * static_cast<size_t>(p.n_bands()), 0);
  back_j_.assign(S * static_cast<size_t>(p.n_bands()), 0);
  tmp_.assign(S, 0.0);
  next_.assign(S, 0.0);
  const int R = o.max_phase_jump;
  std::vector<double> phase_cost(static_cast<size_t>(2 * R + 1));
  for (int q = -R; q <= R; ++q) {
    const double dphi = static_cast<double>(q) / M;
    phase_cost[static_cast<size_t>(q + R)] = o.phase_smoothness * dphi * dphi;
  }
  const double scale_cost = o.scale_smoothness * o.scale_step * o.scale_step;
  for (int k = 1; k < p.n_bands(); ++k) ProgrammeStep(p, k, phase_cost, scale_cost);
}

// Band k from band k − 1: the best phase move (tmp_), then the best
// spacing move, then band k's own cost.
void CurveFitter::ProgrammeStep(const Problem& p, int k, const std::vector<double>& phase_cost,
                                double scale_cost) {
  const int J = p.J, M = p.M, R = options_.max_phase_jump;
  const size_t S = static_cast<size_t>(J) * static_cast<size_t>(M);
  int* bm = &back_m_[S * static_cast<size_t>(k)];
  int* bj = &back_j_[S * static_cast<size_t>(k)];
  for (int j = 0; j < J; ++j) {
    const double* c = &cost_[static_cast<size_t>(j) * M];
    for (int m = 0; m < M; ++m) {
      double best = std::numeric_limits<double>::infinity();
      int arg = 0;
      for (int q = -R; q <= R; ++q) {
        const int from = (m - q + M) % M;
        const double value = c[from] + phase_cost[static_cast<size_t>(q + R)];
        if (value < best) {
          best = value;
          arg = q;
        }
      }
      tmp_[static_cast<size_t>(j) * M + m] = best;
      bm[static_cast<size_t>(j) * M + m] = arg;
    }
  }
  for (int j = 0; j < J; ++j) {
    for (int m = 0; m < M; ++m) {
      double best = std::numeric_limits<double>::infinity();
      int arg = j;
      for (int jj = std::max(0, j - 1); jj <= std::min(J - 1, j + 1); ++jj) {
        const double value = tmp_[static_cast<size_t>(jj) * M + m] + (jj == j ? 0.0 : scale_cost);
        if (value < best) {
          best = value;
          arg = jj;
        }
      }
      next_[static_cast<size_t>(j) * M + m] = best + Unary(p, k, j, m);
      bj[static_cast<size_t>(j) * M + m] = arg;
    }
  }
  cost_.swap(next_);
}

// The cheapest state of the top band and the path back to the bottom: the
// spacing index js and phase index ms per band.
void CurveFitter::Backtrack(const Problem& p, std::vector<int>& js, std::vector<int>& ms) const {
  const int M = p.M, n_bands = p.n_bands();
  const size_t S = static_cast<size_t>(p.J) * static_cast<size_t>(M);
  size_t best_state = 0;
  for (size_t s = 1; s < S; ++s) {
    if (cost_[s] < cost_[best_state]) best_state = s;
  }
  js.assign(static_cast<size_t>(n_bands), 0);
  ms.assign(static_cast<size_t>(n_bands), 0);
  int j = static_cast<int>(best_state / M), m = static_cast<int>(best_state % M);
  for (int k = n_bands - 1; k >= 0; --k) {
    js[static_cast<size_t>(k)] = j;
    ms[static_cast<size_t>(k)] = m;
    if (k == 0) break;
    const size_t base = S * static_cast<size_t>(k);
    const int jj = back_j_[base + static_cast<size_t>(j) * M + m];
    const int q = back_m_[base + static_cast<size_t>(jj) * M + m];
    j = jj;
    m = (m - q + M) % M;
  }
}

// c and d smooth in v: weighted least-squares polynomials (degree
// `curve_degree`, fewer with few bands) through the programme's bands, each
// band weighted by its plant matter; bands without any carry none.
void CurveFitter::SmoothInV(const Problem& p, std::vector<double>& phi,
                            std::vector<double>& sigma) const {
  const int n_bands = p.n_bands();
  std::vector<double> wts(static_cast<size_t>(n_bands), 0.0);
  int with_data = 0;
  for (int k = 0; k < n_bands; ++k) {
    const Band& b = p.bands[static_cast<size_t>(k)];
    if (b.has_data()) {
      wts[static_cast<size_t>(k)] = b.mass / p.mean_mass;
      ++with_data;
    }
  }
  const int degree = std::min(options_.curve_degree, with_data - 1);
  if (degree < 0) return;
  const int nc = degree + 1;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(nc, nc);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nc, 2);
  Eigen::VectorXd basis(nc);
  const auto fill = [&](int k) {
    const double t = (p.v_bottom - p.bands[static_cast<size_t>(k)].v) / p.H;  // 0 at the bottom
    double power = 1.0;
    for (int q = 0; q < nc; ++q, power *= t) basis(q) = power;
  };
  for (int k = 0; k < n_bands; ++k) {
    const double wk = wts[static_cast<size_t>(k)];
    if (wk <= 0.0) continue;
    fill(k);
    a.noalias() += wk * basis * basis.transpose();
    rhs.col(0) += wk * phi[static_cast<size_t>(k)] * basis;
    rhs.col(1) += wk * sigma[static_cast<size_t>(k)] * basis;
  }
  a += 1e-9 * Eigen::MatrixXd::Identity(nc, nc);
  const Eigen::MatrixXd coef = a.ldlt().solve(rhs);
  if (!coef.allFinite()) return;
  for (int k = 0; k < n_bands; ++k) {
    fill(k);
    phi[static_cast<size_t>(k)] = basis.dot(coef.col(0));
    sigma[static_cast<size_t>(k)] = basis.dot(coef.col(1));
  }
}

// Coherence of a curve: the plant matter lined up with its comb (Σ of the
// cosine comb over the bands with data) over all of it.
double CurveFitter::Coherence(const Problem& p, const std::vector<double>& phi,
                              const std::vector<double>& sigma) const {
  double coherent = 0.0, mass_used = 0.0;
  for (int k = 0; k < p.n_bands(); ++k) {
    const Band& b = p.bands[static_cast<size_t>(k)];
    if (!b.has_data()) continue;
    const float* prof = &profiles_[static_cast<size_t>(k) * static_cast<size_t>(p.rw)];
    const double period = p.prior.spacing * std::exp(sigma[static_cast<size_t>(k)]);
    const std::complex<double> zk = Dft(prof, p.rw, p.s_first(), p.ds, p.prior.centre_u, period);
    const double a = kTwoPi * phi[static_cast<size_t>(k)];
    coherent += zk.real() * std::cos(a) + zk.imag() * std::sin(a);
    mass_used += b.mass;
  }
  return mass_used > 0.0 ? coherent / mass_used : 0.0;
}

// A knot per band (image pixels), up to where the prior's rows vanish; the
// top of the rows is the highest band with plant matter.
void CurveFitter::MakeKnots(const Problem& p, const std::vector<double>& phi,
                            const std::vector<double>& sigma, CurveFit& out) const {
  const CurvePrior& prior = p.prior;
  out.top_v_px = p.v_bottom;
  out.knots.reserve(p.bands.size());
  for (int k = 0; k < p.n_bands(); ++k) {
    const Band& b = p.bands[static_cast<size_t>(k)];
    const double dv = p.v_bottom - b.v;
    const double shrink = 1.0 - prior.convergence * dv;
    const double period = prior.spacing * std::exp(sigma[static_cast<size_t>(k)]);
    const double c_s = prior.centre_u + phi[static_cast<size_t>(k)] * period;
    CurveKnot knot;
    knot.v_px = b.v;
    knot.centre_u_px = c_s * shrink + prior.lean * dv;
    knot.spacing_px = period * shrink;
    knot.weight = b.usable ? b.mass / p.mean_mass : 0.0;
    if (shrink <= 0.0) break;
    out.knots.push_back(knot);
    if (b.usable && b.mass >= 0.15 * p.mean_mass) out.top_v_px = std::min(out.top_v_px, b.v_top);
  }
}

}  // namespace plantscale::rows
