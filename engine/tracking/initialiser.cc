#include "engine/tracking/initialiser.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "engine/rows/comb.h"

namespace plantscale::tracking {

using geometry::GridState;

OptionErrors InitialiserOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "max_bearing_rad", max_bearing_rad, 0.0, 1.2, false);
  RequirePositive(e, "bearing_step_rad", bearing_step_rad);
  RequirePositive(e, "offset_step_m", offset_step_m);
  RequireInRange(e, "max_offset_fraction", max_offset_fraction, 0.0, 5.0, false);
  RequireInRange(e, "row_halfwidth_fraction", row_halfwidth_fraction, 0.0, 0.5, false);
  RequirePositive(e, "max_range_m", max_range_m);
  RequirePositive(e, "weight_cap_m2", weight_cap_m2);
  RequireInRange(e, "min_row_support", min_row_support, 0.0, 1.0);
  RequireInRange(e, "min_phase_coherence", min_phase_coherence, 0.0, 1.0);
  if (min_features < 2) e.push_back({"min_features", "must be >= 2"});
  if (confirm_frames < 1) e.push_back({"confirm_frames", "must be >= 1"});
  RequireInRange(e, "band_min_elongation", band_min_elongation, 1.0, 1e3);
  RequirePositive(e, "band_min_length_m", band_min_length_m);
  RequireInRange(e, "closed_canopy_fraction", closed_canopy_fraction, 0.0, 1.0);
  RequireInRange(e, "band_bearing_window_rad", band_bearing_window_rad, 0.0, 0.5, false);
  RequirePositive(e, "confirm_offset_m", confirm_offset_m);
  RequirePositive(e, "confirm_bearing_rad", confirm_bearing_rad);
  RequirePositive(e, "confirm_forward_m", confirm_forward_m);
  RequirePositive(e, "offset_sd_m", offset_sd_m);
  RequirePositive(e, "bearing_sd_rad", bearing_sd_rad);
  RequirePositive(e, "forward_sd_m", forward_sd_m);
  return e;
}

namespace {

bool InRange(const Feature& f, const InitialiserOptions& o) {
  return std::isfinite(f.ground_m.x()) && std::isfinite(f.ground_m.y()) && f.ground_m.y() > 0.0 &&
         f.ground_m.y() <= o.max_range_m && f.area_m2 > 0.0;
}

bool Usable(const Feature& f, const InitialiserOptions& o) { return !f.clipped && InRange(f, o); }

// Plants touching along a row, one blob (cut by the border or not).
bool Band(const Feature& f, const InitialiserOptions& o) {
  return InRange(f, o) && f.elongation >= o.band_min_elongation &&
         f.axis_m.norm() >= o.band_min_length_m && std::abs(f.axis_m.y()) > 0.0;
}

// A band's bearing: its axis's angle from the forward axis, in (−π/2, π/2).
double BandBearing(const Feature& f) {
  const Eigen::Vector2d a = f.axis_m.y() < 0.0 ? Eigen::Vector2d(-f.axis_m) : f.axis_m;
  return std::atan2(a.x(), a.y());
}

double Weight(const Feature& f, const InitialiserOptions& o) {
  return std::min(f.area_m2, o.weight_cap_m2);
}

// Lateral distance of a feature from row n of the fitted grid, and its
// position along the rows (grid coordinates, eqs. 2.1–2.2 inverted).
Eigen::Vector2d GridCoordinates(const Eigen::Vector2d& g, double offset_m, double bearing_rad) {
  const double c = std::cos(bearing_rad);
  const double s = std::sin(bearing_rad);
  const double dx = g.x() - offset_m;
  return {c * dx - s * g.y(), s * dx + c * g.y()};
}

// A usable feature within the half-width of one of the fitted rows: its row
// n and its position along the rows.
struct OnRow {
  int n = 0;
  double along_m = 0.0;
};
// Which features a step takes: those seen whole (the thesis's), or on a
// closed canopy the bands too (the rows) or the plants seen apart only
// (the phase: a band has none).
enum class Take { kWhole, kWholeAndBands, kApart };

bool Taken(const Feature& f, const InitialiserOptions& o, Take take) {
  switch (take) {
    case Take::kWhole: return Usable(f, o);
    case Take::kWholeAndBands: return Usable(f, o) || Band(f, o);
    case Take::kApart: return Usable(f, o) && !Band(f, o);
  }
  return false;
}

std::optional<OnRow> FeatureOnRow(const Feature& f, double offset_m, double bearing_rad, double r,
                                  int rows_each_side, const InitialiserOptions& o,
                                  Take take = Take::kWhole) {
  if (!Taken(f, o, take)) return std::nullopt;
  const Eigen::Vector2d g = GridCoordinates(f.ground_m, offset_m, bearing_rad);
  const double n = std::round(g.x() / r);
  if (std::abs(n) > rows_each_side || std::abs(g.x() - n * r) > o.row_halfwidth_fraction * r) {
    return std::nullopt;
  }
  return OnRow{static_cast<int>(n), g.y()};
}

// Bands' area-weighted bearing: a doubled-angle mean (an axis has no sign).
struct AxisMean {
  double c = 0.0, s = 0.0;
  void Add(const Feature& f) {
    const double psi2 = 2.0 * BandBearing(f);
    c += f.area_m2 * std::cos(psi2);
    s += f.area_m2 * std::sin(psi2);
  }
  bool empty() const { return c == 0.0 && s == 0.0; }
  double bearing_rad() const { return 0.5 * std::atan2(s, c); }
};

// The bands' share of the plant matter in range, and their bearing.
struct Bands {
  bool closed = false;
  double bearing_rad = 0.0;
};
Bands BandsOf(std::span<const Feature> features, const InitialiserOptions& o) {
  double band_area = 0.0, apart_area = 0.0;
  AxisMean axes;
  for (const Feature& f : features) {
    if (Band(f, o)) {
      band_area += f.area_m2;
      axes.Add(f);
    } else if (Usable(f, o)) {
      apart_area += f.area_m2;
    }
  }
  Bands b;
  b.closed = band_area > 0.0 && band_area > o.closed_canopy_fraction * (band_area + apart_area);
  if (b.closed) b.bearing_rad = axes.bearing_rad();
  return b;
}

}  // namespace

std::optional<RowFit> FitRowsOnGround(std::span<const Feature> features, double r,
                                      int rows_each_side, const InitialiserOptions& o) {
  const int n_bearing = 2 * static_cast<int>(std::round(o.max_bearing_rad / o.bearing_step_rad)) + 1;
  const double max_offset = o.max_offset_fraction * r;
  const int n_offset = 2 * static_cast<int>(std::ceil(max_offset / o.offset_step_m)) + 1;
  const int half_offset = n_offset / 2;
  const int half_bearing = n_bearing / 2;
  constexpr int kSpread = 3;  // triangular vote over ± this many offset bins
  const Bands bands = BandsOf(features, o);
  const Take take = bands.closed ? Take::kWholeAndBands : Take::kWhole;
  std::vector<double> acc(static_cast<size_t>(n_bearing) * n_offset, 0.0);
  double total = 0.0;
  int usable = 0;
  for (const Feature& f : features) {
    if (!Taken(f, o, take)) continue;
    ++usable;
    const double w = Weight(f, o);
    total += w;
    for (int b = 0; b < n_bearing; ++b) {
      const double psi = (b - half_bearing) * o.bearing_step_rad;
      if (bands.closed && std::abs(psi - bands.bearing_rad) > o.band_bearing_window_rad) continue;
      const double base = f.ground_m.x() - f.ground_m.y() * std::tan(psi);
      const double row_step = r / std::cos(psi);
      // The row comb shared with the image-plane detector (engine/rows).
      rows::VoteComb(std::span<double>(&acc[static_cast<size_t>(b) * n_offset],
                                       static_cast<size_t>(n_offset)),
                     half_offset, o.offset_step_m, base, row_step, rows_each_side, kSpread, w);
    }
  }
  if (usable < o.min_features || total <= 0.0) return std::nullopt;
  const auto best = std::max_element(acc.begin(), acc.end());
  // The bands' bearing outside the searched range: no bin was voted.
  if (bands.closed && !(*best > 0.0)) return std::nullopt;
  const size_t index = static_cast<size_t>(best - acc.begin());
  RowFit fit;
  fit.closed_canopy = bands.closed;
  fit.bearing_rad = (static_cast<int>(index / n_offset) - half_bearing) * o.bearing_step_rad;
  fit.offset_m = (static_cast<int>(index % n_offset) - half_offset) * o.offset_step_m;

  // Weighted least squares on the features near the winning rows:
  //   x − n r̄ / cos Ψ = t_x + y tan Ψ;
  // on a closed canopy Ψ is the bands' on those rows, and t_x alone is fitted.
  for (int iteration = 0; iteration < 3; ++iteration) {
    Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
    Eigen::Vector2d b = Eigen::Vector2d::Zero();
    double on_rows = 0.0;
    AxisMean axes;  // of the bands on the rows
    int count = 0;
    for (const Feature& f : features) {
      const auto on = FeatureOnRow(f, fit.offset_m, fit.bearing_rad, r, rows_each_side, o, take);
      if (!on) continue;
      const double w = Weight(f, o);
      const double lhs = f.ground_m.x() - on->n * r / std::cos(fit.bearing_rad);
      const Eigen::Vector2d row(1.0, f.ground_m.y());
      a += w * row * row.transpose();
      b += w * lhs * row;
      on_rows += w;
      ++count;
      if (bands.closed && Band(f, o)) axes.Add(f);
    }
    fit.support = on_rows / total;
    fit.features_on_rows = count;
    if (bands.closed) {
      if (count < 1 || !(on_rows > 0.0)) break;
      if (!axes.empty()) fit.bearing_rad = axes.bearing_rad();
      fit.offset_m = (b(0) - std::tan(fit.bearing_rad) * a(0, 1)) / a(0, 0);
      continue;
    }
    if (count < 2 || std::abs(a.determinant()) < 1e-12) break;
    const Eigen::Vector2d solution = a.ldlt().solve(b);
    fit.offset_m = solution(0);
    fit.bearing_rad = std::atan(solution(1));
  }
  return fit;
}

std::optional<LinePhase> PlantLinePhaseOnGround(std::span<const Feature> features,
                                                const RowFit& rows, double r, double l,
                                                int rows_each_side,
                                                const InitialiserOptions& o) {
  std::complex<double> sum(0.0, 0.0);
  double total = 0.0;
  for (const Feature& f : features) {
    const auto on = FeatureOnRow(f, rows.offset_m, rows.bearing_rad, r, rows_each_side, o,
                                 rows.closed_canopy ? Take::kApart : Take::kWhole);
    if (!on) continue;
    const double w = Weight(f, o);
    sum += w * std::polar(1.0, -2.0 * std::numbers::pi * on->along_m / l);
    total += w;
  }
  if (total <= 0.0) return std::nullopt;
  LinePhase phase;
  phase.coherence = std::abs(sum) / total;
  double y = -std::arg(sum) * l / (2.0 * std::numbers::pi);
  y = std::fmod(y, l);
  if (y < 0.0) y += l;
  phase.forward_m = y;
  return phase;
}

GridInitialiser::GridInitialiser(const InitialiserOptions& options, double row_spacing_m,
                                 double plant_spacing_m, int rows_each_side, double track_width_m)
    : options_(options),
      row_spacing_m_(row_spacing_m),
      plant_spacing_m_(plant_spacing_m),
      rows_each_side_(rows_each_side),
      track_width_m_(track_width_m) {
  ThrowIfInvalid("tracker initialiser", options.Validate());
}

void GridInitialiser::Reset() {
  previous_.reset();
  agreeing_ = 0;
}

InitialiserResult GridInitialiser::Offer(std::span<const Feature> features,
                                         const WheelIncrement& motion) {
  InitialiserResult result;
  const auto fail = [&](std::string reason) {
    Reset();
    result.reason = std::move(reason);
    return result;
  };
  const auto rows = FitRowsOnGround(features, row_spacing_m_, rows_each_side_, options_);
  if (!rows) return fail("too few features for the row Hough transform");
  if (rows->support < options_.min_row_support) {
    return fail("rows not found: " + std::to_string(static_cast<int>(rows->support * 100)) +
                "% of the plant matter on the fitted rows");
  }
  const auto phase = PlantLinePhaseOnGround(features, *rows, row_spacing_m_, plant_spacing_m_,
                                            rows_each_side_, options_);
  if (!phase || phase->coherence < options_.min_phase_coherence) {
    return fail("plant lines not found: phase coherence " +
                std::to_string(phase ? phase->coherence : 0.0));
  }
  GridState candidate;
  candidate.offset_m = rows->offset_m;
  candidate.bearing_rad = rows->bearing_rad;
  candidate.forward_m = phase->forward_m;
  candidate.row_spacing_m = row_spacing_m_;
  candidate.plant_spacing_m = plant_spacing_m_;

  bool agrees = false;
  const bool had_previous = previous_.has_value();
  if (had_previous) {
    const GridState predicted = PredictGridMotion(*previous_, motion, track_width_m_).state;
    double dy = std::remainder(candidate.forward_m - predicted.forward_m, plant_spacing_m_);
    agrees = std::abs(candidate.offset_m - predicted.offset_m) <= options_.confirm_offset_m &&
             std::abs(candidate.bearing_rad - predicted.bearing_rad) <=
                 options_.confirm_bearing_rad &&
             std::abs(dy) <= options_.confirm_forward_m;
  }
  agreeing_ = agrees ? agreeing_ + 1 : 1;
  previous_ = candidate;
  if (agreeing_ >= options_.confirm_frames) {
    result.state = candidate;
    return result;
  }
  result.reason = had_previous && !agrees
                      ? "candidate disagrees with the previous frame; waiting for the next"
                      : "candidate found, waiting for the next frame to agree";
  return result;
}

}  // namespace plantscale::tracking
