#pragma once
// Centring of found crop rows on the plant matter itself (issue 34). The
// comb fits (the straight model and the curve of row_detector.h) tie every
// row to one spacing rule, u_n(v) = c(v) + n·d(v): they find the rows and
// their spacing, but a row whose plants sit a little off that rule (a
// sowing drill's rows are not exactly even, a bed's rows lean differently
// in a photograph from a tilted camera) is placed where the rule says, not
// where its plants are. This step moves each found row onto its plants:
//
//  1. In horizontal bands of the plant image, each row's centre is the
//     mean shift of the band's column profile: the centroid of the plant
//     matter within ± h·d of the current estimate (d the local spacing),
//     started at the comb's u_n(v) and iterated, never further than
//     `max_shift` spacings from it. The band's background (its profile's
//     median, weeds and soil) is subtracted first so that it does not pull
//     the centroid to the window's middle.
//  2. The centres, in units of the local spacing relative to the comb,
//     e_{n,k} = (x_{n,k} − u_n(v_k)) / d(v_k), are fitted as
//
//       e_n(t) = A(t) + n·B(t) + R_n(t),   t = (v_bottom − v) / H,
//
//     A and B polynomials shared by all rows (B of low degree) (a correction of c(v) and
//     d(v): the comb's even spacing kept as the prior), R_n a polynomial
//     per row penalised by `row_ridge` × its squared coefficients (a row
//     leaves the even spacing only where its own plants say so), weighted
//     by each band's plant matter, with a Tukey reweighting of outliers.
//
// The refined rows are u_n(v) + d(v)·e_n(t), t held in the fitted range
// beyond it (R_n in its own row's range: a row entering from the image's
// side is not extrapolated along a cubic); rows without enough bands of
// their own keep A + n·B.

#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "engine/common/options.h"

namespace plantscale::rows {

struct CentreRefineOptions {
  bool enabled = true;
  int bands = 48;                  // horizontal bands over the rows' visible height
  double window_fraction = 0.15;   // h: mean-shift half-window, of the local spacing
  int iterations = 4;              // mean-shift steps per band
  double max_shift = 0.35;         // no centre further than this × spacing from the comb
  int degree = 3;                  // of A and R_n in t
  int spacing_degree = 1;          // of B (n·B: far rows would amplify a wiggle)
  double row_ridge = 0.3;          // penalty on R_n's coefficients (in bands of full weight)
  double shared_ridge = 0.1;       // ... on A's and B's
  double min_band_matter = 0.25;   // a band's centre counts when its matter is this × the mean
  int min_row_bands = 3;           // bands a row needs for its own R_n
  double outlier_scale = 0.3;      // Tukey's c, in spacings
  int robust_iterations = 3;

  OptionErrors Validate() const;
};

// The correction of one detection: e_n(t) = A(t) + n·B(t) + R_n(t).
struct CentreRefinement {
  std::vector<double> shared_a, shared_b;  // A and B's coefficients (t^0 first)
  std::vector<int> rows;                   // the rows n with their own R_n
  std::vector<std::vector<double>> row_r;  // R_n's coefficients, in the order of `rows`
  std::vector<std::pair<double, double>> row_s;  // each R_n's range of s = t / t_max
  double v_bottom = 0.0, height = 1.0;     // t = (v_bottom − v) / height
  double t_max = 1.0;                      // t held in [0, t_max]
  bool empty() const { return shared_a.empty(); }
  // e_n at image row v, in spacings.
  double Offset(int n, double v_px) const;
};

// One centre observation: row n at image row v, its offset from the comb
// in spacings, and its weight.
struct CentreObservation {
  int n = 0;
  double v_px = 0.0, offset = 0.0, weight = 0.0;
};

struct RowDetection;

// Mean-shift centre observations of `det`'s rows on `plant` (CV_32F plant
// fraction, the image scaled by kfw, kfh image pixels per column and row).
std::vector<CentreObservation> ObserveCentres(const cv::Mat& plant, double kfw, double kfh,
                                              const RowDetection& det, const CentreRefineOptions& o);
// The fit of step 2 to the observations; empty when there are none.
CentreRefinement FitCentres(const std::vector<CentreObservation>& obs, const RowDetection& det,
                            const CentreRefineOptions& o);

}  // namespace plantscale::rows
