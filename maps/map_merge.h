#pragma once
// Merge of several passes over the same field (same field frame and cell
// size) into one map: the grid covers all inputs; crop and weed counts add
// (saturating); a cell's class is the strongest seen (weed > crop > soil >
// unknown); treated is the union. The plant registry merges a plant with an
// earlier one of the same class when their ids match and they lie within
// `same_plant_distance_m`, or, failing an id match, when it lies within that
// distance of one; a merged plant keeps the first position and id, the
// highest confidence and is treated when either was. Other plants join with
// their id, or with a fresh id (max + 1) when their id is taken.

#include <vector>

#include "maps/crop_map.h"

namespace plantscale::maps {

struct MergeOptions {
  double same_plant_distance_m = 0.05;
  OptionErrors Validate() const;
};

// Throws DataError when the inputs differ in resolution or their grids are
// not aligned on whole cells; InvalidOptionsError for bad options.
CropMap MergeMaps(const std::vector<CropMap>& maps, const MergeOptions& options = {});

}  // namespace plantscale::maps
