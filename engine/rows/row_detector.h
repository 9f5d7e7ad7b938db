#pragma once
// Crop-row detection in an image from an unknown, uncalibrated camera
// (issue 11). Crop rows are parallel, equally spaced lines on the ground; a
// pinhole camera maps them to lines through one vanishing point whose
// slopes are affine in the row number. Written with the image's bottom
// pixel row as reference (Δv = v_bottom − v, pixel centres at +0.5):
//
//   u_n(v) = (s_c + n·d) · (1 − g·Δv) + c·Δv
//
// s_c: the central row's u at the bottom row, d: the row spacing at the
// bottom row, g: the convergence (the vanishing point lies 1/g above the
// bottom row; g = 0: parallel rows, seen from straight above), c: the lean
// (the vanishing point's u is c/g). Every pixel maps to
//
//   s = (u − c·Δv) / (1 − g·Δv),
//
// the bottom-row crossing of the line through it and the vanishing point;
// in s the rows are a comb of period d. The detector therefore votes with
// all rows at once (the perspective constraint ties them together, as the
// tracker's initialiser does on the calibrated ground plane):
//   1. a Hough over (g, lean) scoring how sharply the plant matter piles up
//      in s (all rows must converge on one point); the sharpest cells and
//      the sharpest leans of every convergence go on, and so do
//      the geometries whose lines the plant matter's streaks follow best
//      (orientation.h) go on as well, and every score below is scaled by
//      that agreement relative to the best, so that a comb leaning through
//      one big near-field plant does not beat the geometry every narrow
//      row and gap farther up points along,
//   2. the row comb (comb.h, whose votes the ground-plane initialiser
//      shares) over period and phase, each hypothesis scored by the comb's
//      coherence × the agreement of its phase from band to band × the
//      occupancy of its rows × their contrast against the matter half-way
//      between them (which rules out a comb of twice the spacing) × n/(n+1)
//      for n rows (two rows fit any vanishing point; more rows test it);
//      the coherence is taken over all the image's plant matter, so that a
//      geometry that cannot use the upper bands (a low vanishing point, a
//      narrow comb) is not rewarded for explaining less of the image, and
//      occupancy and contrast leave out the bands at the top where the
//      rows have merged into one canopy (teeth no denser than the gaps),
//      as a geometry that cannot use those bands leaves them out,
//   3. a local search of that score from the best hypothesis of each of
//      the best row counts (a comb of twice the spacing through two full
//      rows must not win against the true comb before the latter's period
//      is refined), and a weighted least-squares refit of
//      the four parameters (linear in (s_c, d, c − g·s_c, g·d)) to each
//      row's centre in thin bands, the centroid of its plant matter between
//      the gaps on either side: narrow rows are centred by their mass, rows
//      whose plants nearly touch by their edges; the same refit of (s_c, d)
//      alone on the streaks' best vanishing point competes with it, by the
//      same score (leafy rows merging into a canopy pull the full refit's
//      vanishing point away; the streaks still point true).
// Weeds between rows add a floor to the comb; missing plants, shadows and
// tyre tracks take parts of teeth away; rows are reported only where their
// tooth has plant matter along its length (or, between two such rows, some).
// No rows (confidence 0) when the band agreement, contrast or coherence is
// too low: bare soil, sky, walls, scattered plants.

#include <Eigen/Core>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "engine/common/options.h"
#include "engine/rows/centre_refine.h"
#include "engine/rows/curve_fit.h"

namespace plantscale::rows {

struct RowDetectorOptions {
  int work_width_px = 128;           // the mask is area-averaged to this width for the Hough
  int fit_width_px = 320;            // ... and to this width for the least-squares refit
  int strips = 16;                   // horizontal bands of the Hough
  double max_convergence = 1.5;      // g × image height: vanishing point no lower than this
  int convergence_steps = 13;
  double max_lean = 1.2;             // |du/dv| of the rows at the image's centre column
  int lean_steps = 25;
  double min_spacing_fraction = 0.05;  // spacing at the bottom row, of the image width
  double max_spacing_fraction = 1.0;
  double spacing_step = 0.025;       // relative step of the period search
  int candidates = 4;                // best Hough cells taken on to the comb
  int refined_hypotheses = 3;        // best hypotheses of distinct row counts refined
  int refine_row_checks = 6;         // neighbours per refinement step whose rows are checked
  double prune_fraction = 0.3;       // combs below this × the best score so far are not refined
  double row_halfwidth_fraction = 0.25;  // plant matter within ± this × spacing supports a row
  double min_plant_fraction = 0.002; // less plant matter in the image: no rows
  double min_coherence = 0.15;       // comb phase coherence below this: no rows
  double min_alignment = 0.85;       // agreement of the bands' comb phases below this: no rows
  // ... unless the streaks confirm the geometry: rows that converge sharply
  // (a camera looking far along the bed) leave few rows per band in the
  // near field and their band phases agree less, while their streaks all
  // point at the vanishing point; scattered plants have no such streaks
  // (support ≤ 0.045 in RowDetectorTest.ScatteredBlobsAreNotRows).
  double min_streak_alignment = 0.6;  // band agreement required when the streaks confirm
  double min_streak_support = 0.06;   // streak support (orientation.h) that confirms
  double min_contrast = 0.2;         // 1 − (matter half-way between rows) / (on them)
  double gap_search_fraction = 0.25;  // the refit looks for the gap between two rows within
                                      // ± this × spacing of their midpoint
  int fit_iterations = 6;
  double min_row_occupancy = 0.4;    // fraction of its bands in which a row has plant matter
  double min_gap_row_occupancy = 0.15;  // ... for a row between two such rows (plants missing)
  double min_visible_spacing_px = 6.0;  // rows are reported up to where they are this close
  // The streaks' vote (orientation.h): every hypothesis's score is scaled by
  // (E + floor) / (E_max + floor), E its support beyond chance and E_max the
  // best support over the Hough grid; the floor keeps images without
  // streaks (seen from above, scattered plants) as they were. 0 disables.
  double orientation_floor = 0.02;
  int orientation_candidates = 2;  // best-supported Hough cells also taken on to the comb
  // Rows as curves (curve_fit.h, issue 34), with the straight model above as
  // their prior; when it found no rows (or none at all), the curve decides.
  bool curves = true;
  CurveFitOptions curve;
  double min_curve_coherence = 0.4;  // the curve's comb coherence below this: no rows
  // Where the straight model found rows, the curve is taken when its
  // coherence beats the straight rows' by this much plus this × the
  // straight model's confidence (a confident straight fit, as on wide rows
  // of a narrow bed, is not given up for a few hundredths).
  double min_curve_gain = 0.02;
  double curve_gain_per_confidence = 0.1;
  // The free prior (parallel rows, spacing searched) as well as the straight
  // model's: 0 only where the straight model found no rows, 1 instead of it,
  // 2 both, the more coherent curve wins.
  int curve_free_prior = 0;
  // Each found row centred on its own plant matter (centre_refine.h).
  CentreRefineOptions centring;

  OptionErrors Validate() const;
};

struct DetectedRow {
  int n = 0;               // comb index relative to the central row (0)
  double bottom_u_px = 0;  // u at the bottom pixel row's centre
  double occupancy = 0.0;  // fraction of its in-image bands with plant matter
};

struct RowDetection {
  int width_px = 0;
  int height_px = 0;
  double confidence = 0.0;     // 0: no rows; else comb coherence × mean row occupancy (≥ 0.001)
  std::string reason;          // why no rows, when confidence is 0
  double centre_u_px = 0.0;    // s_c
  double spacing_px = 0.0;     // d, at the bottom row
  double convergence = 0.0;    // g, 1/px
  double lean = 0.0;           // c
  double coherence = 0.0;      // |Σ w e^{2πi s/d}| / Σ w of the plant matter
  double alignment = 0.0;      // |Σ z_k| / Σ |z_k| of the bands' comb phasors z_k
  double contrast = 0.0;       // 1 − (matter half-way between the rows) / (on the rows)
  double streak_support = 0.0; // the streaks' agreement with the rows' lines beyond chance (orientation.h)
  double top_v_px = 0.0;       // rows are told apart from the bottom up to this v
  std::vector<DetectedRow> rows;  // left to right
  // The rows as curves (bottom to top): c(v) and d(v) at each band's centre,
  // interpolated linearly between them and continued beyond the end knots.
  // Empty: the straight model above.
  std::vector<CurveKnot> curve;
  double curve_coherence = 0.0;
  bool curve_prior_straight = false;  // the curve's prior was the straight model above
  // Each row's centring on its plant matter (centre_refine.h), in local
  // spacings from the comb above; empty: the comb's rows as they are.
  CentreRefinement centring;

  double bottom_v_px() const { return height_px - 0.5; }
  // u of row n at image height v (continuous; v = row index + 0.5);
  // beyond the image sides too: the comb's, moved by the centring.
  double U(int n, double v_px) const;
  // u of comb row n (the straight model or the curve, without the centring).
  double CombU(int n, double v_px) const;
  // The central row's u at image height v.
  double CentreAt(double v_px) const;
  // The comb's row spacing at image height v.
  double SpacingAt(double v_px) const;
  // (u, v) of the straight model's vanishing point; nullopt when the rows are parallel.
  std::optional<Eigen::Vector2d> VanishingPoint() const;
  // The central row's offset from the image's centre column at the bottom.
  double CentralOffsetPx() const { return centre_u_px - 0.5 * width_px; }
};

class StraightSearch;

class RowDetector {
 public:
  explicit RowDetector(const RowDetectorOptions& options);
  ~RowDetector();
  RowDetector(RowDetector&&) noexcept;
  RowDetector& operator=(RowDetector&&) noexcept;

  // `plant` is CV_8UC1, plant matter > 0 (a segmentation mask, 255 plant)
  // or CV_32FC1 in [0, 1]. Throws DataError for an empty image or another type.
  RowDetection Detect(const cv::Mat& plant);
  const RowDetectorOptions& options() const { return options_; }

 private:
  // The comb: the straight model, or the curve where it does better.
  RowDetection DetectComb(const cv::Mat& plant);
  // `det`'s rows centred on the plant matter of the fit image.
  void Centre(RowDetection& det) const;
  // The curve fit on the plant image at the refit resolution, with the
  // straight detection `det` as its prior (or the free prior).
  CurveFit FitCurve(const cv::Mat& fit, const RowDetection& det, CurvePrior& prior);
  // `curved`'s rows, contrast and confidence; `det` (with the reason) where
  // the curve has too few rows or too little contrast.
  RowDetection AcceptCurve(RowDetection det, RowDetection curved, const CurveFit& fit) const;
  // The rows of `det`'s curve with plant matter along them (as the
  // straight model keeps rows), with their occupancy.
  // `contrast`: 1 − (plant matter half-way between the rows) / (on them).
  std::vector<DetectedRow> CurveRows(const RowDetection& det, double& contrast) const;

  RowDetectorOptions options_;
  CurveFitter curve_fitter_;
  std::unique_ptr<StraightSearch> straight_;  // the straight model (straight_search.h)
};

}  // namespace plantscale::rows
