#include "engine/sim/field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace plantscale::sim {
namespace {

bool HasKey(const OptionErrors& errors, const std::string& key) {
  return std::any_of(errors.begin(), errors.end(),
                     [&](const OptionError& e) { return e.key == key; });
}

// Only crops: no weeds or stones.
FieldOptions CropsOnly() {
  FieldOptions o;
  o.weed_density_per_m2 = 0.0;
  o.stone_density_per_m2 = 0.0;
  return o;
}

TEST(Field, CropsSitOnTheGridWithinPlantingJitter) {
  FieldOptions o = CropsOnly();
  o.rows = 5;
  o.spacing_drift_fraction = 0.05;  // large, so that r̄(y) visibly matters
  o.spacing_drift_wavelength_m = 10.0;
  o.planting_jitter_m = 0.01;
  o.missing_plant_fraction = 0.0;
  const Field field(o, 0.0, 60.0, 3);
  ASSERT_EQ(field.crop_count(), static_cast<int>(field.line_y_m().size()) * 5);
  ASSERT_EQ(field.weed_count(), 0);
  ASSERT_TRUE(field.stones().empty());
  double sum2_x = 0.0;
  double sum2_y = 0.0;
  std::vector<int> per_row(5, 0);
  for (const Plant& p : field.plants()) {
    ASSERT_EQ(p.cls, PlantClass::kCrop);
    ASSERT_GE(p.line, 0);
    ASSERT_LT(static_cast<size_t>(p.line), field.line_y_m().size());
    ASSERT_GE(p.row, -2);
    ASSERT_LE(p.row, 2);
    ++per_row[static_cast<size_t>(p.row + 2)];
    const double line_y = field.line_y_m()[static_cast<size_t>(p.line)];
    const double ex = p.position_m.x() - field.RowX(p.row, line_y);
    const double ey = p.position_m.y() - line_y;
    // Five planting-jitter sds (p ≈ 6e-7 per coordinate).
    EXPECT_LE(std::abs(ex), 5.0 * 0.01) << "plant " << p.id;
    EXPECT_LE(std::abs(ey), 5.0 * 0.01) << "plant " << p.id;
    sum2_x += ex * ex;
    sum2_y += ey * ey;
  }
  // The jitter's sd itself: ≈ 670 plants, so the sample sd is within ≈ 3 %
  // (1 sd) of 10 mm; accept 15 %.
  const auto n = static_cast<double>(field.plants().size());
  EXPECT_NEAR(std::sqrt(sum2_x / n), 0.01, 0.0015);
  EXPECT_NEAR(std::sqrt(sum2_y / n), 0.01, 0.0015);
  for (int count : per_row) EXPECT_EQ(count, static_cast<int>(field.line_y_m().size()));
  // r̄ drifts by ±5 %; the drifted row x is not the nominal one.
  double min_r = 1e9;
  double max_r = -1e9;
  for (double y = 0.0; y <= 60.0; y += 0.1) {
    min_r = std::min(min_r, field.RowSpacingAt(y));
    max_r = std::max(max_r, field.RowSpacingAt(y));
  }
  EXPECT_GE(min_r, 0.475 * 0.95 - 1e-12);
  EXPECT_LE(max_r, 0.475 * 1.05 + 1e-12);
  EXPECT_GT(max_r - min_r, 0.475 * 0.09);  // nearly the full ±5 % swing over 60 m
}

TEST(Field, LineSpacingFollowsPlantSpacingAt) {
  FieldOptions o = CropsOnly();
  o.spacing_drift_fraction = 0.08;
  o.spacing_drift_wavelength_m = 7.0;
  const Field field(o, -3.0, 40.0, 12);
  const std::vector<double>& lines = field.line_y_m();
  ASSERT_GE(lines.size(), 90U);  // 43 m / 0.45 m ≈ 95 lines
  EXPECT_NEAR(lines.front(), -3.0, 1e-12);
  EXPECT_LE(lines.back(), 40.0);
  EXPECT_GT(lines.back() + field.PlantSpacingAt(lines.back()), 40.0);
  double min_l = 1e9;
  double max_l = -1e9;
  for (size_t i = 1; i < lines.size(); ++i) {
    const double spacing = lines[i] - lines[i - 1];
    EXPECT_NEAR(spacing, field.PlantSpacingAt(lines[i - 1]), 1e-9) << "line " << i;
    min_l = std::min(min_l, spacing);
    max_l = std::max(max_l, spacing);
  }
  // The drift stays within ±8 % of l̄ and spans most of it.
  EXPECT_GE(min_l, 0.45 * 0.92 - 1e-12);
  EXPECT_LE(max_l, 0.45 * 1.08 + 1e-12);
  EXPECT_GT(max_l - min_l, 0.45 * 0.12);
}

TEST(Field, WithoutDriftSpacingsAreConstant) {
  FieldOptions o = CropsOnly();
  o.spacing_drift_fraction = 0.0;
  const Field field(o, 0.0, 10.0, 4);
  for (double y : {-5.0, 0.0, 3.3, 9.9}) {
    EXPECT_NEAR(field.RowSpacingAt(y), 0.475, 1e-15);
    EXPECT_NEAR(field.PlantSpacingAt(y), 0.45, 1e-15);
  }
}

TEST(Field, MissingPlantFractionIsHonoured) {
  FieldOptions o = CropsOnly();
  o.rows = 5;
  o.missing_plant_fraction = 0.2;
  const Field field(o, 0.0, 400.0, 8);
  const auto planted = static_cast<double>(field.line_y_m().size() * 5);  // ≈ 4450 sites
  const double missing = 1.0 - field.crop_count() / planted;
  // Binomial sd = √(0.2·0.8/4450) ≈ 0.006; ±0.03 is five sds.
  EXPECT_NEAR(missing, 0.2, 0.03);
  EXPECT_EQ(static_cast<size_t>(field.crop_count()), field.plants().size());
  // Missing plants leave holes without shifting the others: (line, row) is unique.
  std::vector<std::vector<bool>> seen(field.line_y_m().size(), std::vector<bool>(5, false));
  for (const Plant& p : field.plants()) {
    auto&& slot = seen[static_cast<size_t>(p.line)][static_cast<size_t>(p.row + 2)];
    EXPECT_FALSE(slot) << "line " << p.line << " row " << p.row;
    slot = true;
  }
}

TEST(Field, WeedDensityPerSquareMetreIsHonoured) {
  FieldOptions o;
  o.rows = 3;
  o.weed_density_per_m2 = 6.0;
  o.weed_in_row_fraction = 0.0;
  o.stone_density_per_m2 = 3.0;
  o.missing_plant_fraction = 0.0;
  const Field field(o, 0.0, 100.0, 21);
  // The populated area: outer rows ± r̄ plus bed_margin_m on each side.
  const double half_width = 0.475 + 0.6;
  const double area = 2.0 * half_width * 100.0;  // 215 m²
  const double expected_weeds = 6.0 * area;      // 1290, Poisson sd ≈ 36
  EXPECT_NEAR(field.weed_count(), expected_weeds, 4.0 * std::sqrt(expected_weeds));
  const double expected_stones = 3.0 * area;  // 645, Poisson sd ≈ 25
  EXPECT_NEAR(static_cast<double>(field.stones().size()), expected_stones,
              4.0 * std::sqrt(expected_stones));
  int weeds = 0;
  for (const Plant& p : field.plants()) {
    if (p.cls != PlantClass::kWeed) continue;
    ++weeds;
    EXPECT_LE(std::abs(p.position_m.x()), half_width);
    EXPECT_GE(p.position_m.y(), 0.0);
    EXPECT_LE(p.position_m.y(), 100.0);
    EXPECT_EQ(p.line, -1);
    EXPECT_LE(p.radius_m, o.weed_max_radius_m);
    EXPECT_GT(p.radius_m, 0.0);
  }
  EXPECT_EQ(weeds, field.weed_count());
  // Uniform across the bed: as many weeds left of the centre row as right of it
  // (binomial sd ≈ 18 of ≈ 645 per side; accept 5 sds).
  const auto left = std::count_if(field.plants().begin(), field.plants().end(), [](const Plant& p) {
    return p.cls == PlantClass::kWeed && p.position_m.x() < 0.0;
  });
  EXPECT_NEAR(static_cast<double>(left), 0.5 * weeds, 5.0 * 0.5 * std::sqrt(weeds));
}

// Index of the row nearest to x among the bed's rows −half..half.
int NearestRow(const Field& field, const Plant& p) {
  const int half = field.options().rows / 2;
  int best = -half;
  for (int n = -half; n <= half; ++n) {
    if (std::abs(p.position_m.x() - field.RowX(n, p.position_m.y())) <
        std::abs(p.position_m.x() - field.RowX(best, p.position_m.y()))) {
      best = n;
    }
  }
  return best;
}

TEST(Field, WeedRowIsTheNearestRowInsideTheBed) {
  FieldOptions o;
  o.spacing_drift_fraction = 0.0;
  o.stone_density_per_m2 = 0.0;
  const Field field(o, 0.0, 30.0, 6);
  int checked = 0;
  for (const Plant& p : field.plants()) {
    // Between the outer rows and half a spacing beyond them.
    if (p.cls != PlantClass::kWeed || std::abs(p.position_m.x()) > 1.5 * 0.475) continue;
    EXPECT_EQ(p.row, NearestRow(field, p)) << "weed at x = " << p.position_m.x();
    ++checked;
  }
  EXPECT_GT(checked, 200);  // ≈ 6/m² · 1.425 m · 30 m ≈ 256 (+ in-row weeds)
}

// Weeds in the bed margin, beyond the outer rows, belong to the outer row
// (field.h: Plant::row of a weed is the nearest row), not to a row ±2 that
// a 3-row bed does not have.
TEST(Field, WeedRowInTheMarginIsTheOuterRow) {
  FieldOptions o;
  o.spacing_drift_fraction = 0.0;
  o.stone_density_per_m2 = 0.0;
  const Field field(o, 0.0, 30.0, 6);
  int checked = 0;
  for (const Plant& p : field.plants()) {
    if (p.cls != PlantClass::kWeed || std::abs(p.position_m.x()) <= 1.5 * 0.475) continue;
    EXPECT_EQ(p.row, NearestRow(field, p)) << "weed at x = " << p.position_m.x();
    ++checked;
  }
  EXPECT_GT(checked, 30);  // ≈ 6/m² · 0.725 m · 30 m ≈ 130
}

// Fraction of weeds within `distance` of the nearest (drifted) crop row.
double FractionNearRows(const Field& field, double distance) {
  int near = 0;
  int weeds = 0;
  const int half = field.options().rows / 2;
  for (const Plant& p : field.plants()) {
    if (p.cls != PlantClass::kWeed) continue;
    ++weeds;
    double best = 1e9;
    for (int n = -half; n <= half; ++n) {
      best = std::min(best, std::abs(p.position_m.x() - field.RowX(n, p.position_m.y())));
    }
    if (best <= distance) ++near;
  }
  return weeds > 0 ? static_cast<double>(near) / weeds : 0.0;
}

TEST(Field, WeedInRowFractionPlacesWeedsNearRows) {
  FieldOptions o;
  o.rows = 3;
  o.weed_density_per_m2 = 6.0;
  o.stone_density_per_m2 = 0.0;
  o.weed_in_row_fraction = 1.0;
  const Field in_row(o, 0.0, 60.0, 5);
  ASSERT_GT(in_row.weed_count(), 500);  // ≈ 770 expected
  // All in rows: within 10 cm of one (the in-row scatter is a few cm).
  EXPECT_GT(FractionNearRows(in_row, 0.1), 0.95);

  o.weed_in_row_fraction = 0.0;
  const Field scattered(o, 0.0, 60.0, 5);
  ASSERT_GT(scattered.weed_count(), 500);
  // Uniform over 2.15 m: bands of ±10 cm around 3 rows cover 0.6/2.15 = 28 %
  // (binomial sd ≈ 1.6 % for ≈ 770 weeds; accept ±6 %).
  EXPECT_NEAR(FractionNearRows(scattered, 0.1), 0.6 / 2.15, 0.06);

  o.weed_in_row_fraction = 0.5;
  const Field half(o, 0.0, 60.0, 5);
  // Half in rows (≈ 99 % of them within 10 cm), half scattered: ≈ 0.5·0.99 +
  // 0.5·0.28 = 0.63; accept ±6 %.
  EXPECT_NEAR(FractionNearRows(half, 0.1), 0.5 * 0.99 + 0.5 * 0.6 / 2.15, 0.06);
}

TEST(Field, PlantsAreSortedByYAndPlantsBetweenIsExact) {
  FieldOptions o;  // crops, weeds and stones
  const Field field(o, -2.0, 30.0, 77);
  const std::vector<Plant>& plants = field.plants();
  ASSERT_GT(plants.size(), 300U);
  for (size_t i = 0; i < plants.size(); ++i) {
    EXPECT_EQ(plants[i].id, static_cast<int>(i));
    if (i > 0) {
      EXPECT_LE(plants[i - 1].position_m.y(), plants[i].position_m.y()) << i;
    }
  }
  for (size_t i = 1; i < field.stones().size(); ++i) {
    EXPECT_LE(field.stones()[i - 1].position_m.y(), field.stones()[i].position_m.y()) << i;
  }
  // Ranges, including bounds equal to plant positions (inclusive both ends)
  // and ranges outside the field or empty.
  std::vector<std::pair<double, double>> ranges = {{-100.0, 100.0}, {-100.0, -50.0}, {50.0, 60.0},
                                                   {3.0, 2.0},      {0.0, 0.0},      {5.1, 7.9}};
  for (size_t i = 17; i + 40 < plants.size(); i += 97) {
    ranges.emplace_back(plants[i].position_m.y(), plants[i + 40].position_m.y());
  }
  for (const auto& [y0, y1] : ranges) {
    const auto [first, last] = field.PlantsBetween(y0, y1);
    size_t expected = 0;
    for (size_t i = 0; i < plants.size(); ++i) {
      const double y = plants[i].position_m.y();
      const bool inside = y >= y0 && y <= y1;
      if (inside) ++expected;
      EXPECT_EQ(inside, i >= first && i < last) << "plant " << i << " range " << y0 << ".." << y1;
    }
    EXPECT_EQ(last >= first ? last - first : 0, expected);
  }
  // A degenerate range at a plant's own y contains that plant.
  for (size_t i = 0; i < plants.size(); i += 13) {
    const double y = plants[i].position_m.y();
    const auto [first, last] = field.PlantsBetween(y, y);
    EXPECT_LE(first, i);
    EXPECT_GT(last, i);
  }
}

void ExpectSamePlant(const Plant& a, const Plant& b) {
  EXPECT_EQ(a.id, b.id);
  EXPECT_EQ(a.cls, b.cls);
  EXPECT_EQ(a.position_m, b.position_m);
  EXPECT_EQ(a.radius_m, b.radius_m);
  EXPECT_EQ(a.height_m, b.height_m);
  EXPECT_EQ(a.lean_m, b.lean_m);
  EXPECT_EQ(a.lobes, b.lobes);
  EXPECT_EQ(a.lobe_depth, b.lobe_depth);
  EXPECT_EQ(a.lobe_phase_rad, b.lobe_phase_rad);
  EXPECT_EQ(a.brightness, b.brightness);
  EXPECT_EQ(a.fractured_lobe, b.fractured_lobe);
  EXPECT_EQ(a.row, b.row);
  EXPECT_EQ(a.line, b.line);
}

TEST(Field, SameSeedSameFieldDifferentSeedDifferentField) {
  FieldOptions o;
  o.fractured_fraction = 0.3;
  const Field a(o, 0.0, 20.0, 1234);
  const Field b(o, 0.0, 20.0, 1234);
  const Field c(o, 0.0, 20.0, 1235);
  ASSERT_EQ(a.plants().size(), b.plants().size());
  for (size_t i = 0; i < a.plants().size(); ++i) ExpectSamePlant(a.plants()[i], b.plants()[i]);
  ASSERT_EQ(a.stones().size(), b.stones().size());
  for (size_t i = 0; i < a.stones().size(); ++i) {
    EXPECT_EQ(a.stones()[i].position_m, b.stones()[i].position_m);
    EXPECT_EQ(a.stones()[i].semi_major_m, b.stones()[i].semi_major_m);
  }
  EXPECT_EQ(a.line_y_m(), b.line_y_m());
  // Another seed: the first crops are placed differently (jitter sd 12 mm).
  const auto first_crop = [](const Field& f) {
    return *std::find_if(f.plants().begin(), f.plants().end(),
                         [](const Plant& p) { return p.cls == PlantClass::kCrop; });
  };
  EXPECT_GT((first_crop(a).position_m - first_crop(c).position_m).norm(), 1e-6);
  size_t same_positions = 0;
  const size_t n = std::min(a.plants().size(), c.plants().size());
  for (size_t i = 0; i < n; ++i) {
    if (a.plants()[i].position_m == c.plants()[i].position_m) ++same_positions;
  }
  EXPECT_EQ(same_positions, 0U);
}

TEST(Field, InvalidOptionsThrowNamingTheKey) {
  EXPECT_TRUE(FieldOptions{}.Validate().empty());
  {
    FieldOptions o;
    o.rows = 4;
    try {
      const Field field(o, 0.0, 10.0, 1);
      ADD_FAILURE() << "Field accepted rows = 4";
    } catch (const InvalidOptionsError& e) {
      EXPECT_TRUE(HasKey(e.errors(), "rows"));
      EXPECT_EQ(e.errors().size(), 1U);
      EXPECT_NE(std::string(e.what()).find("rows"), std::string::npos) << e.what();
    }
  }
  {
    FieldOptions o;
    o.plant_spacing_m = -0.45;
    o.row_spacing_m = -0.1;
    try {
      const Field field(o, 0.0, 10.0, 1);
      ADD_FAILURE() << "Field accepted negative spacings";
    } catch (const InvalidOptionsError& e) {
      EXPECT_TRUE(HasKey(e.errors(), "plant_spacing_m"));
      EXPECT_TRUE(HasKey(e.errors(), "row_spacing_m"));
      EXPECT_NE(std::string(e.what()).find("plant_spacing_m"), std::string::npos) << e.what();
    }
  }
  for (int rows : {0, 2, 17, -1}) {
    FieldOptions o;
    o.rows = rows;
    EXPECT_TRUE(HasKey(o.Validate(), "rows")) << rows;
  }
  FieldOptions o;
  o.missing_plant_fraction = 0.95;
  o.weed_density_per_m2 = -1.0;
  o.weed_in_row_fraction = 1.2;
  const OptionErrors errors = o.Validate();
  EXPECT_TRUE(HasKey(errors, "missing_plant_fraction"));
  EXPECT_TRUE(HasKey(errors, "weed_density_per_m2"));
  EXPECT_TRUE(HasKey(errors, "weed_in_row_fraction"));
  EXPECT_EQ(errors.size(), 3U);
}

}  // namespace
}  // namespace plantscale::sim
