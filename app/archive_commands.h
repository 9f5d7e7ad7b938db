#pragma once
// The season archive on the command line (docs/cli/archive.md):
//   plantscale export LOG_OR_MAP --to URL_OR_GPKG --field NAME [--bed N] ...
//   plantscale archive query  --to URL --field F [--from DATE] [--to DATE] [--json]
//   plantscale archive plant ID --to URL [--json]
//   plantscale archive export --to URL --field F --out DIR

#include <optional>
#include <string>

#include "app/command_registry.h"
#include "maps/crop_map.h"
#include "maps/georef.h"

namespace plantscale::app {

// `plantscale export … --to`: one run into the archive.
struct ArchiveExportArgs {
  std::string input;  // the log, map file or simulator folder
  bool is_log = false;
  std::string to, field;
  int bed = 0;
  double match_m = 0.05;
  bool quiet = false;
};

// Appends the run `map` was read from; prints one line. Throws ConfigError
// (bad command line) and what maps::AppendRun throws.
int ExportToArchive(const ArchiveExportArgs& args, const maps::CropMap& map,
                    const std::optional<maps::GeoAnchorOptions>& anchor);

void AddArchiveCommands(CommandRegistry& registry);

}  // namespace plantscale::app
