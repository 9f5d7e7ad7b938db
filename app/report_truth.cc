#include "app/report_truth.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "app/config/config_loader.h"
#include "app/config/run_config.h"
#include "engine/sim/simulator.h"

namespace plantscale::app {
namespace {

// The shift (rows, metres along) that takes the report's bed frame (y from
// where the tracker started) to the simulated field's: the one under which
// most crop records have a true crop within 6 cm. The pattern of missing
// plants and the spacing drift make it unique.
std::pair<int, double> RegisterOnField(const review::StandWindow& stand, const sim::Field& field) {
  std::map<int, std::vector<double>> rows;  // true crop y by row
  for (const sim::Plant& p : field.plants()) {
    if (p.cls == sim::PlantClass::kCrop) rows[p.row].push_back(p.position_m.y());
  }
  for (auto& [n, ys] : rows) std::sort(ys.begin(), ys.end());
  std::vector<std::pair<int, double>> records;  // row, y; at most 400 spread over the run
  const size_t step = std::max<size_t>(1, stand.crops_m.size() / 400);
  for (size_t i = 0; i < stand.crops_m.size(); i += step) {
    records.emplace_back(static_cast<int>(std::lround(stand.crops_m[i].first / stand.row_spacing_m)),
                         stand.crops_m[i].second);
  }
  const auto matches = [&](int dr, double dy) {
    int n = 0;
    for (const auto& [row, y] : records) {
      const auto it = rows.find(row + dr);
      if (it == rows.end()) continue;
      const auto at = std::lower_bound(it->second.begin(), it->second.end(), y + dy - 0.06);
      n += at != it->second.end() && *at <= y + dy + 0.06;
    }
    return n;
  };
  std::pair<int, double> best{0, 0.0};
  int best_n = -1;
  for (int dr = -1; dr <= 1; ++dr) {
    for (int k = -1000; k <= 1000; ++k) {  // ±10 m in 1 cm steps
      const int n = matches(dr, 0.01 * k);
      if (n > best_n) best_n = n, best = {dr, 0.01 * k};
    }
  }
  return best;
}

}  // namespace

std::optional<review::AgronomyTruth> SimulatorTruth(const std::string& run_config, const review::StandWindow& stand,
                                                    const std::string& config_dir_option) {
  const SimRunConfig run = ParseRunConfig(run_config, "run_config event");
  std::filesystem::path dir = config_dir_option;
  std::error_code ec;
  if (dir.empty()) dir = !run.config_dir.empty() && std::filesystem::is_directory(run.config_dir, ec)
                             ? std::filesystem::path(run.config_dir) : DefaultConfigDir();
  const sim::Simulator simulator(SimulatorOptionsOf(run, dir));
  const sim::Field& field = simulator.field();
  const auto [dr, dy] = RegisterOnField(stand, field);
  const double spacing = field.options().plant_spacing_m;
  const double y0 = stand.y0_m + dy - 0.25 * spacing, y1 = stand.y1_m + dy + 0.25 * spacing;
  const int first_row = stand.first_row + dr, last_row = stand.last_row + dr;
  review::AgronomyTruth t;
  std::ostringstream source;
  source << "simulator: preset " << run.preset << ", seed " << run.seed << ", " << run.length_m
         << " m; the bed frame registered on the field at " << std::showpos << dr << " rows, " << std::fixed
         << std::setprecision(2) << dy << " m";
  t.source = source.str();
  std::set<std::pair<int, int>> present;  // row, line
  std::vector<double> radii, weed_radii;
  const double x_lo = (first_row - 0.5) * stand.row_spacing_m, x_hi = (last_row + 0.5) * stand.row_spacing_m;
  for (const sim::Plant& p : field.plants()) {
    const double x = p.position_m.x(), y = p.position_m.y();
    if (p.cls == sim::PlantClass::kCrop) {
      if (p.row < first_row || p.row > last_row || y < y0 || y > y1) continue;
      ++t.crop;
      radii.push_back(p.radius_m);
      present.insert({p.row, p.line});
    } else if (x >= x_lo && x <= x_hi && y >= stand.y0_m + dy && y <= stand.y1_m + dy) {
      ++t.weeds;
      // The outline r(θ) = R (1 − d + d |cos(kθ/2)|) (sim/plant_shape.cc)
      // encloses π R² ((1 − d)² + (4/π)(1 − d) d + d²/2).
      const double d = p.lobes > 0 ? p.lobe_depth : 0.0;
      weed_radii.push_back(p.radius_m * std::sqrt((1 - d) * (1 - d) + 4 / std::numbers::pi * (1 - d) * d + d * d / 2));
    }
  }
  const std::vector<double>& lines = field.line_y_m();
  for (int row = first_row; row <= last_row; ++row) {
    bool in_gap = false;
    for (size_t line = 0; line < lines.size(); ++line) {
      if (lines[line] < y0 || lines[line] > y1) continue;
      const bool missing = !present.count({row, static_cast<int>(line)});
      t.missing += missing;
      t.gaps += missing && !in_gap;
      in_gap = missing;
    }
  }
  const auto median = [](std::vector<double>& v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  };
  t.median_radius_m = median(radii);
  t.median_weed_radius_m = median(weed_radii);
  const double area = (x_hi - x_lo) * (stand.y1_m - stand.y0_m);
  t.weeds_per_m2 = area > 0.0 ? t.weeds / area : 0.0;
  return t;
}

}  // namespace plantscale::app
