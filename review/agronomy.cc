#include "review/agronomy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include <plantscale_lcmtypes/plantscale_plant_t.hpp>

namespace plantscale::review {
namespace {

namespace tm = plantscale::telemetry;

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Quantile q of sorted `v`, linear between order statistics.
double Quantile(const std::vector<double>& v, double q) {
  if (v.empty()) return 0.0;
  const double at = q * static_cast<double>(v.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(at));
  const size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (at - static_cast<double>(i)) * (v[j] - v[i]);
}

double RowSpacing(const RunModel& model, const std::vector<const PlantRecord*>& crops, std::string& source) {
  if (model.grid()) {
    source = "tracker";
    return model.grid()->state.row_spacing_m;
  }
  if (model.truth()) {
    source = "simulator truth";
    return model.truth()->state.row_spacing_m;
  }
  source = "plants";
  std::vector<double> x;
  for (const PlantRecord* r : crops) x.push_back(r->plant.position_m.x());
  std::sort(x.begin(), x.end());
  std::vector<double> steps;
  for (size_t i = 1; i < x.size(); ++i) {
    if (x[i] - x[i - 1] > 0.15) steps.push_back(x[i] - x[i - 1]);
  }
  return steps.empty() ? 0.475 : Median(steps);
}

std::string Num(double v, int decimals) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(decimals);
  out << v;
  return out.str();
}

}  // namespace

OptionErrors AgronomyOptions::Validate() const {
  OptionErrors e;
  RequireNonNegative(e, "rate_l_ha", rate_l_ha);
  RequireInRange(e, "outline_area_fraction", outline_area_fraction, 0.1, 1.0);
  RequirePositive(e, "cell_length_m", cell_length_m);
  RequirePositive(e, "histogram_bin_m", histogram_bin_m);
  RequireInRange(e, "histogram_bins", histogram_bins, 1, 1000);
  RequireInRange(e, "far_view_fraction", far_view_fraction, 0.0, 1.0);
  RequireInRange(e, "gap_crop_fraction", gap_crop_fraction, 0.0, 1.0);
  RequireInRange(e, "gap_crop_reach", gap_crop_reach, 0.0, 0.5);
  RequireInRange(e, "unseen_canopy_fraction", unseen_canopy_fraction, 0.0, 1.0);
  return e;
}

double LeafTipRadius(double area_m2, double outline_area_fraction) {
  return std::sqrt(std::max(0.0, area_m2) / (std::numbers::pi * outline_area_fraction));
}

SizeStats SizeStatsOf(std::vector<double> radii_m, double bin_m, int bins) {
  SizeStats s;
  s.bin_m = bin_m;
  s.histogram.assign(static_cast<size_t>(bins), 0);
  std::sort(radii_m.begin(), radii_m.end());
  s.count = static_cast<int>(radii_m.size());
  s.median_m = Quantile(radii_m, 0.5);
  s.q1_m = Quantile(radii_m, 0.25);
  s.q3_m = Quantile(radii_m, 0.75);
  for (double r : radii_m) {
    const int b = std::clamp(static_cast<int>(r / bin_m), 0, bins - 1);
    ++s.histogram[static_cast<size_t>(b)];
  }
  return s;
}

namespace {

using RowsOfCrops = std::map<int, std::vector<const PlantRecord*>>;

// Crop records by row, each row sorted along it. A "row" with a handful of
// crop records is a stray (a weed taken for a crop between rows): rows
// holding < 10 % of the fullest row are dropped.
RowsOfCrops CropsByRow(const std::vector<const PlantRecord*>& crops, double rs) {
  RowsOfCrops by_row;
  for (const PlantRecord* r : crops) {
    by_row[static_cast<int>(std::lround(r->plant.position_m.x() / rs))].push_back(r);
  }
  size_t fullest = 0;
  for (const auto& [n, v] : by_row) fullest = std::max(fullest, v.size());
  for (auto it = by_row.begin(); it != by_row.end();) {
    it = it->second.size() * 10 < fullest ? by_row.erase(it) : std::next(it);
  }
  for (auto& [n, v] : by_row) {
    std::sort(v.begin(), v.end(), [](const PlantRecord* p, const PlantRecord* q) {
      return p->plant.position_m.y() < q->plant.position_m.y();
    });
  }
  return by_row;
}

// One row's stand, gaps and crop sizes (leaf-tip radii appended to `radii`).
RowAgronomy RowStats(int n, const std::vector<const PlantRecord*>& v, const AgronomyOptions& o,
                     std::vector<double>& radii) {
  RowAgronomy r;
  r.row = n;
  r.crop = static_cast<int>(v.size());
  r.stand_length_m = v.back()->plant.position_m.y() - v.front()->plant.position_m.y();
  std::vector<double> steps, row_radii;
  for (size_t i = 1; i < v.size(); ++i) steps.push_back(v[i]->plant.position_m.y() - v[i - 1]->plant.position_m.y());
  r.plant_spacing_m = Median(steps);
  // Plants per metre of row: the plants that would stand at one spacing
  // each over the stand, so a run of n plants covers n·l̄.
  const double row_m = r.stand_length_m + r.plant_spacing_m;
  r.plants_per_m = row_m > 0.0 ? r.crop / row_m : 0.0;
  for (const PlantRecord* p : v) row_radii.push_back(LeafTipRadius(p->plant.size_m2, o.outline_area_fraction));
  radii.insert(radii.end(), row_radii.begin(), row_radii.end());
  r.crop_size = SizeStatsOf(row_radii, o.histogram_bin_m, o.histogram_bins);
  return r;
}

// The row's gaps: between two neighbours round(Δy / l̄) − 1 places, evenly
// between them; a place where `filled(place)` holds (a crop recorded as a
// weed) is not missing and splits its gap.
template <class Filled>
void CountGaps(RowAgronomy& r, const std::vector<const PlantRecord*>& v, Filled filled) {
  for (size_t i = 1; i < v.size() && r.plant_spacing_m > 0.0; ++i) {
    const Eigen::Vector2d& a = v[i - 1]->plant.position_m;
    const Eigen::Vector2d& b = v[i]->plant.position_m;
    const int places = static_cast<int>(std::lround((b.y() - a.y()) / r.plant_spacing_m)) - 1;
    int run = 0;
    double run_at = a.y();
    for (int k = 1; k <= places + 1; ++k) {
      const bool missing = k <= places && !filled(a + (b - a) * (static_cast<double>(k) / (places + 1)));
      if (missing) {
        if (run == 0) run_at = a.y() + (b.y() - a.y()) * (k - 1.0) / (places + 1);  // the place before
        ++run;
        continue;
      }
      if (run == 0) continue;
      ++r.gaps;
      r.missing += run;
      if (run > r.longest_gap) r.longest_gap = run, r.longest_gap_at_m = run_at;
      run = 0;
    }
  }
}

// A weed record's radius: the disc of its area.
double DiscRadius(const PlantRecord& w) { return std::sqrt(std::max(0.0, w.plant.size_m2) / std::numbers::pi); }

// `fraction` of the crops' median leaf-tip radius (∞ for 0: no record is
// that large), the lines of far_view_fraction and gap_crop_fraction.
double CropRadiusFraction(const AgronomySummary& a, double fraction) {
  return fraction > 0.0 ? fraction * a.crop_size.median_m : std::numeric_limits<double>::infinity();
}

// Every row's gaps (CountGaps), a place filled by a crop-sized weed record
// within half the row's plant spacing of it, or by one of gap_crop_fraction
// of the crops' size within gap_crop_reach spacings (each record fills one
// place); the records that filled one.
std::set<const PlantRecord*> CountAllGaps(const RowsOfCrops& by_row, const std::vector<const PlantRecord*>& weeds,
                                          const AgronomyOptions& o, AgronomySummary& a) {
  const double crop_sized = CropRadiusFraction(a, o.far_view_fraction);
  const double near_sized = CropRadiusFraction(a, o.gap_crop_fraction);
  std::vector<const PlantRecord*> large;  // weed records that may fill a place, by y
  for (const PlantRecord* w : weeds) {
    if (DiscRadius(*w) >= std::min(crop_sized, near_sized)) large.push_back(w);
  }
  std::sort(large.begin(), large.end(), [](const PlantRecord* p, const PlantRecord* q) {
    return p->plant.position_m.y() < q->plant.position_m.y();
  });
  std::set<const PlantRecord*> used;
  size_t i = 0;
  for (const auto& [n, v] : by_row) {
    RowAgronomy& r = a.rows[i++];
    const double reach = 0.5 * r.plant_spacing_m;
    const double near_reach = o.gap_crop_reach * r.plant_spacing_m;
    CountGaps(r, v, [&](const Eigen::Vector2d& place) {
      auto it = std::lower_bound(large.begin(), large.end(), place.y() - reach,
                                 [](const PlantRecord* p, double y) { return p->plant.position_m.y() < y; });
      for (; it != large.end() && (*it)->plant.position_m.y() <= place.y() + reach; ++it) {
        const double distance = (place - (*it)->plant.position_m).norm();
        const bool fills = distance < (DiscRadius(**it) >= crop_sized ? reach : near_reach);
        if (fills && used.insert(*it).second) return true;
      }
      return false;
    });
    a.gaps += r.gaps;
    a.missing += r.missing;
    a.longest_gap = std::max(a.longest_gap, r.longest_gap);
  }
  a.crops_recorded_as_weeds = static_cast<int>(used.size());
  return used;
}

// The heat map: rows × cells along, the crops counted in.
void FillCropCells(const RowsOfCrops& by_row, const AgronomyOptions& o, AgronomySummary& a) {
  a.cells.resize(a.rows.size() * static_cast<size_t>(a.cells_along));
  for (size_t i = 0; i < a.rows.size(); ++i) {
    for (int c = 0; c < a.cells_along; ++c) {
      HeatCell& h = a.cells[i * static_cast<size_t>(a.cells_along) + static_cast<size_t>(c)];
      h.row = a.rows[i].row;
      h.index = c;
    }
  }
  size_t i = 0;
  for (const auto& [n, v] : by_row) {
    for (const PlantRecord* p : v) {
      const int c = std::clamp(static_cast<int>((p->plant.position_m.y() - a.y0_m) / o.cell_length_m), 0,
                               a.cells_along - 1);
      ++a.cells[i * static_cast<size_t>(a.cells_along) + static_cast<size_t>(c)].crop;
    }
    ++i;
  }
}

// The band's crop records as leaf-tip discs, by bed y.
struct CropDisc {
  double y = 0.0, x = 0.0, radius_m = 0.0;
};

std::vector<CropDisc> CropDiscs(const RowsOfCrops& by_row, const AgronomyOptions& o) {
  std::vector<CropDisc> out;
  for (const auto& [n, v] : by_row) {
    for (const PlantRecord* p : v) {
      out.push_back({p->plant.position_m.y(), p->plant.position_m.x(),
                     LeafTipRadius(p->plant.size_m2, o.outline_area_fraction)});
    }
  }
  std::sort(out.begin(), out.end(), [](const CropDisc& a, const CropDisc& b) { return a.y < b.y; });
  return out;
}

// Whether some crop disc's centre lies within `reach(disc)` of p; reach is
// at most `max_reach_m`.
template <class Reach>
bool NearACrop(const std::vector<CropDisc>& discs, const Eigen::Vector2d& p, double max_reach_m, Reach reach) {
  auto it = std::lower_bound(discs.begin(), discs.end(), p.y() - max_reach_m,
                             [](const CropDisc& d, double y) { return d.y < y; });
  for (; it != discs.end() && it->y <= p.y() + max_reach_m; ++it) {
    if (std::hypot(it->x - p.x(), it->y - p.y()) < reach(*it)) return true;
  }
  return false;
}

// The weed side of the plant figures: crop discs, the size above which a
// weed record is as large as a crop, and how near its crop it then is.
struct WeedContext {
  std::vector<CropDisc> discs;
  double crop_sized_m = 0.0;  // weed radius (∞: none)
  double far_view_reach_m = 0.0;
  double max_disc_m = 0.0;
};

WeedContext WeedContextOf(const RowsOfCrops& by_row, const AgronomySummary& a, const AgronomyOptions& o) {
  WeedContext c;
  c.discs = CropDiscs(by_row, o);
  for (const CropDisc& d : c.discs) c.max_disc_m = std::max(c.max_disc_m, d.radius_m);
  c.crop_sized_m = CropRadiusFraction(a, o.far_view_fraction);
  std::vector<double> spacing;
  for (const RowAgronomy& r : a.rows) spacing.push_back(r.plant_spacing_m);
  c.far_view_reach_m = 0.5 * Median(spacing);
  return c;
}

bool FarViewOfCrop(const PlantRecord& w, const WeedContext& c) {
  return DiscRadius(w) >= c.crop_sized_m && NearACrop(c.discs, w.plant.position_m, c.far_view_reach_m,
                                               [&](const CropDisc&) { return c.far_view_reach_m; });
}

bool UnderACanopy(const Eigen::Vector2d& p, const WeedContext& c, double fraction) {
  return NearACrop(c.discs, p, fraction * c.max_disc_m, [&](const CropDisc& d) { return fraction * d.radius_m; });
}

// A weed record's share of its row and heat cell.
void AddWeedToCells(const PlantRecord& w, const std::map<int, size_t>& row_index, const AgronomyOptions& o,
                    AgronomySummary& a) {
  const Eigen::Vector2d& p = w.plant.position_m;
  const auto it = row_index.find(static_cast<int>(std::lround(p.x() / a.row_spacing_m)));
  if (it == row_index.end()) return;
  const int c = std::clamp(static_cast<int>((p.y() - a.y0_m) / o.cell_length_m), 0, a.cells_along - 1);
  HeatCell& h = a.cells[it->second * static_cast<size_t>(a.cells_along) + static_cast<size_t>(c)];
  ++h.weeds;
  h.weed_area_m2 += w.plant.size_m2;
  ++a.rows[it->second].weeds;
}

// Weeds within the surveyed band [x_lo, x_hi] × the stand: their count,
// sizes, density (over the band and over the ground seen), and their rows'
// and cells' shares; crop-sized records beside a crop counted apart.
void CountWeeds(const std::vector<const PlantRecord*>& weeds, const RowsOfCrops& by_row, double x_lo,
                double x_hi, const std::set<const PlantRecord*>& crops_as_weeds, const AgronomyOptions& o,
                AgronomySummary& a) {
  const double rs = a.row_spacing_m;
  std::map<int, size_t> row_index;
  for (size_t i = 0; i < a.rows.size(); ++i) row_index[a.rows[i].row] = i;
  const WeedContext context = WeedContextOf(by_row, a, o);
  std::vector<double> weed_radii;
  int seen = 0;
  for (const PlantRecord* w : weeds) {
    const Eigen::Vector2d& p = w->plant.position_m;
    if (p.x() < x_lo || p.x() > x_hi || p.y() < a.y0_m || p.y() > a.y1_m) continue;
    if (FarViewOfCrop(*w, context)) {
      ++a.far_views_of_crops;
      a.weed_records_taken_as_crops.insert(w->plant.id);
      continue;
    }
    if (crops_as_weeds.count(w)) {  // a crop in a gap's place (CountGaps)
      a.weed_records_taken_as_crops.insert(w->plant.id);
      continue;
    }
    ++a.weeds;
    a.weeds_by_model += w->plant.why == plantscale_plant_t::WHY_LEARNED;
    seen += !UnderACanopy(p, context, o.unseen_canopy_fraction);
    weed_radii.push_back(DiscRadius(*w));
    AddWeedToCells(*w, row_index, o, a);
  }
  a.weeds_per_m2 = a.surveyed_area_m2 > 0.0 ? a.weeds / a.surveyed_area_m2 : 0.0;
  for (const CropDisc& d : context.discs) a.unseen_canopy_m2 += std::numbers::pi * std::pow(o.unseen_canopy_fraction * d.radius_m, 2);
  const double seen_m2 = a.surveyed_area_m2 - a.unseen_canopy_m2;
  a.weeds_per_m2_seen = seen_m2 > 0.0 ? seen / seen_m2 : 0.0;
  const double length = std::max(0.0, a.y1_m - a.y0_m);
  for (RowAgronomy& r : a.rows) {
    const double area = rs * (r.stand_length_m > 0.0 ? length : 0.0);
    r.weeds_per_m2 = area > 0.0 ? r.weeds / area : 0.0;
  }
  a.weed_size = SizeStatsOf(weed_radii, o.histogram_bin_m, o.histogram_bins);
}

}  // namespace

AgronomySummary Agronomy(const RunModel& model, const RunSummary& run, const AgronomyOptions& o) {
  ThrowIfInvalid("agronomy options", o.Validate());
  AgronomySummary a;
  a.distance_m = run.distance_m;
  a.duration_s = 1e-6 * static_cast<double>(model.last_message_utime() - model.first_message_utime());
  a.rate_l_ha = o.rate_l_ha;
  a.shots = run.shots;
  a.faults = static_cast<int>(run.faults.size());
  a.cell_length_m = o.cell_length_m;
  a.area_treated_m2 = run.area_treated_m2;
  if (run.area_treated_m2) a.product_l = *run.area_treated_m2 * 1e-4 * o.rate_l_ha;

  std::vector<const PlantRecord*> crops;
  for (const auto& [id, r] : model.plants()) {
    if (r.plant.kind == tm::PlantKind::kCrop) crops.push_back(&r);
  }
  a.row_spacing_m = RowSpacing(model, crops, a.row_spacing_source);
  AddPlantFigures(a, model.plants(), o);
  if (a.product_l && a.surveyed_area_m2 > 0.0) {
    a.broadcast_product_l = a.surveyed_area_m2 * 1e-4 * o.rate_l_ha;
    a.product_saved_fraction = 1.0 - *a.product_l / *a.broadcast_product_l;
  }
  return a;
}

void AddPlantFigures(AgronomySummary& a, const std::map<int64_t, PlantRecord>& plants, const AgronomyOptions& o) {
  std::vector<const PlantRecord*> crops, weeds;
  for (const auto& [id, r] : plants) {
    if (r.plant.kind == tm::PlantKind::kCrop) crops.push_back(&r);
    if (r.plant.kind == tm::PlantKind::kWeed) weeds.push_back(&r);
  }
  if (a.row_spacing_m <= 0.0) a.row_spacing_m = RowSpacing(RunModel(), crops, a.row_spacing_source);
  const double rs = a.row_spacing_m;
  const RowsOfCrops by_row = CropsByRow(crops, rs);
  if (by_row.empty()) return;
  a.y0_m = 1e300;
  a.y1_m = -1e300;
  for (const auto& [n, v] : by_row) {
    a.y0_m = std::min(a.y0_m, v.front()->plant.position_m.y());
    a.y1_m = std::max(a.y1_m, v.back()->plant.position_m.y());
  }
  const double x_lo = (by_row.begin()->first - 0.5) * rs, x_hi = (by_row.rbegin()->first + 0.5) * rs;
  const double length = std::max(0.0, a.y1_m - a.y0_m);
  a.surveyed_area_m2 = (x_hi - x_lo) * length;
  a.cells_along = std::max(1, static_cast<int>(std::ceil(length / o.cell_length_m)));
  std::vector<double> all_radii;
  double row_metres = 0.0;
  for (const auto& [n, v] : by_row) {
    RowAgronomy r = RowStats(n, v, o, all_radii);
    row_metres += r.stand_length_m + r.plant_spacing_m;
    a.crop += r.crop;
    a.rows.push_back(std::move(r));
  }
  a.plants_per_m = row_metres > 0.0 ? a.crop / row_metres : 0.0;
  a.crop_size = SizeStatsOf(all_radii, o.histogram_bin_m, o.histogram_bins);
  const std::set<const PlantRecord*> crops_as_weeds = CountAllGaps(by_row, weeds, o, a);
  FillCropCells(by_row, o, a);
  CountWeeds(weeds, by_row, x_lo, x_hi, crops_as_weeds, o, a);
}

std::string AgronomyCsv(const AgronomySummary& a) {
  std::ostringstream out;
  out << "row,crop_plants,stand_length_m,plants_per_m,plant_spacing_m,gaps,missing_plants,longest_gap_plants,"
         "crop_radius_median_m,crop_radius_q1_m,crop_radius_q3_m,weeds,weeds_per_m2,weed_radius_median_m,"
         "area_treated_m2,product_l,rate_l_ha,distance_m,duration_s,faults\n";
  for (const RowAgronomy& r : a.rows) {
    out << r.row << ',' << r.crop << ',' << Num(r.stand_length_m, 2) << ',' << Num(r.plants_per_m, 3) << ','
        << Num(r.plant_spacing_m, 3) << ',' << r.gaps << ',' << r.missing << ',' << r.longest_gap << ','
        << Num(r.crop_size.median_m, 4) << ',' << Num(r.crop_size.q1_m, 4) << ',' << Num(r.crop_size.q3_m, 4)
        << ',' << r.weeds << ',' << Num(r.weeds_per_m2, 3) << ",,,,,,,\n";
  }
  const double length = a.y1_m - a.y0_m;
  out << "all," << a.crop << ',' << Num(std::max(0.0, length), 2) << ',' << Num(a.plants_per_m, 3) << ",,"
      << a.gaps << ',' << a.missing << ',' << a.longest_gap << ',' << Num(a.crop_size.median_m, 4) << ','
      << Num(a.crop_size.q1_m, 4) << ',' << Num(a.crop_size.q3_m, 4) << ',' << a.weeds << ','
      << Num(a.weeds_per_m2, 3) << ',' << Num(a.weed_size.median_m, 4) << ','
      << (a.area_treated_m2 ? Num(*a.area_treated_m2, 3) : std::string()) << ','
      << (a.product_l ? Num(*a.product_l, 4) : std::string()) << ',' << Num(a.rate_l_ha, 1) << ','
      << Num(a.distance_m, 2) << ',' << Num(a.duration_s, 1) << ',' << a.faults << '\n';
  return out.str();
}

}  // namespace plantscale::review
