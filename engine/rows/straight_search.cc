#include "engine/rows/straight_search.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "engine/rows/comb.h"
#include "engine/rows/straight_search_internal.h"

namespace plantscale::rows {

using straight_internal::kMinShrink;
using straight_internal::MeanOccupancy;
using straight_internal::RowCountFactor;

namespace {

// A column stretched by m = 1 / (1 − g·Δv) ≤ 1 / kMinShrink spreads over
// up to this many pieces.
constexpr int kMaxPieces = 4;

// BuildHistogram's inner loop: each column's mass in `pieces` equal parts
// at bin coordinates t = x·m + piece_t[q], each shared linearly between
// the two bins about it; parts beyond [0, last_t) are dropped. (Holding
// the two bins in registers while t stays between them was slower: the
// branch on t's bin is not predictable.)
template <int pieces>
void SplatColumns(const float* p, int w, double m, double share, const double* piece_t, double last_t,
                  double* bins) {
  for (int x = 0; x < w; ++x) {
    if (p[x] <= 0.0F) continue;
    const double mass = static_cast<double>(p[x]) * share;
    const double xm = x * m;
    for (int q = 0; q < pieces; ++q) {
      const double t = xm + piece_t[q];
      if (!(t >= 0.0 && t < last_t)) continue;  // beyond [−W, 2W): dropped
      const int i = static_cast<int>(t);
      const double f = t - i;
      bins[i] += mass * (1.0 - f);
      bins[i + 1] += mass * f;
    }
  }
}

// Two Hough cells (row-major, `nl` leans per convergence) next to each other.
bool NearCells(int a, int b, int nl) {
  return std::abs(a / nl - b / nl) <= 1 && std::abs(a % nl - b % nl) <= 1;
}

void AddOnce(std::vector<int>& cells, int index) {
  if (std::find(cells.begin(), cells.end(), index) == cells.end()) cells.push_back(index);
}

// Mean plant matter per cell of the columns (kw image pixels each, w of
// them) within ± half of u in one band (running sums `cum`, `rows_in_band`
// rows); −1 when the window leaves the image.
inline double Window(const double* cum, double u, double half, int rows_in_band, double kw, int w) {
  const int x0 = std::max(0, static_cast<int>(std::ceil((u - half) / kw - 0.5)));
  const int x1 = std::min(w - 1, static_cast<int>(std::floor((u + half) / kw - 0.5)));
  if (x1 < x0) return -1.0;
  return (cum[x1 + 1] - cum[x0]) / ((x1 - x0 + 1) * rows_in_band);
}

}  // namespace

std::vector<StraightSearch::Band> StraightSearch::SplitIntoBands(const cv::Mat& image, int n_bands,
                                                                 double scale, double v_bottom,
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

RowDetection StraightSearch::Detect(const cv::Mat& plant) {
  RowDetection out;
  out.width_px = plant.cols;
  out.height_px = plant.rows;
  if (!Prepare(plant, out)) return out;

  // 1. Candidate geometries: the sharpest Hough cells, the streaks' best,
  // and the sharpest leans of every convergence.
  const std::vector<double> sharpness = HoughSharpness();
  std::vector<int> order(sharpness.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return sharpness[static_cast<size_t>(a)] > sharpness[static_cast<size_t>(b)];
  });
  std::vector<int> chosen = DistinctCells(order, o_.candidates);
  support_max_ = 0.0;
  locked_ = false;
  if (use_orientation_) AddStreakCandidates(order, chosen);
  AddLeanPeaks(sharpness, chosen);

  // 2.–3. The row comb on each candidate, refined.
  const Hypothesis best = BestRefined(CombHypotheses(chosen));
  if (best.score < 0.0) {
    out.reason = "no rows: no comb of evenly spaced rows with plant matter along them";
    return out;
  }
  const Geometry geo = GeometryAt(best.g, best.lean);
  Fit searched{geo, best.d, best.sc, FindRows(geo, best.d, best.sc)};
  if (!searched.found.adjacent) {
    out.reason = "no rows: the refined comb has no two neighbouring rows with plant matter";
    return out;
  }
  // 4.–5.
  Finish(BestFit(searched), out);
  return out;
}

bool StraightSearch::Prepare(const cv::Mat& plant, RowDetection& out) {
  W_ = plant.cols;
  H_ = plant.rows;
  v_bottom_ = H_ - 0.5;
  cv::Mat unit;
  if (plant.type() == CV_8UC1) {
    cv::Mat binary;
    cv::compare(plant, 0, binary, cv::CMP_GT);
    binary.convertTo(unit, CV_32F, 1.0 / 255.0);
  } else {
    unit = plant;
  }
  const double plant_fraction = cv::mean(unit)[0];
  if (plant_fraction < o_.min_plant_fraction) {
    out.reason = "no plant matter (" + std::to_string(plant_fraction * 100.0) + "% of the image)";
    return false;
  }
  const auto resized = [&](int width, cv::Mat& dst) {
    if (width >= plant.cols) {
      unit.copyTo(dst);
      return;
    }
    const int height = std::max(4, static_cast<int>(std::lround(H_ * width / W_)));
    cv::resize(unit, dst, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  };
  resized(o_.work_width_px, work_);
  resized(o_.fit_width_px, fit_);
  w_ = work_.cols;
  h_ = work_.rows;
  kw_ = W_ / w_;
  kh_ = H_ / h_;
  use_orientation_ = o_.orientation_floor > 0.0;
  if (use_orientation_) orientation_.Build(work_, kw_, kh_, v_bottom_);

  n_bands_ = std::min(o_.strips, h_);
  bands_ = SplitIntoBands(work_, n_bands_, kh_, v_bottom_, profiles_);
  total_mass_ = 0.0;
  for (const float m : profiles_) total_mass_ += static_cast<double>(m);
  // Running sums of the band profiles: the plant matter in a window of
  // columns in constant time.
  cumulative_.assign(static_cast<size_t>(n_bands_) * (w_ + 1), 0.0);
  for (int k = 0; k < n_bands_; ++k) {
    const float* p = &profiles_[static_cast<size_t>(k) * w_];
    double* cum = &cumulative_[static_cast<size_t>(k) * (w_ + 1)];
    for (int x = 0; x < w_; ++x) cum[x + 1] = cum[x] + static_cast<double>(p[x]);
  }
  n_bins_ = 3 * w_;
  s0_ = -W_ + 0.5 * kw_;
  d_min_ = o_.min_spacing_fraction * W_;
  d_max_ = o_.max_spacing_fraction * W_;
  min_spacing_ = std::max(o_.min_visible_spacing_px, 2.0 * kw_);
  ng_ = o_.convergence_steps;
  nl_ = o_.lean_steps;
  g_step_ = o_.max_convergence / H_ / (ng_ - 1);
  l_step_ = nl_ > 1 ? 2.0 * o_.max_lean / (nl_ - 1) : 0.0;
  return true;
}

StraightSearch::Geometry StraightSearch::GeometryAt(double g, double lean_at_centre) const {
  return Geometry{g, lean_at_centre + g * 0.5 * W_};
}

StraightSearch::Geometry StraightSearch::CellGeometry(int index) const {
  return GeometryAt((index / nl_) * g_step_, -o_.max_lean + (index % nl_) * l_step_);
}

// The s histogram over [−W, 2W) for one geometry, from the bands with
// Δv ≤ max_dv whose rows are not too compressed. Each column's mass is
// spread over its stretched width so that stretching adds no holes.
void StraightSearch::BuildHistogram(const Geometry& geo, double max_dv) {
  histogram_.assign(static_cast<size_t>(n_bins_), 0.0);
  for (int k = 0; k < n_bands_; ++k) {
    const Band& b = bands_[static_cast<size_t>(k)];
    const double shrink = 1.0 - geo.g * b.dv;
    if (shrink < kMinShrink || b.dv > max_dv) continue;
    const double m = 1.0 / shrink;
    const int pieces = std::clamp(static_cast<int>(std::ceil(m - 1e-9)), 1, kMaxPieces);
    const float* p = &profiles_[static_cast<size_t>(k) * w_];
    // Bin coordinate t = (s − s0)/kw of column position x (in columns):
    // t = x·m + offset.
    const double offset = (-geo.c * b.dv * m - s0_) / kw_;
    const double last_t = n_bins_ - 1.0;
    double* bins = histogram_.data();
    // The pieces' offsets within a column, and the share of each, out of
    // the loop (a division per piece cost a fifth of the search); the
    // loop over the pieces unrolled for each count.
    const double share = 1.0 / pieces;
    double piece_t[kMaxPieces];
    for (int q = 0; q < pieces; ++q) piece_t[q] = (q + 0.5) * share * m + offset;
    switch (pieces) {
      case 1: SplatColumns<1>(p, w_, m, share, piece_t, last_t, bins); break;
      case 2: SplatColumns<2>(p, w_, m, share, piece_t, last_t, bins); break;
      case 3: SplatColumns<3>(p, w_, m, share, piece_t, last_t, bins); break;
      default: SplatColumns<kMaxPieces>(p, w_, m, share, piece_t, last_t, bins); break;
    }
  }
}

// A row is occupied in a band when its window holds clearly more plant
// matter than the windows half-way between the rows.
StraightSearch::Rows StraightSearch::FindRows(const Geometry& geo, double d, double sc) const {
  const int n_lo = static_cast<int>(std::ceil((-W_ - sc) / d));
  const int n_hi = static_cast<int>(std::floor((2.0 * W_ - sc) / d));
  if (n_hi < n_lo || n_hi - n_lo > 200) {
    Rows none;
    none.top_v = v_bottom_;
    return none;
  }
  const size_t n_rows = static_cast<size_t>(n_hi - n_lo + 1);
  const int k_first = FirstContrastBand(geo, d, sc, n_lo, n_rows);
  return SelectRows(TallyBands(geo, d, sc, n_lo, n_rows, k_first), geo, d, sc, n_lo);
}

// Towards the vanishing point the rows merge into one canopy: the bands at
// the top where the teeth hold no more plant matter than the gaps between
// them are left out (of occupancy and contrast alike), as a geometry that
// cannot use them at all leaves them out. The first band below them.
int StraightSearch::FirstContrastBand(const Geometry& geo, double d, double sc, int n_lo,
                                      size_t n_rows) const {
  const double hw = o_.row_halfwidth_fraction;
  int k_first = 0;
  for (; k_first < n_bands_; ++k_first) {
    const Band& b = bands_[static_cast<size_t>(k_first)];
    const double shrink = 1.0 - geo.g * b.dv;
    if (shrink < kMinShrink || d * shrink < min_spacing_) continue;
    const double* p = &cumulative_[static_cast<size_t>(k_first) * (w_ + 1)];
    const double half = std::max(0.5 * kw_, hw * d * shrink);
    double on = 0.0, between = 0.0;
    for (size_t r = 0; r < n_rows; ++r) {
      const double u = (sc + (n_lo + static_cast<int>(r)) * d) * shrink + geo.c * b.dv;
      const double m = u + 0.5 * d * shrink;
      if (u >= 0.0 && u <= W_) on += std::max(0.0, Window(p, u, half, b.rows, kw_, w_));
      if (m >= 0.0 && m <= W_) between += std::max(0.0, Window(p, m, half, b.rows, kw_, w_));
    }
    if (on > 0.0 && 1.0 - between / on >= o_.min_contrast) break;
  }
  return k_first;
}

StraightSearch::Tallies StraightSearch::TallyBands(const Geometry& geo, double d, double sc,
                                                   int n_lo, size_t n_rows, int k_first) const {
  const double hw = o_.row_halfwidth_fraction;
  Tallies t{std::vector<int>(n_rows, 0),     std::vector<int>(n_rows, 0),
            std::vector<int>(n_rows, -1),    std::vector<double>(n_rows, 0.0),
            std::vector<double>(n_rows, 0.0), std::vector<int>(n_rows, 0),
            std::vector<int>(n_rows, 0)};
  std::vector<double> density(n_rows);
  for (int k = k_first; k < n_bands_; ++k) {
    const Band& b = bands_[static_cast<size_t>(k)];
    const double shrink = 1.0 - geo.g * b.dv;
    if (shrink < kMinShrink || d * shrink < min_spacing_) continue;
    const double* p = &cumulative_[static_cast<size_t>(k) * (w_ + 1)];
    const double half = std::max(0.5 * kw_, hw * d * shrink);
    double background = 0.0;
    int n_background = 0;
    for (size_t r = 0; r < n_rows; ++r) {
      const int n = n_lo + static_cast<int>(r);
      const double u = (sc + n * d) * shrink + geo.c * b.dv;
      density[r] = (u >= 0.0 && u <= W_) ? Window(p, u, half, b.rows, kw_, w_) : -1.0;
      const double m = u + 0.5 * d * shrink;
      if (m < 0.0 || m > W_) continue;  // the gap beyond this row is out of the image
      const double between = Window(p, m, half, b.rows, kw_, w_);
      if (between >= 0.0) {
        background += between;
        ++n_background;
        t.between_sum[r] += between;
        ++t.between_count[r];
      }
    }
    background = n_background > 0 ? background / n_background : 0.0;
    const double level = std::max(0.02, 1.3 * background);
    for (size_t r = 0; r < n_rows; ++r) {
      if (density[r] < 0.0) continue;
      ++t.in_image[r];
      t.on_sum[r] += density[r];
      ++t.on_count[r];
      if (density[r] >= level) {
        ++t.occupied[r];
        t.highest[r] = t.highest[r] < 0 ? k : std::min(t.highest[r], k);
      }
    }
  }
  return t;
}

// Rows with plant matter along most of their length; between two of them,
// a tooth with some (a row with many plants missing) is a row too. A comb
// of half the rows' spacing keeps only every other tooth.
StraightSearch::Rows StraightSearch::SelectRows(const Tallies& t, const Geometry& geo, double d,
                                                double sc, int n_lo) const {
  Rows result;
  result.top_v = v_bottom_;
  const size_t n_rows = t.in_image.size();
  std::vector<double> occupancy(n_rows, -1.0);
  int first = -1, last = -1;
  for (size_t r = 0; r < n_rows; ++r) {
    if (t.in_image[r] < 2) continue;
    occupancy[r] = static_cast<double>(t.occupied[r]) / t.in_image[r];
    if (occupancy[r] < o_.min_row_occupancy) continue;
    if (first < 0) first = static_cast<int>(r);
    last = static_cast<int>(r);
  }
  int top_band = n_bands_;
  int previous = n_lo - 2;
  for (int r = std::max(first, 0); first >= 0 && r <= last; ++r) {
    const double occ = occupancy[static_cast<size_t>(r)];
    if (occ < o_.min_row_occupancy && occ < o_.min_gap_row_occupancy) continue;
    const int n = n_lo + r;
    if (n == previous + 1) result.adjacent = true;
    previous = n;
    result.rows.push_back({n, sc + n * d, occ});
    if (t.highest[static_cast<size_t>(r)] >= 0) {
      top_band = std::min(top_band, t.highest[static_cast<size_t>(r)]);
    }
  }
  if (result.rows.empty()) return result;
  if (last > first) {
    double on = 0.0, between = 0.0;
    int n_on = 0, n_between = 0;
    for (int r = first; r <= last; ++r) {
      on += t.on_sum[static_cast<size_t>(r)];
      n_on += t.on_count[static_cast<size_t>(r)];
      if (r < last) {
        between += t.between_sum[static_cast<size_t>(r)];
        n_between += t.between_count[static_cast<size_t>(r)];
      }
    }
    if (n_on > 0 && n_between > 0 && on > 0.0) {
      result.contrast = std::max(0.0, 1.0 - (between / n_between) / (on / n_on));
    }
  }
  double top = bands_[static_cast<size_t>(top_band)].v_top;
  if (geo.g > 0.0) top = std::max(top, v_bottom_ - (1.0 - min_spacing_ / d) / geo.g);
  result.top_v = std::clamp(top, 0.0, v_bottom_);
  return result;
}

// 1. Hough over (g, lean): how sharply the plant matter piles up in s
// (smoothed Σh²/(Σh)²), on the bands that every cell can use.
std::vector<double> StraightSearch::HoughSharpness() {
  std::vector<double> sharpness(static_cast<size_t>(ng_) * nl_, 0.0);
  for (int i = 0; i < ng_; ++i) {
    for (int j = 0; j < nl_; ++j) {
      BuildHistogram(GeometryAt(i * g_step_, -o_.max_lean + j * l_step_), H_);
      // The histogram smoothed by (¼, ½, ¼), zero beyond its ends; the
      // first and last bins apart so that the loop has no branches.
      const double* hist = histogram_.data();
      const int n = n_bins_;
      double sum = 0.0, sum2 = 0.0;
      const auto add = [&](double v) {
        sum += v;
        sum2 += v * v;
      };
      add(0.5 * hist[0] + 0.25 * (n > 1 ? hist[1] : 0.0));
      for (int b = 1; b + 1 < n; ++b) add(0.25 * hist[b - 1] + 0.5 * hist[b] + 0.25 * hist[b + 1]);
      if (n > 1) add(0.25 * hist[n - 2] + 0.5 * hist[n - 1]);
      sharpness[static_cast<size_t>(i) * nl_ + j] = sum > 0.0 ? sum2 / (sum * sum) : 0.0;
    }
  }
  return sharpness;
}

// The first `count` cells of `order` that are not next to one taken before.
std::vector<int> StraightSearch::DistinctCells(const std::vector<int>& order, int count) const {
  std::vector<int> taken;
  for (int index : order) {
    if (static_cast<int>(taken.size()) >= count) break;
    const bool near =
        std::any_of(taken.begin(), taken.end(), [&](int c) { return NearCells(c, index, nl_); });
    if (!near) taken.push_back(index);
  }
  return taken;
}

// The streaks' support over the same grid; its best cells are candidates
// too (a near-field plant can make a wrong geometry the sharpest).
void StraightSearch::AddStreakCandidates(const std::vector<int>& order, std::vector<int>& chosen) {
  std::vector<double> support(order.size(), 0.0);
  for (int i = 0; i < ng_; ++i) {
    for (int j = 0; j < nl_; ++j) {
      const Geometry geo = GeometryAt(i * g_step_, -o_.max_lean + j * l_step_);
      support[static_cast<size_t>(i) * nl_ + j] = orientation_.Support(geo.g, geo.c);
    }
  }
  std::vector<int> by_support(order);
  std::sort(by_support.begin(), by_support.end(), [&](int a, int b) {
    return support[static_cast<size_t>(a)] > support[static_cast<size_t>(b)];
  });
  support_max_ = support[static_cast<size_t>(by_support.front())];
  for (int index : DistinctCells(by_support, o_.orientation_candidates)) AddOnce(chosen, index);
  if (support_max_ > 0.0) LockStreaks(by_support.front());
}

// The streaks' own best geometry, refined off the grid by halving steps:
// the vanishing point the refit may keep (step 4).
void StraightSearch::LockStreaks(int best_support_index) {
  locked_ = true;
  lock_g_ = (best_support_index / nl_) * g_step_;
  lock_lean_ = -o_.max_lean + (best_support_index % nl_) * l_step_;
  double best_support = support_max_, sg = g_step_, sl = l_step_;
  for (int level = 0; level < 6; ++level) {
    sg *= 0.5;
    sl *= 0.5;
    double bg = lock_g_, bl = lock_lean_;
    for (int i = -1; i <= 1; ++i) {
      for (int j = -1; j <= 1; ++j) {
        const double g = std::max(0.0, lock_g_ + i * sg), l = lock_lean_ + j * sl;
        const Geometry geo = GeometryAt(g, l);
        const double e = orientation_.Support(geo.g, geo.c);
        if (e > best_support) best_support = e, bg = g, bl = l;
      }
    }
    lock_g_ = bg;
    lock_lean_ = bl;
  }
}

// Sharpness alone favours little convergence when wide rows merge far
// away; every convergence keeps its two sharpest leans that are local
// maxima along the lean axis as candidates too.
void StraightSearch::AddLeanPeaks(const std::vector<double>& sharpness,
                                  std::vector<int>& chosen) const {
  for (int i = 0; i < ng_; ++i) {
    const double* row = &sharpness[static_cast<size_t>(i) * nl_];
    int first = -1, second = -1;
    for (int j = 0; j < nl_; ++j) {
      const bool peak = (j == 0 || row[j] >= row[j - 1]) && (j + 1 == nl_ || row[j] > row[j + 1]);
      if (!peak) continue;
      if (first < 0 || row[j] > row[first]) {
        second = first;
        first = j;
      } else if (second < 0 || row[j] > row[second]) {
        second = j;
      }
    }
    for (const int j : {first, second}) {
      if (j >= 0) AddOnce(chosen, i * nl_ + j);
    }
  }
}

// Every score is scaled by the streaks' agreement with the geometry,
// relative to the best (row_detector.h, orientation_floor).
double StraightSearch::StreakFactor(const Geometry& geo) const {
  if (!use_orientation_) return 1.0;
  const double floor = o_.orientation_floor;
  return std::min(1.0, (orientation_.Support(geo.g, geo.c) + floor) / (support_max_ + floor));
}

// Rows agree in phase from band to band whatever their width; a comb
// forced onto scattered matter or onto the wrong geometry does not. The
// score is the comb's coherence times that agreement.
StraightSearch::BandComb StraightSearch::CombOnBands(const Geometry& geo, double d) const {
  std::complex<double> z_sum(0.0, 0.0);
  double z_abs = 0.0, mass = 0.0;
  for (int k = 0; k < n_bands_; ++k) {
    const Band& b = bands_[static_cast<size_t>(k)];
    const double shrink = 1.0 - geo.g * b.dv;
    if (shrink < kMinShrink || d * shrink < min_spacing_) continue;
    if (cumulative_[static_cast<size_t>(k) * (w_ + 1) + static_cast<size_t>(w_)] <= 0.0) continue;  // no plant matter
    const float* p = &profiles_[static_cast<size_t>(k) * w_];
    const double s_first = (0.5 * kw_ - geo.c * b.dv) / shrink;
    const double a0 = -2.0 * std::numbers::pi * s_first / d;
    const double da = -2.0 * std::numbers::pi * kw_ / (shrink * d);
    const Phasor ph = PhasorSum(std::span<const float>(p, static_cast<size_t>(w_)), a0, da);
    const double m = ph.mass;
    if (m <= 0.0) continue;
    const std::complex<double> z(ph.re, ph.im);
    z_sum += z;
    z_abs += std::sqrt(std::norm(z));  // |z| without hypot's care for overflow
    mass += m;
  }
  BandComb r;
  if (mass <= 0.0 || z_abs <= 0.0) return r;
  // Coherence over all the image's plant matter, not only the bands this
  // geometry can use: a vanishing point placed low in the image (or a
  // narrow comb) drops the upper bands, and must not be rewarded for
  // explaining less of the image.
  r.coherence = std::abs(z_sum) / std::max(mass, total_mass_);
  r.alignment = std::abs(z_sum) / z_abs;
  double phase = -std::arg(z_sum) * d / (2.0 * std::numbers::pi);
  phase = std::fmod(phase, d);
  if (phase < 0.0) phase += d;
  r.phase = phase;
  return r;
}

// A hypothesis's score: the comb's score × its rows' occupancy × their
// contrast × n/(n + 1) × the streaks' agreement; false when the comb is at
// or below `floor` or has no two neighbouring rows.
bool StraightSearch::ScoreOf(const Geometry& geo, double period, double floor, Hypothesis& hyp,
                             size_t& n_rows) const {
  const BandComb bc = CombOnBands(geo, period);
  if (bc.score() <= floor) return false;
  const Rows rows = FindRows(geo, period, bc.phase);
  if (!rows.adjacent) return false;
  hyp.sc = bc.phase;
  hyp.score = bc.score() * MeanOccupancy(rows.rows) * rows.contrast * RowCountFactor(rows.rows) *
              StreakFactor(geo);
  n_rows = rows.rows.size();
  return true;
}

// 2. The row comb on each candidate: the best period whose rows are really
// there (two neighbouring rows with plant matter along them). Hypotheses
// are kept per row count: a comb of twice the spacing (two rows, every
// other row sparse) and the true comb (more rows, but a coarse period grid
// drifts in phase across them) are both refined before they are compared.
std::vector<StraightSearch::Hypothesis> StraightSearch::CombHypotheses(
    const std::vector<int>& chosen) {
  std::vector<Hypothesis> by_count(12);
  double best_start = -1.0;
  for (int index : chosen) {
    const double g = (index / nl_) * g_step_;
    const double lean = -o_.max_lean + (index % nl_) * l_step_;
    const Geometry geo = GeometryAt(g, lean);
    BuildHistogram(geo, H_);
    std::vector<double> periods;
    for (const CombFit& fit :
         BestCombs(histogram_, s0_, kw_, d_min_, d_max_, 2.0 * o_.spacing_step, 3)) {
      // A comb of twice the rows' spacing can fit rows too (every other
      // tooth empty, or two rows between teeth); its half is tried as well.
      periods.push_back(fit.period);
      if (fit.period / 2.0 >= d_min_) periods.push_back(fit.period / 2.0);
    }
    for (const double period : periods) {
      Hypothesis hyp{g, lean, period, 0.0, -1.0};
      size_t n_rows = 0;
      // A comb far below the best so far will not win after refinement.
      if (!ScoreOf(geo, period, o_.prune_fraction * best_start, hyp, n_rows)) continue;
      best_start = std::max(best_start, hyp.score);
      Hypothesis& slot = by_count[std::min(n_rows, by_count.size() - 1)];
      if (hyp.score > slot.score) slot = hyp;
    }
  }
  return by_count;
}

// 3. Local search on (g, lean, d) by the same score from one hypothesis:
// the comb (cheap) on the 27 neighbours, the rows (dearer) only on the few
// whose comb could still beat the current best; steps halve per level.
StraightSearch::Hypothesis StraightSearch::Refine(const Hypothesis& start) const {
  struct Neighbour {
    Geometry geo;
    double g, lean, d, comb;
  };
  Hypothesis local = start;
  double step_g = g_step_, step_l = l_step_, step_d = 2.0 * o_.spacing_step;
  for (int level = 0; level < 4; ++level) {
    step_g *= 0.5;
    step_l *= 0.5;
    const Hypothesis centre = local;
    std::vector<Neighbour> neighbours;
    neighbours.reserve(27);
    for (int i = -1; i <= 1; ++i) {
      for (int j = -1; j <= 1; ++j) {
        const double g = std::max(0.0, centre.g + i * step_g);
        const double lean = centre.lean + j * step_l;
        for (int k = -1; k <= 1; ++k) {
          const double d = centre.d * (1.0 + k * step_d);
          const Geometry geo_n = GeometryAt(g, lean);
          const double comb = CombOnBands(geo_n, d).score();
          if (comb > local.score) neighbours.push_back({geo_n, g, lean, d, comb});
        }
      }
    }
    const size_t keep = std::min(neighbours.size(), static_cast<size_t>(o_.refine_row_checks));
    std::partial_sort(neighbours.begin(), neighbours.begin() + static_cast<std::ptrdiff_t>(keep),
                      neighbours.end(),
                      [](const Neighbour& a, const Neighbour& b) { return a.comb > b.comb; });
    for (size_t q = 0; q < keep; ++q) {
      const Neighbour& nb = neighbours[q];
      Hypothesis hyp{nb.g, nb.lean, nb.d, 0.0, -1.0};
      size_t n_rows = 0;
      if (!ScoreOf(nb.geo, nb.d, local.score, hyp, n_rows)) continue;
      if (hyp.score > local.score) local = hyp;
    }
    step_d *= 0.5;
  }
  return local;
}

// Each of the best row counts' best hypothesis refined; the best of them.
StraightSearch::Hypothesis StraightSearch::BestRefined(std::vector<Hypothesis> by_count) const {
  std::sort(by_count.begin(), by_count.end(),
            [](const Hypothesis& a, const Hypothesis& b) { return a.score > b.score; });
  by_count.resize(std::min(by_count.size(), static_cast<size_t>(o_.refined_hypotheses)));
  Hypothesis best;
  for (const Hypothesis& start : by_count) {
    if (start.score < 0.0) continue;
    const Hypothesis local = Refine(start);
    if (local.score > best.score) best = local;
  }
  return best;
}

}  // namespace plantscale::rows
