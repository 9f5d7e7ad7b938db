#include "engine/rows/row_detector.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "engine/rows/comb.h"

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
  RequireInRange(e, "min_contrast", min_contrast, 0.0, 1.0);
  RequireInRange(e, "gap_search_fraction", gap_search_fraction, 0.0, 0.5, false);
  if (fit_iterations < 0) e.push_back({"fit_iterations", "must be >= 0"});
  RequireInRange(e, "min_row_occupancy", min_row_occupancy, 0.0, 1.0);
  RequireInRange(e, "min_gap_row_occupancy", min_gap_row_occupancy, 0.0, 1.0);
  RequirePositive(e, "min_visible_spacing_px", min_visible_spacing_px);
  RequireInRange(e, "orientation_floor", orientation_floor, 0.0, 1.0);
  if (orientation_candidates < 0) e.push_back({"orientation_candidates", "must be >= 0"});
  for (const OptionError& c : curve.Validate()) e.push_back({"curve." + c.key, c.reason});
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

namespace {

// Below this factor 1 − g·Δv the rows are too compressed to use.
constexpr double kMinShrink = 0.25;

struct Geometry {
  double g = 0.0;  // convergence, 1/px
  double c = 0.0;  // lean
};

struct Band {
  double dv = 0.0;     // Δv of the band's centre, px
  double v_top = 0.0;  // the band's top edge, px
  int rows = 0;        // work rows in the band
};

// `n_bands` horizontal bands of `image` (CV_32F, `scale` image pixels per
// row of it) and, in `profiles` (n_bands × cols), each band's column sums.
std::vector<Band> SplitIntoBands(const cv::Mat& image, int n_bands, double scale, double v_bottom,
                                 std::vector<float>& profiles) {
  const int w = image.cols, h = image.rows;
  std::vector<Band> bands(static_cast<size_t>(n_bands));
  profiles.assign(static_cast<size_t>(n_bands) * static_cast<size_t>(w), 0.0F);
  for (int k = 0; k < n_bands; ++k) {
    const int r0 = k * h / n_bands;
    const int r1 = (k + 1) * h / n_bands;
    Band& b = bands[static_cast<size_t>(k)];
    b.rows = r1 - r0;
    b.v_top = r0 * scale;
    b.dv = v_bottom - 0.5 * (r0 + r1) * scale;
    float* p = &profiles[static_cast<size_t>(k) * static_cast<size_t>(w)];
    for (int r = r0; r < r1; ++r) {
      const float* row = image.ptr<float>(r);
      for (int x = 0; x < w; ++x) p[x] += row[x];
    }
  }
  return bands;
}

double MeanOccupancy(const std::vector<DetectedRow>& rows) {
  if (rows.empty()) return 0.0;
  double sum = 0.0;
  for (const DetectedRow& r : rows) sum += r.occupancy;
  return sum / static_cast<double>(rows.size());
}

// Two rows fix a vanishing point whatever it is; every further row is a
// test of the perspective constraint, so hypotheses with more rows found
// are trusted more: n / (n + 1).
double RowCountFactor(const std::vector<DetectedRow>& rows) {
  const double n = static_cast<double>(rows.size());
  return n / (n + 1.0);
}

}  // namespace

RowDetector::RowDetector(const RowDetectorOptions& options)
    : options_((ThrowIfInvalid("row detector", options.Validate()), options)),
      curve_fitter_(options.curve) {}

RowDetection RowDetector::Detect(const cv::Mat& plant) {
  if (plant.empty()) throw DataError("row detector: empty image");
  if (plant.type() != CV_8UC1 && plant.type() != CV_32FC1) {
    throw DataError("row detector: plant image must be CV_8UC1 or CV_32FC1");
  }
  RowDetection det = DetectStraight(plant);
  if (!options_.curves || fit_.empty() || det.reason.rfind("no plant matter", 0) == 0) return det;
  const double W = plant.cols, H = plant.rows;
  CurvePrior prior;
  if (det.spacing_px > 0.0) {
    prior = {true, det.centre_u_px, det.spacing_px, det.convergence, det.lean};
  }
  CurveFit fit = curve_fitter_.Fit(fit_, W / fit_.cols, H / fit_.rows, W, H, prior);
  if (options_.curve_free_prior == 1) {
    fit = curve_fitter_.Fit(fit_, W / fit_.cols, H / fit_.rows, W, H, CurvePrior{});
  } else if (prior.valid && (options_.curve_free_prior == 2 ||
      (det.confidence <= 0.0 && (fit.knots.size() < 2 || fit.coherence < options_.min_curve_coherence)))) {
    // The straight model's geometry may be wrong where it found no rows:
    // the free prior (parallel rows, spacing searched) gets its turn.
    CurveFit free = curve_fitter_.Fit(fit_, W / fit_.cols, H / fit_.rows, W, H, CurvePrior{});
    if (free.knots.size() >= 2 && free.coherence > fit.coherence) fit = std::move(free);
  }
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

std::vector<DetectedRow> RowDetector::CurveRows(const RowDetection& det, double& contrast) const {
  contrast = 0.0;
  const double W = det.width_px, H = det.height_px;
  const double v_bottom = H - 0.5;
  const int fw = fit_.cols, fh = fit_.rows;
  const double kfw = W / fw, kfh = H / fh;
  const int n_bands = std::min(24, fh);
  const double d0 = det.SpacingAt(v_bottom);
  const double c0 = det.U(0, v_bottom);
  if (!(d0 > 0.0)) return {};
  const int n_lo = static_cast<int>(std::floor((-W - c0) / d0));
  const int n_hi = static_cast<int>(std::ceil((2.0 * W - c0) / d0));
  if (n_hi - n_lo > 200) return {};
  const size_t n_rows = static_cast<size_t>(n_hi - n_lo + 1);
  std::vector<int> in_image(n_rows, 0), occupied(n_rows, 0);
  int visible_bands = 0;
  double on_sum = 0.0, between_sum = 0.0;  // plant matter on the rows and half-way between
  std::vector<double> profile(static_cast<size_t>(fw));
  std::vector<double> cum(static_cast<size_t>(fw) + 1);
  std::vector<double> density(n_rows);
  const double hw = options_.row_halfwidth_fraction;
  for (int k = 0; k < n_bands; ++k) {
    const int r0 = fh - (k + 1) * fh / n_bands, r1 = fh - k * fh / n_bands;
    const double v = 0.5 * (r0 + r1) * kfh;
    if (v < det.top_v_px) break;
    const double d = det.SpacingAt(v);
    if (d < options_.min_visible_spacing_px) break;
    ++visible_bands;
    std::fill(profile.begin(), profile.end(), 0.0);
    for (int r = r0; r < r1; ++r) {
      const float* row = fit_.ptr<float>(r);
      for (int x = 0; x < fw; ++x) profile[static_cast<size_t>(x)] += static_cast<double>(row[x]);
    }
    for (int x = 0; x < fw; ++x) cum[static_cast<size_t>(x) + 1] = cum[static_cast<size_t>(x)] + profile[static_cast<size_t>(x)];
    const auto window = [&](double u, double half) {
      const int x0 = std::max(0, static_cast<int>(std::ceil((u - half) / kfw - 0.5)));
      const int x1 = std::min(fw - 1, static_cast<int>(std::floor((u + half) / kfw - 0.5)));
      if (x1 < x0) return -1.0;
      return (cum[static_cast<size_t>(x1) + 1] - cum[static_cast<size_t>(x0)]) / ((x1 - x0 + 1) * (r1 - r0));
    };
    const double half = std::max(0.5 * kfw, hw * d);
    double background = 0.0;
    int n_background = 0;
    for (size_t i = 0; i < n_rows; ++i) {
      const int n = n_lo + static_cast<int>(i);
      const double u = det.U(n, v);
      density[i] = (u >= 0.0 && u <= W) ? window(u, half) : -1.0;
      const double m = u + 0.5 * d;
      if (m >= 0.0 && m <= W) {
        const double between = window(m, half);
        if (between >= 0.0) {
          background += between;
          ++n_background;
        }
      }
    }
    for (size_t i = 0; i < n_rows; ++i) {
      if (density[i] >= 0.0) on_sum += density[i];
    }
    between_sum += background;
    background = n_background > 0 ? background / n_background : 0.0;
    const double level = std::max(0.02, 1.3 * background);
    for (size_t i = 0; i < n_rows; ++i) {
      if (density[i] < 0.0) continue;
      ++in_image[i];
      if (density[i] >= level) ++occupied[i];
    }
  }
  std::vector<double> occupancy(n_rows, -1.0);
  int first = -1, last = -1;
  // A row is judged where it is in the image for a third of the visible
  // height at least (rows fanning in at the top corners are not).
  contrast = on_sum > 0.0 ? 1.0 - between_sum / on_sum : 0.0;
  const int min_in_image = std::max(2, visible_bands / 3);
  for (size_t i = 0; i < n_rows; ++i) {
    if (in_image[i] < min_in_image) continue;
    occupancy[i] = static_cast<double>(occupied[i]) / in_image[i];
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

RowDetection RowDetector::DetectStraight(const cv::Mat& plant) {
  const RowDetectorOptions& o = options_;
  RowDetection out;
  out.width_px = plant.cols;
  out.height_px = plant.rows;
  const double W = plant.cols;
  const double H = plant.rows;
  const double v_bottom = H - 0.5;

  // Plant fraction images at the Hough and refit resolutions.
  cv::Mat unit;
  if (plant.type() == CV_8UC1) {
    cv::Mat binary;
    cv::compare(plant, 0, binary, cv::CMP_GT);
    binary.convertTo(unit, CV_32F, 1.0 / 255.0);
  } else {
    unit = plant;
  }
  const double plant_fraction = cv::mean(unit)[0];
  if (plant_fraction < o.min_plant_fraction) {
    out.reason = "no plant matter (" + std::to_string(plant_fraction * 100.0) + "% of the image)";
    return out;
  }
  const auto resized = [&](int width, cv::Mat& dst) {
    if (width >= plant.cols) {
      unit.copyTo(dst);
      return;
    }
    const int height = std::max(4, static_cast<int>(std::lround(H * width / W)));
    cv::resize(unit, dst, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  };
  resized(o.work_width_px, work_);
  resized(o.fit_width_px, fit_);
  const int w = work_.cols;
  const int h = work_.rows;
  const double kw = W / w;
  const double kh = H / h;

  const bool use_orientation = o.orientation_floor > 0.0;
  if (use_orientation) orientation_.Build(work_, kw, kh, v_bottom);

  // Bands and their column profiles.
  const int n_bands = std::min(o.strips, h);
  const std::vector<Band> bands = SplitIntoBands(work_, n_bands, kh, v_bottom, profiles_);

  double total_mass = 0.0;
  for (const float m : profiles_) total_mass += static_cast<double>(m);
  // Running sums of the band profiles: the plant matter in a window of
  // columns in constant time.
  cumulative_.assign(static_cast<size_t>(n_bands) * (w + 1), 0.0);
  for (int k = 0; k < n_bands; ++k) {
    const float* p = &profiles_[static_cast<size_t>(k) * w];
    double* cum = &cumulative_[static_cast<size_t>(k) * (w + 1)];
    for (int x = 0; x < w; ++x) cum[x + 1] = cum[x] + static_cast<double>(p[x]);
  }

  // The s histogram over [−W, 2W) for one geometry, from the bands with
  // Δv ≤ max_dv whose rows are not too compressed. Each column's mass is
  // spread over its stretched width so that stretching adds no holes.
  const int n_bins = 3 * w;
  const double s0 = -W + 0.5 * kw;  // centre of bin 0
  const auto build = [&](const Geometry& geo, double max_dv) {
    histogram_.assign(static_cast<size_t>(n_bins), 0.0);
    for (int k = 0; k < n_bands; ++k) {
      const Band& b = bands[static_cast<size_t>(k)];
      const double shrink = 1.0 - geo.g * b.dv;
      if (shrink < kMinShrink || b.dv > max_dv) continue;
      const double m = 1.0 / shrink;
      const int pieces = std::max(1, static_cast<int>(std::ceil(m - 1e-9)));
      const float* p = &profiles_[static_cast<size_t>(k) * w];
      // Bin coordinate t = (s − s0)/kw of column position x (in columns):
      // t = x·m + offset.
      const double offset = (-geo.c * b.dv * m - s0) / kw;
      const double last_t = n_bins - 1.0;
      double* bins = histogram_.data();
      for (int x = 0; x < w; ++x) {
        if (p[x] <= 0.0F) continue;
        const double mass = static_cast<double>(p[x]) / pieces;
        for (int q = 0; q < pieces; ++q) {
          const double t = (x + (q + 0.5) / pieces) * m + offset;
          if (!(t >= 0.0 && t < last_t)) continue;  // beyond [−W, 2W): dropped
          const int i = static_cast<int>(t);
          const double f = t - i;
          bins[i] += mass * (1.0 - f);
          bins[i + 1] += mass * f;
        }
      }
    }
  };
  const auto geometry_at = [&](double g, double lean_at_centre) {
    return Geometry{g, lean_at_centre + g * 0.5 * W};
  };
  const double d_min = o.min_spacing_fraction * W;
  const double d_max = o.max_spacing_fraction * W;
  const double min_spacing = std::max(o.min_visible_spacing_px, 2.0 * kw);
  const double hw = o.row_halfwidth_fraction;

  // Rows of one comb that have plant matter along their length: a row is
  // occupied in a band when its window holds clearly more plant matter
  // than the windows half-way between the rows.
  struct Rows {
    std::vector<DetectedRow> rows;
    double top_v = 0.0;
    bool adjacent = false;  // two neighbouring teeth both kept
    // 1 − (plant matter half-way between kept rows) / (on them): a comb of
    // twice the spacing has a row half-way between its teeth.
    double contrast = 0.0;
  };
  const auto find_rows = [&](const Geometry& geo, double d, double sc) {
    Rows result;
    result.top_v = v_bottom;
    const int n_lo = static_cast<int>(std::ceil((-W - sc) / d));
    const int n_hi = static_cast<int>(std::floor((2.0 * W - sc) / d));
    if (n_hi < n_lo || n_hi - n_lo > 200) return result;
    const size_t n_rows = static_cast<size_t>(n_hi - n_lo + 1);
    std::vector<int> in_image(n_rows, 0), occupied(n_rows, 0);
    std::vector<int> highest(n_rows, -1);
    std::vector<double> density(n_rows);
    std::vector<double> on_sum(n_rows, 0.0), between_sum(n_rows, 0.0);
    std::vector<int> on_count(n_rows, 0), between_count(n_rows, 0);
    const auto window = [&](const double* cum, double u, double half, int rows_in_band) {
      const int x0 = std::max(0, static_cast<int>(std::ceil((u - half) / kw - 0.5)));
      const int x1 = std::min(w - 1, static_cast<int>(std::floor((u + half) / kw - 0.5)));
      if (x1 < x0) return -1.0;
      return (cum[x1 + 1] - cum[x0]) / ((x1 - x0 + 1) * rows_in_band);
    };
    // Towards the vanishing point the rows merge into one canopy: the
    // bands at the top where the teeth hold no more plant matter than the
    // gaps between them are left out (of occupancy and contrast alike), as
    // a geometry that cannot use them at all leaves them out.
    int k_first = 0;
    for (; k_first < n_bands; ++k_first) {
      const Band& b = bands[static_cast<size_t>(k_first)];
      const double shrink = 1.0 - geo.g * b.dv;
      if (shrink < kMinShrink || d * shrink < min_spacing) continue;
      const double* p = &cumulative_[static_cast<size_t>(k_first) * (w + 1)];
      const double half = std::max(0.5 * kw, hw * d * shrink);
      double on = 0.0, between = 0.0;
      for (size_t r = 0; r < n_rows; ++r) {
        const double u = (sc + (n_lo + static_cast<int>(r)) * d) * shrink + geo.c * b.dv;
        const double m = u + 0.5 * d * shrink;
        if (u >= 0.0 && u <= W) on += std::max(0.0, window(p, u, half, b.rows));
        if (m >= 0.0 && m <= W) between += std::max(0.0, window(p, m, half, b.rows));
      }
      if (on > 0.0 && 1.0 - between / on >= o.min_contrast) break;
    }
    for (int k = k_first; k < n_bands; ++k) {
      const Band& b = bands[static_cast<size_t>(k)];
      const double shrink = 1.0 - geo.g * b.dv;
      if (shrink < kMinShrink || d * shrink < min_spacing) continue;
      const double* p = &cumulative_[static_cast<size_t>(k) * (w + 1)];
      const double half = std::max(0.5 * kw, hw * d * shrink);
      double background = 0.0;
      int n_background = 0;
      for (size_t r = 0; r < n_rows; ++r) {
        const int n = n_lo + static_cast<int>(r);
        const double u = (sc + n * d) * shrink + geo.c * b.dv;
        density[r] = (u >= 0.0 && u <= W) ? window(p, u, half, b.rows) : -1.0;
        const double between = window(p, u + 0.5 * d * shrink, half, b.rows);
        if (between >= 0.0 && u + 0.5 * d * shrink >= 0.0 && u + 0.5 * d * shrink <= W) {
          background += between;
          ++n_background;
          between_sum[r] += between;
          ++between_count[r];
        }
      }
      background = n_background > 0 ? background / n_background : 0.0;
      const double level = std::max(0.02, 1.3 * background);
      for (size_t r = 0; r < n_rows; ++r) {
        if (density[r] < 0.0) continue;
        ++in_image[r];
        on_sum[r] += density[r];
        ++on_count[r];
        if (density[r] >= level) {
          ++occupied[r];
          highest[r] = highest[r] < 0 ? k : std::min(highest[r], k);
        }
      }
    }
    // Rows with plant matter along most of their length; between two of
    // them, a tooth with some (a row with many plants missing) is a row
    // too. A comb of half the rows' spacing keeps only every other tooth.
    std::vector<double> occupancy(n_rows, -1.0);
    int first = -1, last = -1;
    for (size_t r = 0; r < n_rows; ++r) {
      if (in_image[r] < 2) continue;
      occupancy[r] = static_cast<double>(occupied[r]) / in_image[r];
      if (occupancy[r] < o.min_row_occupancy) continue;
      if (first < 0) first = static_cast<int>(r);
      last = static_cast<int>(r);
    }
    int top_band = n_bands;
    int previous = n_lo - 2;
    for (int r = std::max(first, 0); first >= 0 && r <= last; ++r) {
      const double occ = occupancy[static_cast<size_t>(r)];
      if (occ < o.min_row_occupancy && occ < o.min_gap_row_occupancy) continue;
      const int n = n_lo + r;
      if (n == previous + 1) result.adjacent = true;
      previous = n;
      result.rows.push_back({n, sc + n * d, occ});
      if (highest[static_cast<size_t>(r)] >= 0) {
        top_band = std::min(top_band, highest[static_cast<size_t>(r)]);
      }
    }
    if (result.rows.empty()) return result;
    if (last > first) {
      double on = 0.0, between = 0.0;
      int n_on = 0, n_between = 0;
      for (int r = first; r <= last; ++r) {
        on += on_sum[static_cast<size_t>(r)];
        n_on += on_count[static_cast<size_t>(r)];
        if (r < last) {
          between += between_sum[static_cast<size_t>(r)];
          n_between += between_count[static_cast<size_t>(r)];
        }
      }
      if (n_on > 0 && n_between > 0 && on > 0.0) {
        result.contrast = std::max(0.0, 1.0 - (between / n_between) / (on / n_on));
      }
    }
    double top = bands[static_cast<size_t>(top_band)].v_top;
    if (geo.g > 0.0) top = std::max(top, v_bottom - (1.0 - min_spacing / d) / geo.g);
    result.top_v = std::clamp(top, 0.0, v_bottom);
    return result;
  };

  // 1. Hough over (g, lean): how sharply the plant matter piles up in s
  // (smoothed Σh²/(Σh)²), on the bands that every cell can use.
  const double g_max = o.max_convergence / H;
  const int ng = o.convergence_steps;
  const int nl = o.lean_steps;
  const double g_step = g_max / (ng - 1);
  const double l_step = nl > 1 ? 2.0 * o.max_lean / (nl - 1) : 0.0;
  std::vector<double> sharpness(static_cast<size_t>(ng) * nl, 0.0);
  for (int i = 0; i < ng; ++i) {
    for (int j = 0; j < nl; ++j) {
      build(geometry_at(i * g_step, -o.max_lean + j * l_step), H);
      double sum = 0.0, sum2 = 0.0;
      for (int b = 0; b < n_bins; ++b) {
        const double l = b > 0 ? histogram_[static_cast<size_t>(b - 1)] : 0.0;
        const double r = b + 1 < n_bins ? histogram_[static_cast<size_t>(b + 1)] : 0.0;
        const double v = 0.25 * l + 0.5 * histogram_[static_cast<size_t>(b)] + 0.25 * r;
        sum += v;
        sum2 += v * v;
      }
      sharpness[static_cast<size_t>(i) * nl + j] = sum > 0.0 ? sum2 / (sum * sum) : 0.0;
    }
  }
  std::vector<int> order(sharpness.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return sharpness[static_cast<size_t>(a)] > sharpness[static_cast<size_t>(b)];
  });
  std::vector<int> chosen;
  for (int index : order) {
    if (static_cast<int>(chosen.size()) >= o.candidates) break;
    const bool near = std::any_of(chosen.begin(), chosen.end(), [&](int c) {
      return std::abs(c / nl - index / nl) <= 1 && std::abs(c % nl - index % nl) <= 1;
    });
    if (!near) chosen.push_back(index);
  }
  // The streaks' support over the same grid; its best cells are candidates
  // too (a near-field plant can make a wrong geometry the sharpest).
  double support_max = 0.0;
  int best_support_index = 0;
  if (use_orientation) {
    std::vector<double> support(sharpness.size(), 0.0);
    for (int i = 0; i < ng; ++i) {
      for (int j = 0; j < nl; ++j) {
        const Geometry geo = geometry_at(i * g_step, -o.max_lean + j * l_step);
        support[static_cast<size_t>(i) * nl + j] = orientation_.Support(geo.g, geo.c);
      }
    }
    std::vector<int> by_support(order);
    std::sort(by_support.begin(), by_support.end(), [&](int a, int b) {
      return support[static_cast<size_t>(a)] > support[static_cast<size_t>(b)];
    });
    best_support_index = by_support.front();
    support_max = support[static_cast<size_t>(best_support_index)];
    std::vector<int> taken;
    for (int index : by_support) {
      if (static_cast<int>(taken.size()) >= o.orientation_candidates) break;
      const bool near = std::any_of(taken.begin(), taken.end(), [&](int c) {
        return std::abs(c / nl - index / nl) <= 1 && std::abs(c % nl - index % nl) <= 1;
      });
      if (near) continue;
      taken.push_back(index);
      if (std::find(chosen.begin(), chosen.end(), index) == chosen.end()) chosen.push_back(index);
    }
  }
  // The streaks' own best geometry, refined off the grid by halving steps:
  // the vanishing point the refit may keep (step 4).
  double lock_g = 0.0, lock_lean = 0.0;
  const bool locked = use_orientation && support_max > 0.0;
  if (locked) {
    lock_g = (best_support_index / nl) * g_step;
    lock_lean = -o.max_lean + (best_support_index % nl) * l_step;
    double best_support = support_max, sg = g_step, sl = l_step;
    for (int level = 0; level < 6; ++level) {
      sg *= 0.5;
      sl *= 0.5;
      double bg = lock_g, bl = lock_lean;
      for (int i = -1; i <= 1; ++i) {
        for (int j = -1; j <= 1; ++j) {
          const double g = std::max(0.0, lock_g + i * sg), l = lock_lean + j * sl;
          const Geometry geo = geometry_at(g, l);
          const double e = orientation_.Support(geo.g, geo.c);
          if (e > best_support) best_support = e, bg = g, bl = l;
        }
      }
      lock_g = bg;
      lock_lean = bl;
    }
  }
  const auto streak_factor = [&](const Geometry& geo) {
    if (!use_orientation) return 1.0;
    const double floor = o.orientation_floor;
    return std::min(1.0, (orientation_.Support(geo.g, geo.c) + floor) / (support_max + floor));
  };

  // Sharpness alone favours little convergence when wide rows merge far
  // away; every convergence keeps its sharpest lean as a candidate too.
  for (int i = 0; i < ng; ++i) {
    const double* row = &sharpness[static_cast<size_t>(i) * nl];
    // The two sharpest leans that are local maxima along the lean axis.
    int first = -1, second = -1;
    for (int j = 0; j < nl; ++j) {
      const bool peak = (j == 0 || row[j] >= row[j - 1]) && (j + 1 == nl || row[j] > row[j + 1]);
      if (!peak) continue;
      if (first < 0 || row[j] > row[first]) {
        second = first;
        first = j;
      } else if (second < 0 || row[j] > row[second]) {
        second = j;
      }
    }
    for (const int j : {first, second}) {
      if (j < 0) continue;
      const int index = i * nl + j;
      if (std::find(chosen.begin(), chosen.end(), index) == chosen.end()) chosen.push_back(index);
    }
  }

  // The comb on the bands one by one: z_k = Σ w e^{−2πi s/d} over band k.
  // Rows agree in phase from band to band whatever their width; a comb
  // forced onto scattered matter or onto the wrong geometry does not. The
  // score is the comb's coherence times that agreement.
  struct BandComb {
    double coherence = 0.0, alignment = 0.0, phase = 0.0;
    double score() const { return coherence * alignment; }
  };
  const auto band_comb = [&](const Geometry& geo, double d) {
    std::complex<double> z_sum(0.0, 0.0);
    double z_abs = 0.0, mass = 0.0;
    for (int k = 0; k < n_bands; ++k) {
      const Band& b = bands[static_cast<size_t>(k)];
      const double shrink = 1.0 - geo.g * b.dv;
      if (shrink < kMinShrink || d * shrink < min_spacing) continue;
      const float* p = &profiles_[static_cast<size_t>(k) * w];
      const double s_first = (0.5 * kw - geo.c * b.dv) / shrink;
      // The phasor advances by a fixed rotation per column (written out:
      // std::complex's product checks for NaN at every step), in four
      // interleaved chains (columns x, x + 1, x + 2, x + 3, each rotated by
      // four columns' angle) so that the steps do not wait on each other.
      const double a0 = -2.0 * std::numbers::pi * s_first / d;
      const double da = -2.0 * std::numbers::pi * kw / (shrink * d);
      constexpr int kChains = 4;
      double pr[kChains], pi[kChains], zr[kChains] = {}, zi[kChains] = {}, mc[kChains] = {};
      for (int q = 0; q < kChains; ++q) {
        pr[q] = std::cos(a0 + q * da);
        pi[q] = std::sin(a0 + q * da);
      }
      const double sr = std::cos(kChains * da), si = std::sin(kChains * da);
      int x = 0;
      for (; x + kChains <= w; x += kChains) {
        for (int q = 0; q < kChains; ++q) {
          const double wx = static_cast<double>(p[x + q]);
          zr[q] += wx * pr[q];
          zi[q] += wx * pi[q];
          mc[q] += wx;
          const double next_r = pr[q] * sr - pi[q] * si;
          pi[q] = pr[q] * si + pi[q] * sr;
          pr[q] = next_r;
        }
      }
      for (int q = 0; x < w; ++x, ++q) {  // the last columns, fewer than four
        const double wx = static_cast<double>(p[x]);
        zr[q] += wx * pr[q];
        zi[q] += wx * pi[q];
        mc[q] += wx;
      }
      const double m = mc[0] + mc[1] + mc[2] + mc[3];
      if (m <= 0.0) continue;
      const std::complex<double> z(zr[0] + zr[1] + zr[2] + zr[3], zi[0] + zi[1] + zi[2] + zi[3]);
      z_sum += z;
      z_abs += std::abs(z);
      mass += m;
    }
    BandComb r;
    if (mass <= 0.0 || z_abs <= 0.0) return r;
    // Coherence over all the image's plant matter, not only the bands this
    // geometry can use: a vanishing point placed low in the image (or a
    // narrow comb) drops the upper bands, and must not be rewarded for
    // explaining less of the image.
    r.coherence = std::abs(z_sum) / std::max(mass, total_mass);
    r.alignment = std::abs(z_sum) / z_abs;
    double phase = -std::arg(z_sum) * d / (2.0 * std::numbers::pi);
    phase = std::fmod(phase, d);
    if (phase < 0.0) phase += d;
    r.phase = phase;
    return r;
  };

  // 2. The row comb on each candidate: the best period whose rows are
  // really there (two neighbouring rows with plant matter along them).
  struct Hypothesis {
    double g = 0.0, lean = 0.0, d = 0.0, sc = 0.0, score = -1.0;
  };
  // Hypotheses are kept per row count: a comb of twice the spacing (two
  // rows, every other row sparse) and the true comb (more rows, but a
  // coarse period grid drifts in phase across them) are both refined
  // before they are compared.
  std::vector<Hypothesis> by_count(12);
  double best_start = -1.0;
  const auto score_of = [&](const Geometry& geo, double period, double floor, Hypothesis& hyp,
                            size_t& n_rows) {
    const BandComb bc = band_comb(geo, period);
    if (bc.score() <= floor) return false;
    const Rows rows = find_rows(geo, period, bc.phase);
    if (!rows.adjacent) return false;
    hyp.sc = bc.phase;
    hyp.score = bc.score() * MeanOccupancy(rows.rows) * rows.contrast * RowCountFactor(rows.rows) *
                streak_factor(geo);
    n_rows = rows.rows.size();
    return true;
  };
  for (int index : chosen) {
    const double g = (index / nl) * g_step;
    const double lean = -o.max_lean + (index % nl) * l_step;
    const Geometry geo = geometry_at(g, lean);
    build(geo, H);
    std::vector<double> periods;
    for (const CombFit& fit :
         BestCombs(histogram_, s0, kw, d_min, d_max, 2.0 * o.spacing_step, 3)) {
      // A comb of twice the rows' spacing can fit rows too (every other
      // tooth empty, or two rows between teeth); its half is tried as well.
      periods.push_back(fit.period);
      if (fit.period / 2.0 >= d_min) periods.push_back(fit.period / 2.0);
    }
    for (const double period : periods) {
      Hypothesis hyp{g, lean, period, 0.0, -1.0};
      size_t n_rows = 0;
      // A comb far below the best so far will not win after refinement.
      if (!score_of(geo, period, o.prune_fraction * best_start, hyp, n_rows)) continue;
      best_start = std::max(best_start, hyp.score);
      Hypothesis& slot = by_count[std::min(n_rows, by_count.size() - 1)];
      if (hyp.score > slot.score) slot = hyp;
    }
  }

  // 3. Local search on (g, lean, d) by the same score, for each row count's
  // best hypothesis; the best refined one goes on.
  std::sort(by_count.begin(), by_count.end(),
            [](const Hypothesis& a, const Hypothesis& b) { return a.score > b.score; });
  by_count.resize(std::min(by_count.size(), static_cast<size_t>(o.refined_hypotheses)));
  Hypothesis best;
  for (const Hypothesis& start : by_count) {
    if (start.score < 0.0) continue;
    Hypothesis local = start;
    double step_g = g_step, step_l = l_step, step_d = 2.0 * o.spacing_step;
    for (int level = 0; level < 4; ++level) {
      step_g *= 0.5;
      step_l *= 0.5;
      const Hypothesis centre = local;
      // The comb (cheap) on the 27 neighbours; the rows (dearer) only on
      // the few whose comb could still beat the current best.
      struct Neighbour {
        Geometry geo;
        double g, lean, d, comb;
      };
      std::vector<Neighbour> neighbours;
      neighbours.reserve(27);
      for (int i = -1; i <= 1; ++i) {
        for (int j = -1; j <= 1; ++j) {
          const double g = std::max(0.0, centre.g + i * step_g);
          const double lean = centre.lean + j * step_l;
          for (int k = -1; k <= 1; ++k) {
            const double d = centre.d * (1.0 + k * step_d);
            const Geometry geo_n = geometry_at(g, lean);
            const double comb = band_comb(geo_n, d).score();
            if (comb > local.score) neighbours.push_back({geo_n, g, lean, d, comb});
          }
        }
      }
      const size_t keep = std::min(neighbours.size(), static_cast<size_t>(o.refine_row_checks));
      std::partial_sort(neighbours.begin(), neighbours.begin() + static_cast<std::ptrdiff_t>(keep),
                        neighbours.end(),
                        [](const Neighbour& a, const Neighbour& b) { return a.comb > b.comb; });
      for (size_t q = 0; q < keep; ++q) {
        const Neighbour& nb = neighbours[q];
        Hypothesis hyp{nb.g, nb.lean, nb.d, 0.0, -1.0};
        size_t n_rows = 0;
        if (!score_of(nb.geo, nb.d, local.score, hyp, n_rows)) continue;
        if (hyp.score > local.score) local = hyp;
      }
      step_d *= 0.5;
    }
    if (local.score > best.score) best = local;
  }
  if (best.score < 0.0) {
    out.reason = "no rows: no comb of evenly spaced rows with plant matter along them";
    return out;
  }
  Geometry geo = geometry_at(best.g, best.lean);
  double d = best.d;
  double sc = best.sc;
  Rows found = find_rows(geo, d, sc);
  if (!found.adjacent) {
    out.reason = "no rows: the refined comb has no two neighbouring rows with plant matter";
    return out;
  }

  // 4. Weighted least squares on each row's centre in thin bands: the
  // centroid of its plant matter between the gaps on either side (the
  // lowest columns between it and its neighbours), so that rows whose
  // plants nearly touch are centred by their edges, narrow rows by their
  // mass. Linear in (s_c, d, c − g·s_c, g·d):
  //   u = s_c + n·d + Δv·(c − g·s_c) − n·Δv·(g·d).
  const int fw = fit_.cols;
  const int fh = fit_.rows;
  const double kfw = W / fw;
  const double kfh = H / fh;
  const int fit_bands = std::max(4, fh / 4);
  const std::vector<Band> fbands = SplitIntoBands(fit_, fit_bands, kfh, v_bottom, fit_profiles_);
  struct Fit {
    Geometry geo;
    double d = 0.0, sc = 0.0;
    Rows found;
  };
  // With fix_vp the vanishing point stays and only (s_c, d) are fitted,
  // linear as well: u − c·Δv = s_c·(1 − g·Δv) + n·d·(1 − g·Δv).
  const auto refit = [&](Fit& fit, bool fix_vp) {
    for (int iteration = 0; iteration < o.fit_iterations; ++iteration) {
      Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
      Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
      Eigen::Matrix2d a2 = Eigen::Matrix2d::Zero();
      Eigen::Vector2d rhs2 = Eigen::Vector2d::Zero();
      int observations = 0;
      for (int k = 0; k < fit_bands; ++k) {
        const Band& b = fbands[static_cast<size_t>(k)];
        if (b.v_top + b.rows * kfh < fit.found.top_v) continue;
        const double shrink = 1.0 - fit.geo.g * b.dv;
        const double ds = fit.d * shrink;
        if (shrink < kMinShrink || ds < min_spacing) continue;
        const float* p = &fit_profiles_[static_cast<size_t>(k) * fw];
        const auto column = [&](double u) { return static_cast<int>(std::floor(u / kfw)); };
        // Lowest column in [u0, u1), or −1 when the range leaves the image.
        const auto gap = [&](double u0, double u1) {
          const int x0 = column(u0);
          const int x1 = column(u1);
          if (x0 < 0 || x1 >= fw) return -1;
          int lowest = x0;
          for (int x = x0 + 1; x <= x1; ++x) {
            if (p[x] < p[lowest] || (p[x] == p[lowest] && std::abs(x - 0.5 * (x0 + x1)) <
                                                              std::abs(lowest - 0.5 * (x0 + x1)))) {
              lowest = x;
            }
          }
          return lowest;
        };
        for (const DetectedRow& row : fit.found.rows) {
          const int n = row.n;
          const double u = (fit.sc + n * fit.d) * shrink + fit.geo.c * b.dv;
          const double f = o.gap_search_fraction;
          const int left = gap(u - (0.5 + f) * ds, u - (0.5 - f) * ds);
          const int right = gap(u + (0.5 - f) * ds, u + (0.5 + f) * ds);
          if (left < 0 || right <= left + 1) continue;
          double mass = 0.0, moment = 0.0;
          for (int x = left + 1; x < right; ++x) {
            mass += static_cast<double>(p[x]);
            moment += static_cast<double>(p[x]) * (x + 0.5) * kfw;
          }
          // A band where the row has little plant matter says little.
          if (mass < 0.1 * (right - left - 1) * b.rows) continue;
          const double u_obs = moment / mass;
          // Residuals measured in s (u / shrink): a band counts as much at
          // the top of the rows as at the bottom.
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
      if (observations < 6) break;
      if (fix_vp) {
        const Eigen::Vector2d q = a2.ldlt().solve(rhs2);
        if (!q.allFinite() || q(1) <= 0.7 * fit.d || q(1) >= 1.3 * fit.d) break;
        const Rows next_rows = find_rows(fit.geo, q(1), q(0));
        if (!next_rows.adjacent) break;
        fit.d = q(1);
        fit.sc = q(0);
        fit.found = next_rows;
        continue;
      }
      const Eigen::LDLT<Eigen::Matrix4d> ldlt(a);
      if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-12)) break;
      const Eigen::Vector4d p = ldlt.solve(rhs);
      if (!p.allFinite() || p(1) <= 0.7 * fit.d || p(1) >= 1.3 * fit.d) break;
      const Geometry next{p(3) / p(1), p(2) + p(3) / p(1) * p(0)};
      const Rows next_rows = find_rows(next, p(1), p(0));
      if (!next_rows.adjacent) break;
      fit.geo = next;
      fit.d = p(1);
      fit.sc = p(0);
      fit.found = next_rows;
    }
  };
  // Two fits compete by the score the search used: the full refit from the
  // best hypothesis, and the refit of (s_c, d) on the streaks' own
  // vanishing point. On photographs of tall, leafy rows the row centres
  // between gaps pull the full fit's vanishing point away (the rows merge
  // into a canopy towards it) where the streaks still point true; on
  // clean rows of separate plants the full fit is the finer one.
  // The final score of a fitted comb, as the search scored hypotheses.
  const auto fit_score = [&](const Fit& fit) {
    if (!fit.found.adjacent) return -1.0;
    return band_comb(fit.geo, fit.d).score() * MeanOccupancy(fit.found.rows) * fit.found.contrast *
           RowCountFactor(fit.found.rows) * streak_factor(fit.geo);
  };
  Fit chosen_fit{geo, d, sc, found};
  refit(chosen_fit, false);
  if (locked) {
    Fit fixed;
    fixed.geo = geometry_at(lock_g, lock_lean);
    fixed.d = d;
    fixed.sc = band_comb(fixed.geo, d).phase;
    fixed.found = find_rows(fixed.geo, fixed.d, fixed.sc);
    if (fixed.found.adjacent) {
      refit(fixed, true);
      const double a = fit_score(chosen_fit), b = fit_score(fixed);
      if (b > a) chosen_fit = fixed;
    }
  }
  geo = chosen_fit.geo;
  d = chosen_fit.d;
  sc = chosen_fit.sc;
  found = chosen_fit.found;

  // 5. The central row (nearest the image's centre at the bottom), the
  // comb's coherence over every usable band, the confidence.
  const DetectedRow* central = &found.rows.front();
  for (const DetectedRow& r : found.rows) {
    if (std::abs(r.bottom_u_px - 0.5 * W) < std::abs(central->bottom_u_px - 0.5 * W)) central = &r;
  }
  const int n_central = central->n;
  sc += n_central * d;
  for (DetectedRow& r : found.rows) r.n -= n_central;
  build(geo, H);
  const CombFit final_fit = CombAt(histogram_, s0, kw, d);
  const BandComb final_comb = band_comb(geo, d);
  const double alignment = final_comb.alignment;
  double occupancy = 0.0;
  for (const DetectedRow& r : found.rows) occupancy += r.occupancy;
  occupancy /= static_cast<double>(found.rows.size());

  out.centre_u_px = sc;
  out.spacing_px = d;
  out.convergence = geo.g;
  out.lean = geo.c;
  out.coherence = final_fit.coherence;
  out.alignment = alignment;
  // Rows are reported up to where they can no longer be told apart: the
  // spacing is still min_spacing and a reported row still has plant matter
  // in the band (above the bands the fit used, towards the vanishing point).
  double top_v = found.top_v;
  for (int k = n_bands - 1; k >= 0; --k) {
    const Band& b = bands[static_cast<size_t>(k)];
    if (b.v_top >= top_v) continue;
    const double shrink = 1.0 - geo.g * b.dv;
    if (shrink <= 0.0 || d * shrink < min_spacing) break;
    const float* p = &profiles_[static_cast<size_t>(k) * w];
    const double half = std::max(0.5 * kw, hw * d * shrink);
    bool any = false;
    for (const DetectedRow& r : found.rows) {
      const double u = (sc + r.n * d) * shrink + geo.c * b.dv;
      const int x0 = std::max(0, static_cast<int>(std::ceil((u - half) / kw - 0.5)));
      const int x1 = std::min(w - 1, static_cast<int>(std::floor((u + half) / kw - 0.5)));
      double sum = 0.0;
      for (int x = x0; x <= x1; ++x) sum += static_cast<double>(p[x]);
      if (x1 >= x0 && sum / ((x1 - x0 + 1) * b.rows) >= 0.05) any = true;
    }
    if (!any) break;
    top_v = b.v_top;
  }
  if (geo.g > 0.0) top_v = std::max(top_v, v_bottom - (1.0 - min_spacing / d) / geo.g);
  out.top_v_px = std::clamp(top_v, 0.0, v_bottom);
  out.contrast = found.contrast;
  if (final_fit.coherence < o.min_coherence || alignment < o.min_alignment ||
      found.contrast < o.min_contrast) {
    out.reason = "no rows: plant matter does not follow evenly spaced rows (coherence " +
                 std::to_string(final_fit.coherence) + ", band agreement " +
                 std::to_string(alignment) + ", contrast " + std::to_string(found.contrast) + ")";
    return out;
  }
  out.rows = std::move(found.rows);
  out.confidence = std::clamp(final_fit.coherence * occupancy, 1e-3, 1.0);
  return out;
}

}  // namespace plantscale::rows
