#pragma once
// `plantscale detect-rows` (crop rows in photographs from unknown cameras)
// and `plantscale evaluate rows` (the same detector on simulator frames seen
// in perspective, scored with CRDA).

#include <filesystem>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/command_registry.h"
#include "app/config/photo_segmentation.h"

namespace plantscale::app {

struct DetectRowsRequest {
  std::vector<std::filesystem::path> inputs;  // files and folders
  std::filesystem::path out;
  bool progress = true;
  std::filesystem::path model;  // a learned crop/weed model: rows in its crop class
};

struct DetectRowsResult : ImageBatchResult {
  int with_rows = 0;
};

// For each NAME.ext: OUT/NAME_rows.csv (row,v,u), OUT/NAME_rows.png (the
// photograph with the rows drawn), OUT/NAME_rows.json (vanishing point,
// spacing at the bottom row, confidence, the rows' curve). Unreadable files
// are errors of their own; the others are still processed. The command exits
// 0 when any image was processed and 2 when none could be.
DetectRowsResult DetectRows(const DetectRowsRequest& request, std::ostream& log);

void AddRowsCommands(CommandRegistry& registry);

}  // namespace plantscale::app
