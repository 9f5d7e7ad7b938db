#pragma once
// Scores a simulated spraying run against the field's plant truth (thesis
// §8.2.1): the simulated bar's shots are painted into a fine raster of the
// field frame; a plant is hit when the spray covers its root; placement is
// the centre of the bounding box of the sprayed patch over a plant (within a
// window around it, so patches joined to a neighbour's are cut) minus its
// root (x_w across, y_w along the rows, thesis fig. 8.3 and table 8.3), and
// also minus the plant's footprint centre (root + lean), which is what a
// camera can see; the treated area is the sprayed fraction of the bed.

#include <span>
#include <vector>

#include "engine/sim/field.h"
#include "engine/treatment/simulated_bar.h"

namespace plantscale::app {

struct SprayScoreRegion {
  double y_begin_m = 0.0;  // field y range whose plants count
  double y_end_m = 0.0;
  double bed_half_width_m = 0.7;  // |x| within this is the bed
  double raster_m = 0.005;
  double patch_half_size_m = 0.15;  // a plant's sprayed patch is looked for this far around its root
};

// A crop plant the spray missed, and how near the spray came to its root.
struct MissedCrop {
  int seed_index = 0;  // which run (set by the caller merging runs)
  int plant_id = 0;
  Eigen::Vector2d root_m{0.0, 0.0};  // field frame
  double radius_m = 0.0;
  // Root to the nearest sprayed raster cell within the patch window
  // (SprayScoreRegion::patch_half_size_m); ∞ when none: nothing sprayed near.
  double nearest_spray_m = 0.0;
};

struct SprayScore {
  int crop_plants = 0, crop_hits = 0;
  int weeds = 0, weed_hits = 0;
  int weeds_clear = 0, weed_hits_clear = 0;  // weeds not under a crop's leaves
  // Of those, weeds whose outline touches a crop's (root beyond the crop's
  // leaf-tip radius, within it plus the weed's own): hit, and hit with that
  // crop's root left dry (spray-weed mode's aim).
  int weeds_touching = 0, weed_hits_touching = 0, weed_hits_touching_crop_dry = 0;
  // Sums over hit crops, field frame (x across, y along).
  Eigen::Vector2d error_sum = Eigen::Vector2d::Zero();
  Eigen::Vector2d error2_sum = Eigen::Vector2d::Zero();
  Eigen::Vector2d centre_error_sum = Eigen::Vector2d::Zero();
  Eigen::Vector2d centre_error2_sum = Eigen::Vector2d::Zero();
  double sprayed_bed_m2 = 0.0;
  double bed_m2 = 0.0;
  std::vector<MissedCrop> missed;

  void Merge(const SprayScore& other);
};

SprayScore ScoreSpray(const sim::Field& field, std::span<const treatment::Shot> shots,
                      const SprayScoreRegion& region);

}  // namespace plantscale::app
