#pragma once
// The agronomic summary of a run (issue 36): what an agronomist asks first,
// per run and per crop row, from the run model a log was replayed into:
// crop plants and plants per metre of row, gaps (missing plants against the
// plant spacing), plant size as leaf-tip radius, weeds per m² and their
// sizes, area treated and product used at a rate, time, distance, faults;
// and the 1 m × row cells of the overview heat map. No VTK here.
//
// Definitions (docs/cli/report.md#agronomic-summary):
//  - a crop record belongs to row n = round(x / r̄), r̄ the row spacing of
//    the newest grid estimate (tracker, else simulator truth, else the
//    median spacing between crop rows);
//  - a row's stand runs from its first to its last crop record; plants per
//    metre = crops / that length; the plant spacing l̄ is the median of the
//    gaps between neighbours along the row; between two neighbours
//    round(Δy / l̄) − 1 plants are missing; a gap is one such run, its
//    length the number of missing plants;
//  - leaf-tip radius from the record's ground area A: R = √(A / (π f)),
//    f the area of a lobed outline over πR² (engine/sim/plant_shape.h:
//    f = (1−d)² + (4/π)(1−d)d + d²/2, 0.832 for lobe depth d = 0.25); weeds
//    as the radius of a disc of the same area;
//  - weeds per m² over the surveyed band: the crop rows' span across plus
//    r̄/2 on each side, times the stand length. A weed record at least
//    `far_view_fraction` of the crops' median leaf-tip radius in radius
//    (as large as a crop: no weed of the crop profiles grows so) within
//    half a plant spacing of a crop record of its row is a far view of
//    that crop, recorded before the grid associated it (the crop is
//    recorded already): it is not a weed and is counted apart;
//  - a crop-sized weed record in a gap, within half a plant spacing of a
//    missing plant's place in its row, is that crop recorded as a weed
//    (a large weed merged with it moved the blob's centroid out of every
//    association region): the place is not missing, and the record is
//    neither a weed nor a gap (`crops_recorded_as_weeds`); so is a smaller
//    weed record, down to `gap_crop_fraction` of the crops' median radius,
//    within `gap_crop_reach` plant spacings of the place: a small crop
//    recorded beside its place, which a weed of that size would have to
//    hit by chance;
//  - weeds per m² of the ground seen: the weeds outside the crops' unseen
//    ground over the band less that ground. A crop's canopy hides the
//    ground under it from every view; it is taken as the disc of
//    `unseen_canopy_fraction` of each crop record's leaf-tip radius. Weeds
//    stand on the ground whatever covers it, so this is the estimate of the
//    whole band's density where the canopy hides some of it.

#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "engine/common/options.h"
#include "review/run_model.h"

namespace plantscale::review {

struct AgronomyOptions {
  double rate_l_ha = 200.0;            // product applied on the treated area, litres per hectare
  double outline_area_fraction = 0.832;  // crop area / (π R²), see above
  double cell_length_m = 1.0;          // heat map cells along the row
  double histogram_bin_m = 0.01;       // plant-size histogram bin (radius)
  int histogram_bins = 25;
  // Crop-sized weed records (above): (1 − 3 × 0.15) of the crops' median
  // leaf-tip radius, 0.15 the crop profiles' plant-to-plant spread (the
  // registry's undersized line). 0: every weed record counts.
  double far_view_fraction = 0.55;
  // A weed record of this fraction of the crops' median leaf-tip radius
  // within `gap_crop_reach` plant spacings of a missing plant's place is
  // that crop (above). 0: only crop-sized records fill a gap.
  // docs/results/2026-11-27-report.md, session 31.
  double gap_crop_fraction = 0.35;
  double gap_crop_reach = 0.15;
  // The ground no view sees under a crop (above): within this fraction of
  // its leaf-tip radius (docs/results/2026-11-27-report.md, session 27).
  double unseen_canopy_fraction = 0.75;

  OptionErrors Validate() const;
};

struct SizeStats {
  int count = 0;
  double median_m = 0.0, q1_m = 0.0, q3_m = 0.0;  // radius quartiles
  std::vector<int> histogram;                      // counts per bin, the last bin open-ended
  double bin_m = 0.01;
};

struct RowAgronomy {
  int row = 0;  // 0 the central row, negative to the left
  int crop = 0;
  double stand_length_m = 0.0;  // first to last crop along the row
  double plants_per_m = 0.0;
  double plant_spacing_m = 0.0;  // median neighbour spacing
  int gaps = 0;                  // runs of missing plants
  int missing = 0;               // plants missing in all gaps
  int longest_gap = 0;           // plants missing in the longest gap
  double longest_gap_at_m = 0.0; // y where the longest gap starts
  SizeStats crop_size;
  int weeds = 0;  // weeds within r̄/2 of the row
  double weeds_per_m2 = 0.0;
};

// One 1 m × row cell of the overview.
struct HeatCell {
  int row = 0;
  int index = 0;  // along the run: y from y0_m + index · cell_length_m
  int crop = 0;
  int weeds = 0;
  double weed_area_m2 = 0.0;
};

struct AgronomySummary {
  double distance_m = 0.0;
  double duration_s = 0.0;  // first to last message
  double row_spacing_m = 0.0;
  std::string row_spacing_source;  // "tracker", "simulator truth" or "plants"
  double y0_m = 0.0, y1_m = 0.0;   // stand along the rows (field frame)
  double surveyed_area_m2 = 0.0;
  int crop = 0;
  double plants_per_m = 0.0;  // crops / row metres
  int gaps = 0, missing = 0, longest_gap = 0;
  SizeStats crop_size;
  int weeds = 0;
  double weeds_per_m2 = 0.0;
  int weeds_by_model = 0;            // of `weeds`: records the grower's learned model classified (WHY_LEARNED)
  int far_views_of_crops = 0;        // crop-sized weed records beside their crop (above), not in `weeds`
  int crops_recorded_as_weeds = 0;   // weed records filling a gap's place (above), in neither
  std::set<int64_t> weed_records_taken_as_crops;  // ids of both (the bed picture draws them as crops' rings)
  double unseen_canopy_m2 = 0.0;     // ground under the crops that no view sees (above)
  double weeds_per_m2_seen = 0.0;    // weeds per m² of the ground seen (above)
  SizeStats weed_size;
  std::optional<double> area_treated_m2;
  std::optional<double> product_l;
  // A broadcast application of the bed (the surveyed band of the rows over
  // the stand) at the same rate, and the share of it the spot sprayer saved
  // (1 − product / broadcast). None without tiles or a stand.
  std::optional<double> broadcast_product_l;
  std::optional<double> product_saved_fraction;
  double rate_l_ha = 0.0;
  int shots = 0;
  int faults = 0;
  std::vector<RowAgronomy> rows;
  double cell_length_m = 1.0;
  int cells_along = 0;
  std::vector<HeatCell> cells;  // rows × cells_along, row-major by row order of `rows`
};

// Leaf-tip radius of a crop of ground area `area_m2` (see above).
double LeafTipRadius(double area_m2, double outline_area_fraction);
// Median, quartiles (linear interpolation) and histogram of `radii_m`.
SizeStats SizeStatsOf(std::vector<double> radii_m, double bin_m, int bins);

// Throws InvalidOptionsError.
AgronomySummary Agronomy(const RunModel& model, const RunSummary& run, const AgronomyOptions& options = {});

// The per-row and whole-run plant figures (crop, plants per metre, gaps,
// sizes, weeds, heat cells) of `plants` into `a`, on the rows of spacing
// a.row_spacing_m (when 0: the median spacing between crop rows, source
// "plants"). Agronomy() is this on the run model's registry; the season
// archive calls it on a map's plants.
void AddPlantFigures(AgronomySummary& a, const std::map<int64_t, PlantRecord>& plants,
                     const AgronomyOptions& options = {});

// Where the stand of a run lies, for the truth to be counted over.
struct StandWindow {
  double y0_m = 0.0, y1_m = 0.0;  // along the rows, field frame
  int first_row = 0, last_row = 0;
  double row_spacing_m = 0.0;
  std::vector<std::pair<double, double>> crops_m;  // the crop records (x, y), to register a truth against
};

// Simulator truth over the same stand (filled by the app, which can rebuild
// the simulated field from the log's run_config event: app/report_truth.h).
struct AgronomyTruth {
  std::string source;  // e.g. "simulator: preset field, seed 1"
  int crop = 0;
  int missing = 0;  // missing plants (planting gaps)
  int gaps = 0;
  double median_radius_m = 0.0;
  double weeds_per_m2 = 0.0;
  int weeds = 0;
  // Median radius of the disc with a weed's outline area (the report's weed
  // radius is that of its record's area), weeds of the stand's rows.
  double median_weed_radius_m = 0.0;
};

// CSV: one line per row and one for the whole run (row = "all").
std::string AgronomyCsv(const AgronomySummary& a);

}  // namespace plantscale::review
