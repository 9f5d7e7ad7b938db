#include "engine/sim/field.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/common/rng.h"

namespace plantscale::sim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

enum Stream : uint64_t { kDrift = 1, kCrops = 2, kWeeds = 3, kStones = 4 };

template <typename T>
std::pair<size_t, size_t> Between(const std::vector<T>& items, double y0, double y1) {
  const auto lo = std::lower_bound(items.begin(), items.end(), y0,
                                   [](const T& a, double y) { return a.position_m.y() < y; });
  const auto hi = std::upper_bound(lo, items.end(), y1,
                                   [](double y, const T& a) { return y < a.position_m.y(); });
  return {static_cast<size_t>(lo - items.begin()), static_cast<size_t>(hi - items.begin())};
}

}  // namespace

OptionErrors FieldOptions::Validate() const {
  OptionErrors e;
  if (rows < 1 || rows > 15 || rows % 2 == 0) e.push_back({"rows", "must be odd, 1..15"});
  RequirePositive(e, "row_spacing_m", row_spacing_m);
  RequirePositive(e, "plant_spacing_m", plant_spacing_m);
  RequireNonNegative(e, "nominal_row_spacing_m", nominal_row_spacing_m);
  RequireNonNegative(e, "nominal_plant_spacing_m", nominal_plant_spacing_m);
  RequireInRange(e, "spacing_drift_fraction", spacing_drift_fraction, 0.0, 0.2);
  RequirePositive(e, "spacing_drift_wavelength_m", spacing_drift_wavelength_m);
  RequireNonNegative(e, "planting_jitter_m", planting_jitter_m);
  RequireInRange(e, "missing_plant_fraction", missing_plant_fraction, 0.0, 0.9);
  RequirePositive(e, "crop_radius_m", crop_radius_m);
  RequireInRange(e, "crop_radius_sd_fraction", crop_radius_sd_fraction, 0.0, 0.5);
  RequireInRange(e, "crop_height_ratio", crop_height_ratio, 0.0, 3.0);
  RequireNonNegative(e, "crop_lean_sd_m", crop_lean_sd_m);
  if (crop_lobes < 0 || crop_lobes > 16) e.push_back({"crop_lobes", "must be in [0, 16]"});
  RequireInRange(e, "crop_lobe_depth", crop_lobe_depth, 0.0, 0.9);
  RequireInRange(e, "fractured_fraction", fractured_fraction, 0.0, 1.0);
  RequireNonNegative(e, "weed_density_per_m2", weed_density_per_m2);
  RequirePositive(e, "weed_radius_median_m", weed_radius_median_m);
  RequireNonNegative(e, "weed_radius_log_sd", weed_radius_log_sd);
  RequirePositive(e, "weed_max_radius_m", weed_max_radius_m);
  RequireInRange(e, "weed_in_row_fraction", weed_in_row_fraction, 0.0, 1.0);
  RequireInRange(e, "weed_height_ratio", weed_height_ratio, 0.0, 3.0);
  RequireNonNegative(e, "stone_density_per_m2", stone_density_per_m2);
  RequirePositive(e, "stone_size_median_m", stone_size_median_m);
  RequireInRange(e, "plant_brightness_sd", plant_brightness_sd, 0.0, 0.5);
  RequireNonNegative(e, "bed_margin_m", bed_margin_m);
  return e;
}

Field::Field(const FieldOptions& options, double y_begin_m, double y_end_m, uint64_t seed)
    : options_(options) {
  ThrowIfInvalid("field", options.Validate());
  Rng drift = Rng::Derived(seed, kDrift);
  drift_phase_r_ = drift.Uniform(0.0, kTwoPi);
  drift_phase_l_ = drift.Uniform(0.0, kTwoPi);
  // Plant lines: l̄ drifts slowly, so lines are laid out by integrating it.
  for (double y = y_begin_m; y <= y_end_m; y += PlantSpacingAt(y)) line_y_.push_back(y);
  PlantCrops(seed);
  SowWeeds(seed, y_begin_m, y_end_m);
  ScatterStones(seed, y_begin_m, y_end_m);
  const auto by_y = [](const auto& a, const auto& b) {
    return a.position_m.y() < b.position_m.y();
  };
  std::stable_sort(plants_.begin(), plants_.end(), by_y);
  std::stable_sort(stones_.begin(), stones_.end(), by_y);
  for (size_t i = 0; i < plants_.size(); ++i) plants_[i].id = static_cast<int>(i);
  for (const Plant& p : plants_) {
    max_radius_ = std::max(max_radius_, p.radius_m + p.lean_m.norm());
    max_height_ = std::max(max_height_, p.height_m);
  }
}

double Field::RowSpacingAt(double y_m) const {
  const FieldOptions& o = options_;
  return o.row_spacing_m *
         (1.0 + o.spacing_drift_fraction *
                    std::sin(kTwoPi * y_m / (1.7 * o.spacing_drift_wavelength_m) + drift_phase_r_));
}

double Field::PlantSpacingAt(double y_m) const {
  const FieldOptions& o = options_;
  return o.plant_spacing_m *
         (1.0 + o.spacing_drift_fraction *
                    std::sin(kTwoPi * y_m / o.spacing_drift_wavelength_m + drift_phase_l_));
}

double Field::HalfWidth() const {
  return 0.5 * (options_.rows - 1) * options_.row_spacing_m + options_.bed_margin_m;
}

void Field::PlantCrops(uint64_t seed) {
  const FieldOptions& o = options_;
  Rng rng = Rng::Derived(seed, kCrops);
  const int half = o.rows / 2;
  for (size_t line = 0; line < line_y_.size(); ++line) {
    for (int n = -half; n <= half; ++n) {
      Plant p;  // draw every random number even for missing plants: stable layouts
      p.cls = PlantClass::kCrop;
      const double y = line_y_[line];
      p.position_m = {RowX(n, y) + rng.Normal(0.0, o.planting_jitter_m),
                      y + rng.Normal(0.0, o.planting_jitter_m)};
      p.radius_m = std::max(0.2 * o.crop_radius_m,
                            o.crop_radius_m * (1.0 + rng.Normal(0.0, o.crop_radius_sd_fraction)));
      p.height_m = o.crop_height_ratio * p.radius_m;
      p.lean_m = {rng.Normal(0.0, o.crop_lean_sd_m), rng.Normal(0.0, o.crop_lean_sd_m)};
      p.lobes = o.crop_lobes;
      p.lobe_depth = o.crop_lobe_depth;
      p.lobe_phase_rad = rng.Uniform(0.0, kTwoPi);
      p.brightness = 1.0 + rng.Normal(0.0, o.plant_brightness_sd);
      const bool fractured = rng.Bernoulli(o.fractured_fraction);
      const int lobe = static_cast<int>(rng.Uniform(0.0, std::max(1, p.lobes)));
      p.fractured_lobe = fractured && p.lobes > 0 ? lobe : -1;
      p.row = n;
      p.line = static_cast<int>(line);
      if (rng.Bernoulli(o.missing_plant_fraction)) continue;
      plants_.push_back(p);
      ++crop_count_;
    }
  }
}

void Field::SowWeeds(uint64_t seed, double y_begin, double y_end) {
  const FieldOptions& o = options_;
  Rng rng = Rng::Derived(seed, kWeeds);
  const double half_width = HalfWidth();
  const int count = rng.Poisson(o.weed_density_per_m2 * 2.0 * half_width * (y_end - y_begin));
  const int half = o.rows / 2;
  for (int i = 0; i < count; ++i) {
    Plant p;
    p.cls = PlantClass::kWeed;
    const double y = rng.Uniform(y_begin, y_end);
    double x = rng.Uniform(-half_width, half_width);
    if (rng.Bernoulli(o.weed_in_row_fraction)) {
      const int n = static_cast<int>(std::lround(rng.Uniform(-half - 0.499, half + 0.499)));
      x = RowX(n, y) + rng.Normal(0.0, 0.04);
    }
    p.position_m = {x, y};
    p.radius_m =
        std::min(o.weed_max_radius_m, rng.LogNormal(o.weed_radius_median_m, o.weed_radius_log_sd));
    p.height_m = o.weed_height_ratio * p.radius_m;
    p.lobes = 2 + static_cast<int>(rng.Uniform(0.0, 4.0));
    p.lobe_depth = rng.Uniform(0.2, 0.6);
    p.lobe_phase_rad = rng.Uniform(0.0, kTwoPi);
    p.brightness = 0.95 + rng.Normal(0.0, o.plant_brightness_sd);
    p.row = std::clamp(static_cast<int>(std::lround(x / RowSpacingAt(y))), -half, half);
    plants_.push_back(p);
  }
}

void Field::ScatterStones(uint64_t seed, double y_begin, double y_end) {
  const FieldOptions& o = options_;
  Rng rng = Rng::Derived(seed, kStones);
  const double half_width = HalfWidth();
  const int count = rng.Poisson(o.stone_density_per_m2 * 2.0 * half_width * (y_end - y_begin));
  for (int i = 0; i < count; ++i) {
    Stone s;
    s.position_m = {rng.Uniform(-half_width, half_width), rng.Uniform(y_begin, y_end)};
    s.semi_major_m = rng.LogNormal(o.stone_size_median_m, 0.4);
    s.semi_minor_m = s.semi_major_m * rng.Uniform(0.5, 0.95);
    s.angle_rad = rng.Uniform(0.0, std::numbers::pi);
    s.brightness = rng.Uniform(0.8, 1.2);
    stones_.push_back(s);
  }
}

std::pair<size_t, size_t> Field::PlantsBetween(double y0, double y1) const {
  return Between(plants_, y0, y1);
}

std::pair<size_t, size_t> Field::StonesBetween(double y0, double y1) const {
  return Between(stones_, y0, y1);
}

}  // namespace plantscale::sim
