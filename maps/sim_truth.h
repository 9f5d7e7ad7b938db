#pragma once
// A crop map built from a simulator output folder (`plantscale simulate
// --out DIR`): the field truth of the plants the camera saw. Reads
//   DIR/truth/plants.csv          every plant (id, class, row, x, y, radius)
//   DIR/truth/visible_plants.csv  which plants were in view (the map keeps those)
//   DIR/truth/lines.csv           plant lines (y, row spacing) → crop rows
//   DIR/run.json                  preset and seed → metadata
// Metadata "source" is "simulator truth". Until spray logs exist (treatment
// issue) the map marks the ideal treatment: every seen weed is treated
// (why: "simulator truth: weed, ideal treatment"), no crop is.

#include <filesystem>
#include <functional>

#include "maps/crop_map.h"

namespace plantscale::maps {

struct SimTruthOptions {
  double resolution_m = 0.02;  // map cell edge
  double margin_m = 0.25;      // observed soil around the outermost seen plants
  OptionErrors Validate() const;
};

// Progress: (bytes read, bytes in all) while reading the CSV files.
using ReadProgress = std::function<void(size_t done, size_t total)>;

// True when `dir` looks like a simulator output folder.
bool IsSimulatorOutput(const std::filesystem::path& dir);

// Throws MapIoError for unreadable files, DataError naming file, line and
// column for malformed content.
CropMap LoadSimulatorTruth(const std::filesystem::path& dir, const SimTruthOptions& options = {},
                           const ReadProgress& progress = {});

}  // namespace plantscale::maps
