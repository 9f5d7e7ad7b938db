#pragma once
// The synthetic field (docs/simulator.md): one bed of crop rows planted on a grid
// whose spacings drift slowly along the bed, with missing plants, size
// variation, lean, fractured leaves, weeds (some inside the rows), stones.
//
// Field frame (docs/design.md §3): fixed at the start of the run, x across the
// bed (right), y along the bed (direction of travel), z up; the central row
// of the bed runs along x = 0 and rows sit at x = n·r̄(y).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "engine/common/options.h"
#include "engine/common/plant_class.h"

namespace plantscale::sim {

// What a plant is; the values double as the label image's pixel values
// (engine/common/plant_class.h).
using PlantClass = SoilCropWeed;
using plantscale::ToString;

struct Plant {
  int id = 0;
  PlantClass cls = PlantClass::kCrop;
  Eigen::Vector2d position_m;        // root, field frame
  double radius_m = 0.1;             // outline radius at the tips of the leaves
  double height_m = 0.1;             // height of the leaf tips (the bowl's rim)
  Eigen::Vector2d lean_m{0.0, 0.0};  // rim centre offset from the root
  int lobes = 6;                     // leaves
  double lobe_depth = 0.3;           // 0: round outline; 1: leaves separated to the centre
  double lobe_phase_rad = 0.0;
  double brightness = 1.0;  // relative reflectance of this plant
  int fractured_lobe = -1;  // leaf cut from the body by a dark gap (fig. 2.18)
  int row = 0;              // crop: row index n; weed: nearest row
  int line = -1;            // crop: field plant-line index; weed: −1
};

struct Stone {
  Eigen::Vector2d position_m;
  double semi_major_m = 0.02;
  double semi_minor_m = 0.015;
  double angle_rad = 0.0;
  double brightness = 1.0;
};

struct FieldOptions {
  int rows = 3;                          // rows in the bed (odd: a central row)
  double row_spacing_m = 0.475;          // r̄ (thesis test footage ≈ 475 mm)
  double plant_spacing_m = 0.45;         // l̄ (≈ 450 mm)
  // The spacings the grower set on the planter, which is all a tracker that
  // does not estimate them is told; 0: the same as planted. A planter's
  // ground wheel slips, so the planted l̄ is often a few per cent longer
  // (thesis §8.1.1: the fixed-grid tracker under-read distance by 3–4 %).
  double nominal_row_spacing_m = 0.0;
  double nominal_plant_spacing_m = 0.0;
  double NominalRowSpacing() const {
    return nominal_row_spacing_m > 0.0 ? nominal_row_spacing_m : row_spacing_m;
  }
  double NominalPlantSpacing() const {
    return nominal_plant_spacing_m > 0.0 ? nominal_plant_spacing_m : plant_spacing_m;
  }
  double spacing_drift_fraction = 0.01;  // amplitude of the slow drift of r̄ and l̄
  double spacing_drift_wavelength_m = 25.0;
  double planting_jitter_m = 0.012;  // per-plant placement error (sd)
  double missing_plant_fraction = 0.03;
  double crop_radius_m = 0.11;  // mean leaf-tip radius
  double crop_radius_sd_fraction = 0.15;
  double crop_height_ratio = 0.8;  // rim height / radius (inverted-hemisphere = 1)
  double crop_lean_sd_m = 0.01;
  int crop_lobes = 7;
  double crop_lobe_depth = 0.25;
  double fractured_fraction = 0.0;  // crops with a leaf cut off by shadow
  double weed_density_per_m2 = 6.0;
  double weed_radius_median_m = 0.025;
  double weed_radius_log_sd = 0.45;
  double weed_max_radius_m = 0.09;
  double weed_in_row_fraction = 0.25;  // weeds placed inside a crop row
  double weed_height_ratio = 0.35;
  double stone_density_per_m2 = 3.0;
  double stone_size_median_m = 0.025;
  double plant_brightness_sd = 0.06;  // plant-to-plant reflectance variation
  double bed_margin_m = 0.6;          // soil beyond the outer rows that is populated

  OptionErrors Validate() const;
};

class Field {
 public:
  // Generates a field covering y ∈ [y_begin_m, y_end_m].
  Field(const FieldOptions& options, double y_begin_m, double y_end_m, uint64_t seed);

  const FieldOptions& options() const { return options_; }
  const std::vector<Plant>& plants() const { return plants_; }  // sorted by y
  const std::vector<Stone>& stones() const { return stones_; }  // sorted by y
  // Planted (nominal) y of every plant line, increasing; index = line id.
  const std::vector<double>& line_y_m() const { return line_y_; }
  double RowSpacingAt(double y_m) const;    // r̄ at y, with drift
  double PlantSpacingAt(double y_m) const;  // l̄ at y, with drift
  double RowX(int n, double y_m) const { return n * RowSpacingAt(y_m); }
  int crop_count() const { return crop_count_; }
  int weed_count() const { return static_cast<int>(plants_.size()) - crop_count_; }
  double max_plant_radius_m() const { return max_radius_; }
  double max_plant_height_m() const { return max_height_; }
  // Index range [first, last) of plants with y in [y0, y1].
  std::pair<size_t, size_t> PlantsBetween(double y0, double y1) const;
  std::pair<size_t, size_t> StonesBetween(double y0, double y1) const;

 private:
  void PlantCrops(uint64_t seed);
  void SowWeeds(uint64_t seed, double y_begin, double y_end);
  void ScatterStones(uint64_t seed, double y_begin, double y_end);
  double HalfWidth() const;

  FieldOptions options_;
  double drift_phase_r_ = 0.0;
  double drift_phase_l_ = 0.0;
  std::vector<Plant> plants_;
  std::vector<Stone> stones_;
  std::vector<double> line_y_;
  int crop_count_ = 0;
  double max_radius_ = 0.0;
  double max_height_ = 0.0;
};

}  // namespace plantscale::sim
