#include "engine/rows/row_detector.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "engine/rows/straight_search.h"

namespace plantscale::rows {

OptionErrors RowDetectorOptions::Validate() const {
  OptionErrors e;
  if (work_width_px < 16) e.push_back({"work_width_px", "must be >= 16"});
  if (fit_width_px < 16) e.push_back({"fit_width_px", "must be >= 16"});
  if (strips < 4) e.push_back({"strips", "must be >= 4"});
  RequireInRange(e, "max_convergence", max_convergence, 0.0, 3.0);
  if (convergence_steps < 2) e.push_back({"convergence_steps", "must be >= 2"});
  RequireInRange(e, "max_lean", max_lean, 0.0, 5.0);
  if (lean_steps < 1) e.push_back({"lean_steps", "must be >= 1"});
  RequireInRange(e, "min_spacing_fraction", min_spacing_fraction, 0.0, 1.0, false);
  if (!(max_spacing_fraction > min_spacing_fraction)) {
    e.push_back({"max_spacing_fraction", "must be > min_spacing_fraction"});
  }
  RequireInRange(e, "spacing_step", spacing_step, 0.0, 0.5, false);
  if (candidates < 1) e.push_back({"candidates", "must be >= 1"});
  if (refined_hypotheses < 1) e.push_back({"refined_hypotheses", "must be >= 1"});
  if (refine_row_checks < 1) e.push_back({"refine_row_checks", "must be >= 1"});
  RequireInRange(e, "prune_fraction", prune_fraction, 0.0, 1.0);
  RequireInRange(e, "row_halfwidth_fraction", row_halfwidth_fraction, 0.0, 0.5, false);
  RequireInRange(e, "min_plant_fraction", min_plant_fraction, 0.0, 1.0);
  RequireInRange(e, "min_coherence", min_coherence, 0.0, 1.0);
  RequireInRange(e, "min_alignment", min_alignment, 0.0, 1.0);
  RequireInRange(e, "min_streak_alignment", min_streak_alignment, 0.0, 1.0);
  RequireInRange(e, "min_streak_support", min_streak_support, 0.0, 1.0);
  RequireInRange(e, "min_contrast", min_contrast, 0.0, 1.0);
  RequireInRange(e, "gap_search_fraction", gap_search_fraction, 0.0, 0.5, false);
  if (fit_iterations < 0) e.push_back({"fit_iterations", "must be >= 0"});
  RequireInRange(e, "min_row_occupancy", min_row_occupancy, 0.0, 1.0);
  RequireInRange(e, "min_gap_row_occupancy", min_gap_row_occupancy, 0.0, 1.0);
  RequirePositive(e, "min_visible_spacing_px", min_visible_spacing_px);
  RequireInRange(e, "orientation_floor", orientation_floor, 0.0, 1.0);
  if (orientation_candidates < 0) e.push_back({"orientation_candidates", "must be >= 0"});
  for (const OptionError& c : curve.Validate()) e.push_back({"curve." + c.key, c.reason});
  for (const OptionError& c : centring.Validate()) e.push_back({"centring." + c.key, c.reason});
  RequireInRange(e, "min_curve_coherence", min_curve_coherence, 0.0, 1.0);
  RequireInRange(e, "min_curve_gain", min_curve_gain, -1.0, 1.0);
  RequireInRange(e, "curve_gain_per_confidence", curve_gain_per_confidence, 0.0, 10.0);
  return e;
}

namespace {

// c(v) and d(v) of a curve: linear between knots (bottom to top, v
// decreasing), continued along the end segments.
std::pair<double, double> CurveAt(const std::vector<CurveKnot>& knots, double v) {
  size_t i = 0;
  while (i + 2 < knots.size() && v < knots[i + 1].v_px) ++i;
  const CurveKnot& a = knots[i];
  const CurveKnot& b = knots[i + 1];
  const double t = (v - a.v_px) / (b.v_px - a.v_px);
  return {a.centre_u_px + t * (b.centre_u_px - a.centre_u_px),
          a.spacing_px + t * (b.spacing_px - a.spacing_px)};
}

}  // namespace

double RowDetection::U(int n, double v_px) const {
  const double u = CombU(n, v_px);
  if (centring.empty()) return u;
  return u + SpacingAt(v_px) * centring.Offset(n, v_px);
}

double RowDetection::CombU(int n, double v_px) const {
  if (curve.size() >= 2) {
    const auto [c, d] = CurveAt(curve, v_px);
    return c + n * d;
  }
  const double dv = bottom_v_px() - v_px;
  return (centre_u_px + n * spacing_px) * (1.0 - convergence * dv) + lean * dv;
}

double RowDetection::CentreAt(double v_px) const { return U(0, v_px); }

double RowDetection::SpacingAt(double v_px) const {
  if (curve.size() >= 2) return CurveAt(curve, v_px).second;
  return spacing_px * (1.0 - convergence * (bottom_v_px() - v_px));
}

std::optional<Eigen::Vector2d> RowDetection::VanishingPoint() const {
  if (convergence * height_px < 1e-3) return std::nullopt;
  return Eigen::Vector2d(lean / convergence, bottom_v_px() - 1.0 / convergence);
}

RowDetector::RowDetector(const RowDetectorOptions& options)
    : options_((ThrowIfInvalid("row detector", options.Validate()), options)),
      curve_fitter_(options.curve),
      straight_(std::make_unique<StraightSearch>(options)) {}

RowDetector::~RowDetector() = default;
RowDetector::RowDetector(RowDetector&&) noexcept = default;
RowDetector& RowDetector::operator=(RowDetector&&) noexcept = default;

RowDetection RowDetector::Detect(const cv::Mat& plant) {
  RowDetection det = DetectComb(plant);
  if (options_.centring.enabled && det.confidence > 0.0 && !det.rows.empty()) Centre(det);
  return det;
}

void RowDetector::Centre(RowDetection& det) const {
  const cv::Mat& fit = straight_->fit_image();
  if (fit.empty()) return;
  const double kfw = static_cast<double>(det.width_px) / fit.cols;
  const double kfh = static_cast<double>(det.height_px) / fit.rows;
  const std::vector<CentreObservation> obs = ObserveCentres(fit, kfw, kfh, det, options_.centring);
  det.centring = FitCentres(obs, det, options_.centring);
  for (DetectedRow& row : det.rows) row.bottom_u_px = det.U(row.n, det.bottom_v_px());
}

RowDetection RowDetector::DetectComb(const cv::Mat& plant) {
  if (plant.empty()) throw DataError("row detector: empty image");
  if (plant.type() != CV_8UC1 && plant.type() != CV_32FC1) {
    throw DataError("row detector: plant image must be CV_8UC1 or CV_32FC1");
  }
  RowDetection det = straight_->Detect(plant);
  const cv::Mat& fit_image = straight_->fit_image();
  if (!options_.curves || fit_image.empty() || det.reason.rfind("no plant matter", 0) == 0) return det;
  CurvePrior prior;
  const CurveFit fit = FitCurve(fit_image, det, prior);
  if (fit.knots.size() < 2) return det;
  // Where the straight model found rows, the curve replaces it only when it
  // lines up clearly more plant matter than the straight rows do.
  if (det.confidence > 0.0 && fit.prior.valid &&
      fit.coherence < fit.prior_coherence + options_.min_curve_gain +
                          options_.curve_gain_per_confidence * det.confidence) {
    det.curve_coherence = fit.coherence;
    return det;
  }
  RowDetection curved = det;
  curved.curve = fit.knots;
  curved.curve_coherence = fit.coherence;
  curved.curve_prior_straight = fit.prior.valid && prior.valid;
  if (!curved.curve_prior_straight) {
    curved.centre_u_px = fit.prior.centre_u;
    curved.spacing_px = fit.prior.spacing;
    curved.convergence = 0.0;
    curved.lean = 0.0;
  }
  // The central row: nearest the image's centre at the bottom.
  const double W = plant.cols, H = plant.rows;
  const double v_bottom = H - 0.5;
  const double shift = std::round((0.5 * W - curved.U(0, v_bottom)) / curved.SpacingAt(v_bottom));
  for (CurveKnot& k : curved.curve) k.centre_u_px += shift * k.spacing_px;
  curved.top_v_px = std::clamp(std::min(fit.top_v_px, det.confidence > 0.0 ? det.top_v_px : H),
                               0.0, v_bottom);
  if (fit.coherence < options_.min_curve_coherence && det.confidence <= 0.0) {
    det.curve_coherence = fit.coherence;
    if (det.reason.empty()) det.reason = "no rows";
    det.reason += "; curved rows: coherence " + std::to_string(fit.coherence);
    return det;
  }
  return AcceptCurve(std::move(det), std::move(curved), fit);
}

CurveFit RowDetector::FitCurve(const cv::Mat& fit, const RowDetection& det, CurvePrior& prior) {
  const double W = det.width_px, H = det.height_px;
  const double ku = W / fit.cols, kv = H / fit.rows;
  if (det.spacing_px > 0.0) {
    prior = {true, det.centre_u_px, det.spacing_px, det.convergence, det.lean};
  }
  CurveFit result = curve_fitter_.Fit(fit, ku, kv, W, H, prior);
  if (options_.curve_free_prior == 1) {
    result = curve_fitter_.Fit(fit, ku, kv, W, H, CurvePrior{});
  } else if (prior.valid && (options_.curve_free_prior == 2 ||
      (det.confidence <= 0.0 && (result.knots.size() < 2 || result.coherence < options_.min_curve_coherence)))) {
    // The straight model's geometry may be wrong where it found no rows:
    // the free prior (parallel rows, spacing searched) gets its turn.
    CurveFit free = curve_fitter_.Fit(fit, ku, kv, W, H, CurvePrior{});
    if (free.knots.size() >= 2 && free.coherence > result.coherence) result = std::move(free);
  }
  return result;
}

RowDetection RowDetector::AcceptCurve(RowDetection det, RowDetection curved,
                                      const CurveFit& fit) const {
  double contrast = 0.0;
  curved.rows = CurveRows(curved, contrast);
  curved.contrast = contrast;
  if (curved.rows.size() >= 2 && contrast < options_.min_contrast) {
    det.curve_coherence = fit.coherence;
    if (det.confidence > 0.0) return det;
    det.reason += "; curved rows: contrast " + std::to_string(contrast) + " between rows and gaps";
    return det;
  }
  if (curved.rows.size() < 2) {
    det.curve_coherence = fit.coherence;
    if (det.confidence > 0.0) return det;
    det.reason += "; curved rows: fewer than two rows with plant matter along them";
    return det;
  }
  double occupancy = 0.0;
  for (const DetectedRow& r : curved.rows) occupancy += r.occupancy;
  occupancy /= static_cast<double>(curved.rows.size());
  curved.confidence = std::clamp(fit.coherence * occupancy, 1e-3, 1.0);
  curved.reason.clear();
  return curved;
}

namespace {

// Per row of a curve, over the bands from the bottom up to its top: in how
// many it is in the image and in how many it holds plant matter clearly
// above the matter half-way between the rows; and that matter on the rows
// and half-way between them, summed.
struct CurveTally {
  std::vector<int> in_image, occupied;
  int visible_bands = 0;
  double on_sum = 0.0, between_sum = 0.0;
};

// A band of the fit image's rows [r0, r1): its column sums, cumulated, read
// as the mean plant matter in a window of image columns.
class BandProfile {
 public:
  BandProfile(const cv::Mat& fit, double kfw)
      : fit_(fit),
        kfw_(kfw),
        profile_(static_cast<size_t>(fit.cols)),
        cum_(static_cast<size_t>(fit.cols) + 1) {}

  void Load(int r0, int r1) {
    r0_ = r0;
    r1_ = r1;
    const int fw = fit_.cols;
    std::fill(profile_.begin(), profile_.end(), 0.0);
    for (int r = r0; r < r1; ++r) {
      const float* row = fit_.ptr<float>(r);
      for (int x = 0; x < fw; ++x) profile_[static_cast<size_t>(x)] += static_cast<double>(row[x]);
    }
    for (int x = 0; x < fw; ++x) {
      cum_[static_cast<size_t>(x) + 1] = cum_[static_cast<size_t>(x)] + profile_[static_cast<size_t>(x)];
    }
  }

  // Mean over the columns within `half` of image column u; −1 when none.
  double Window(double u, double half) const {
    const int x0 = std::max(0, static_cast<int>(std::ceil((u - half) / kfw_ - 0.5)));
    const int x1 = std::min(fit_.cols - 1, static_cast<int>(std::floor((u + half) / kfw_ - 0.5)));
    if (x1 < x0) return -1.0;
    return (cum_[static_cast<size_t>(x1) + 1] - cum_[static_cast<size_t>(x0)]) /
           ((x1 - x0 + 1) * (r1_ - r0_));
  }

 private:
  const cv::Mat& fit_;
  double kfw_;
  std::vector<double> profile_, cum_;
  int r0_ = 0, r1_ = 0;
};

// One band at image row v, spacing d: each row's matter (density, −1 out of
// the image) against the matter half-way between the rows, into the tally.
void TallyBand(const BandProfile& band, const RowDetection& det, double v, double half, double d,
               int n_lo, std::vector<double>& density, CurveTally& t) {
  const double W = det.width_px;
  const size_t n_rows = density.size();
  double background = 0.0;
  int n_background = 0;
  for (size_t i = 0; i < n_rows; ++i) {
    const int n = n_lo + static_cast<int>(i);
    const double u = det.U(n, v);
    density[i] = (u >= 0.0 && u <= W) ? band.Window(u, half) : -1.0;
    const double m = u + 0.5 * d;
    const double between = (m >= 0.0 && m <= W) ? band.Window(m, half) : -1.0;
    if (between >= 0.0) {
      background += between;
      ++n_background;
    }
  }
  for (size_t i = 0; i < n_rows; ++i) {
    if (density[i] >= 0.0) t.on_sum += density[i];
  }
  t.between_sum += background;
  background = n_background > 0 ? background / n_background : 0.0;
  const double level = std::max(0.02, 1.3 * background);
  for (size_t i = 0; i < n_rows; ++i) {
    if (density[i] < 0.0) continue;
    ++t.in_image[i];
    if (density[i] >= level) ++t.occupied[i];
  }
}

CurveTally TallyCurveRows(const cv::Mat& fit, const RowDetection& det, double hw,
                          double min_visible_spacing_px, int n_lo, size_t n_rows) {
  const double W = det.width_px, H = det.height_px;
  const int fw = fit.cols, fh = fit.rows;
  const double kfw = W / fw, kfh = H / fh;
  const int n_bands = std::min(24, fh);
  CurveTally t{std::vector<int>(n_rows, 0), std::vector<int>(n_rows, 0)};
  BandProfile band(fit, kfw);
  std::vector<double> density(n_rows);
  for (int k = 0; k < n_bands; ++k) {
    const int r0 = fh - (k + 1) * fh / n_bands, r1 = fh - k * fh / n_bands;
    const double v = 0.5 * (r0 + r1) * kfh;
    if (v < det.top_v_px) break;
    const double d = det.SpacingAt(v);
    if (d < min_visible_spacing_px) break;
    ++t.visible_bands;
    band.Load(r0, r1);
    TallyBand(band, det, v, std::max(0.5 * kfw, hw * d), d, n_lo, density, t);
  }
  return t;
}

}  // namespace

std::vector<DetectedRow> RowDetector::CurveRows(const RowDetection& det, double& contrast) const {
  contrast = 0.0;
  const double W = det.width_px;
  const double v_bottom = det.height_px - 0.5;
  const double d0 = det.SpacingAt(v_bottom);
  const double c0 = det.U(0, v_bottom);
  if (!(d0 > 0.0)) return {};
  const int n_lo = static_cast<int>(std::floor((-W - c0) / d0));
  const int n_hi = static_cast<int>(std::ceil((2.0 * W - c0) / d0));
  if (n_hi - n_lo > 200) return {};
  const size_t n_rows = static_cast<size_t>(n_hi - n_lo + 1);
  const CurveTally t = TallyCurveRows(straight_->fit_image(), det, options_.row_halfwidth_fraction,
                                      options_.min_visible_spacing_px, n_lo, n_rows);
  contrast = t.on_sum > 0.0 ? 1.0 - t.between_sum / t.on_sum : 0.0;
  // A row is judged where it is in the image for a third of the visible
  // height at least (rows fanning in at the top corners are not).
  std::vector<double> occupancy(n_rows, -1.0);
  int first = -1, last = -1;
  const int min_in_image = std::max(2, t.visible_bands / 3);
  for (size_t i = 0; i < n_rows; ++i) {
    if (t.in_image[i] < min_in_image) continue;
    occupancy[i] = static_cast<double>(t.occupied[i]) / t.in_image[i];
    if (occupancy[i] < options_.min_row_occupancy) continue;
    if (first < 0) first = static_cast<int>(i);
    last = static_cast<int>(i);
  }
  std::vector<DetectedRow> rows;
  for (int i = std::max(first, 0); first >= 0 && i <= last; ++i) {
    const double occ = occupancy[static_cast<size_t>(i)];
    if (occ < options_.min_gap_row_occupancy) continue;
    const int n = n_lo + i;
    rows.push_back({n, det.U(n, v_bottom), occ});
  }
  return rows;
}

}  // namespace plantscale::rows
