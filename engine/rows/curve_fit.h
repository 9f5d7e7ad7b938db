#pragma once
// Crop rows as curves (issue 34). The rows of a bed stay evenly spaced
// across each image row even where they bend:
//
//   u_n(v) = c(v) + n·d(v),   c and d smooth in v.
//
// The straight, one-vanishing-point model of row_detector.h is the prior:
// the image is rectified with it (every image row mapped to s, the bottom
// row's coordinate, in which the prior's rows are vertical and d apart), so
// that only what the prior does not explain is left to the curve. In
// horizontal bands of the rectified plant image each band's profile is
// matched with a cosine comb by one DFT coefficient per candidate spacing:
//
//   Z_k(σ) = Σ_s P_k(s) · exp(2πi (s − s_c) / (d·e^σ)),
//
// whose phase places the central row at φ = arg Z / 2π spacings from s_c and
// whose magnitude is the plant matter lined up with the comb (weeds and
// bare patches between rows add nothing to it); the comb at twice the
// spacing, |Z_k(σ + ln 2)|, is subtracted so that a comb at half the rows'
// spacing (a tooth on every gap) does not win. A dynamic programme over the
// bands, bottom to top, picks the (σ_k, φ_k) of every band at once: the
// bands' comb scores against a smoothness prior on the change of phase
// (circular: a row index may slip, the curve does not jump) and of spacing
// from band to band, and on the spacing's departure from the prior. Bands
// without plant matter carry the curve on. The result is a knot per band
// (v, c, d) in image pixels; RowDetection::U interpolates them.
//
// Without a straight prior (no vanishing point found) the prior is parallel
// vertical rows whose spacing is the best comb of the lower bands, and the
// spacing may then range further.

#include <complex>
#include <opencv2/core.hpp>
#include <vector>

#include "engine/common/options.h"

namespace plantscale::rows {

struct CurveKnot {
  double v_px = 0.0;        // image height of the band's centre
  double centre_u_px = 0.0; // c(v): the central row
  double spacing_px = 0.0;  // d(v)
  double weight = 0.0;      // the band's comb score (0: carried on from its neighbours)
};

struct CurveFitOptions {
  int bands = 24;                 // horizontal bands of the DP
  int phase_steps = 48;           // phase states per spacing
  double scale_step = 0.04;       // log-spacing step
  double max_scale = 0.12;        // |ln(d_band / d_prior)| with a straight prior
  double free_max_scale = 1.0;    // ... without one
  int max_phase_jump = 4;         // phase steps per band
  double phase_smoothness = 25.0; // cost per (Δφ)² (φ in spacings) between bands
  double scale_smoothness = 8.0;  // cost per (Δσ)² between bands
  double scale_prior = 1.0;       // cost per σ² in each band
  double half_comb_weight = 0.5;  // weight of the half-spacing comb's magnitude
  int curve_degree = 2;           // c and d: polynomials of this degree in v through the bands
  double min_shrink = 0.12;       // rectified rows compressed below this are not used
  double min_spacing_px = 6.0;    // bands where the rows are closer are not used
  double min_free_spacing_fraction = 0.05;  // of the width, for the free prior's spacing
  double max_free_spacing_fraction = 0.6;

  OptionErrors Validate() const;
};

struct CurvePrior {
  bool valid = false;     // false: parallel vertical rows, spacing searched
  double centre_u = 0.0;  // s_c at the bottom row
  double spacing = 0.0;   // d at the bottom row
  double convergence = 0.0;
  double lean = 0.0;
};

struct CurveFit {
  std::vector<CurveKnot> knots;  // bottom to top
  double coherence = 0.0;        // Σ comb score / Σ plant matter of the bands with data
  double prior_coherence = 0.0;  // the same of the prior's straight rows
  double top_v_px = 0.0;         // highest image v whose band had plant matter and usable spacing
  CurvePrior prior;              // the prior used (the free one when none was given)
};

class CurveFitter {
 public:
  explicit CurveFitter(const CurveFitOptions& options);
  // `plant`: CV_32F plant fraction, `scale` image pixels per column and row
  // of it, image `width` × `height`. Empty knots when nothing to fit.
  CurveFit Fit(const cv::Mat& plant, double scale_u, double scale_v, double width, double height,
               const CurvePrior& prior);
  const CurveFitOptions& options() const { return options_; }

 private:
  struct Band {
    int r0 = 0, r1 = 0;   // rows [r0, r1) of the plant image
    double v = 0.0;       // image v of the centre
    double v_top = 0.0;   // image v of the top edge
    double shrink = 1.0;  // 1 − g·Δv at the centre
    double mass = 0.0;    // plant matter in the band's rectified profile
    bool usable = false;
    bool has_data() const { return usable && mass > 0.0; }
  };
  // One fit's state: the image, its bands, the prior, the rectified
  // profiles' bins and the programme's grid of spacings × phases.
  struct Problem {
    double W = 0.0, H = 0.0, v_bottom = 0.0, kfw = 1.0, kfh = 1.0;
    std::vector<Band> bands;
    CurvePrior prior;
    bool free = false;
    double s_lo = 0.0, ds = 1.0;  // profile bins from s_lo, ds wide
    int rw = 0;                   // bins per band
    double mean_mass = 0.0;       // plant matter per band with data
    int j_lo = 0, J = 0, M = 0;   // spacings e^{(j_lo + j)·scale_step}, j < J; M phases
    std::vector<std::complex<double>> z;  // the comb's DFT per (band, spacing) / mean_mass
    std::vector<double> half;             // |the half-spacing comb's DFT| / mean_mass
    std::vector<double> cos_m, sin_m;     // of the M phases
    double s_first() const { return s_lo + 0.5 * ds; }
    int n_bands() const { return static_cast<int>(bands.size()); }
  };

  // Each band's profile in s, the prior's rows made vertical.
  void Rectify(const cv::Mat& plant, Problem& p, const CurvePrior& pr, double bins_per_period);
  // The free prior's spacing (0: none found).
  double FreeSpacing(const cv::Mat& plant, Problem& p);
  void SubtractRunningMean(Problem& p);
  void ComputeCombs(Problem& p) const;
  double Unary(const Problem& p, int k, int j, int m) const;
  // The programme's forward pass (cost_, back_m_, back_j_) and its best path.
  void ForwardPass(const Problem& p);
  void ProgrammeStep(const Problem& p, int k, const std::vector<double>& phase_cost,
                     double scale_cost);
  void Backtrack(const Problem& p, std::vector<int>& js, std::vector<int>& ms) const;
  void SmoothInV(const Problem& p, std::vector<double>& phi, std::vector<double>& sigma) const;
  double Coherence(const Problem& p, const std::vector<double>& phi,
                   const std::vector<double>& sigma) const;
  void MakeKnots(const Problem& p, const std::vector<double>& phi,
                 const std::vector<double>& sigma, CurveFit& out) const;

  CurveFitOptions options_;
  std::vector<float> profiles_;
  std::vector<double> cost_, next_, tmp_;
  std::vector<int> back_m_, back_j_;
};

}  // namespace plantscale::rows
