#pragma once
// The straight, one-vanishing-point row model of row_detector.h searched on
// one image, as the steps that header lists: the Hough over (g, lean) with
// the streaks' candidates (1), the row comb on each candidate (2), the local
// search (3), the least-squares refit against the streaks' own vanishing
// point (4) and the central row, top and confidence (5). The image's bands,
// their running sums and the s histogram are shared by every step; the
// buffers are kept from image to image. Internal to engine/rows: RowDetector
// owns one. Steps 1–3 are in straight_search.cc, 4–5 in
// straight_search_fit.cc.

#include <complex>
#include <opencv2/core.hpp>
#include <vector>

#include "engine/rows/orientation.h"
#include "engine/rows/row_detector.h"

namespace plantscale::rows {

class StraightSearch {
 public:
  explicit StraightSearch(const RowDetectorOptions& options) : o_(options) {}

  // `plant`: CV_8UC1 (plant matter > 0) or CV_32FC1 in [0, 1], non-empty.
  RowDetection Detect(const cv::Mat& plant);
  // The last image's plant fraction at the refit resolution (empty before
  // the first image with plant matter): the curve fit's input.
  const cv::Mat& fit_image() const { return fit_; }

 private:
  struct Geometry {
    double g = 0.0;  // convergence, 1/px
    double c = 0.0;  // lean
  };
  struct Band {
    double dv = 0.0;     // Δv of the band's centre, px
    double v_top = 0.0;  // the band's top edge, px
    int rows = 0;        // work rows in the band
  };
  // Rows of one comb that have plant matter along their length.
  struct Rows {
    std::vector<DetectedRow> rows;
    double top_v = 0.0;
    bool adjacent = false;  // two neighbouring teeth both kept
    // 1 − (plant matter half-way between kept rows) / (on them): a comb of
    // twice the spacing has a row half-way between its teeth.
    double contrast = 0.0;
  };
  // Per tooth of a comb, over the bands: where it is in the image, where it
  // holds plant matter, and the matter on it and half-way to the next.
  struct Tallies {
    std::vector<int> in_image, occupied, highest;
    std::vector<double> on_sum, between_sum;
    std::vector<int> on_count, between_count;
  };
  // The comb on the bands one by one: z_k = Σ w e^{−2πi s/d} over band k.
  struct BandComb {
    double coherence = 0.0, alignment = 0.0, phase = 0.0;
    double score() const { return coherence * alignment; }
  };
  struct Hypothesis {
    double g = 0.0, lean = 0.0, d = 0.0, sc = 0.0, score = -1.0;
  };
  struct Fit {
    Geometry geo;
    double d = 0.0, sc = 0.0;
    Rows found;
  };

  static std::vector<Band> SplitIntoBands(const cv::Mat& image, int n_bands, double scale,
                                          double v_bottom, std::vector<float>& profiles);

  // Plant fraction images, bands, their running sums; false (with the
  // reason in `out`) when there is too little plant matter.
  bool Prepare(const cv::Mat& plant, RowDetection& out);
  Geometry GeometryAt(double g, double lean_at_centre) const;
  Geometry CellGeometry(int index) const;
  void BuildHistogram(const Geometry& geo, double max_dv);

  Rows FindRows(const Geometry& geo, double d, double sc) const;
  int FirstContrastBand(const Geometry& geo, double d, double sc, int n_lo, size_t n_rows) const;
  Tallies TallyBands(const Geometry& geo, double d, double sc, int n_lo, size_t n_rows,
                     int k_first) const;
  Rows SelectRows(const Tallies& t, const Geometry& geo, double d, double sc, int n_lo) const;

  // Step 1.
  std::vector<double> HoughSharpness();
  std::vector<int> DistinctCells(const std::vector<int>& order, int count) const;
  void AddStreakCandidates(const std::vector<int>& order, std::vector<int>& chosen);
  void LockStreaks(int best_support_index);
  void AddLeanPeaks(const std::vector<double>& sharpness, std::vector<int>& chosen) const;
  double StreakFactor(const Geometry& geo) const;

  // Step 2.
  BandComb CombOnBands(const Geometry& geo, double d) const;
  bool ScoreOf(const Geometry& geo, double period, double floor, Hypothesis& hyp,
               size_t& n_rows) const;
  std::vector<Hypothesis> CombHypotheses(const std::vector<int>& chosen);

  // Step 3.
  Hypothesis Refine(const Hypothesis& start) const;
  Hypothesis BestRefined(std::vector<Hypothesis> by_count) const;

  // Step 4.
  void Refit(Fit& fit, bool fix_vp) const;
  bool RefitStep(Fit& fit, bool fix_vp) const;
  double FitScore(const Fit& fit) const;
  Fit BestFit(const Fit& searched);

  // Step 5.
  double TopOfRows(const Geometry& geo, double d, double sc, const Rows& found) const;
  void Finish(Fit fit, RowDetection& out);

  RowDetectorOptions o_;
  // The image, at its own size, and at the Hough resolution.
  double W_ = 0.0, H_ = 0.0, v_bottom_ = 0.0;
  int w_ = 0, h_ = 0;
  double kw_ = 1.0, kh_ = 1.0;
  int n_bands_ = 0;
  std::vector<Band> bands_;
  double total_mass_ = 0.0;
  // The s histogram: 3w bins over [−W, 2W), bin 0 centred at s0_.
  int n_bins_ = 0;
  double s0_ = 0.0;
  double d_min_ = 0.0, d_max_ = 0.0, min_spacing_ = 0.0;
  // The Hough grid: ng × nl cells of (g, lean).
  int ng_ = 0, nl_ = 0;
  double g_step_ = 0.0, l_step_ = 0.0;
  // The streaks (orientation.h): their best support and best geometry.
  bool use_orientation_ = false;
  double support_max_ = 0.0;
  bool locked_ = false;
  double lock_g_ = 0.0, lock_lean_ = 0.0;
  // The refit resolution's bands.
  int fit_bands_ = 0;
  std::vector<Band> fbands_;

  cv::Mat work_;  // CV_32F plant fraction at the Hough resolution
  cv::Mat fit_;   // CV_32F at the refit resolution
  std::vector<float> profiles_;
  std::vector<double> cumulative_;  // running sums of profiles_, w + 1 per band
  std::vector<float> fit_profiles_;
  std::vector<double> histogram_;
  OrientationField orientation_;
};

}  // namespace plantscale::rows
