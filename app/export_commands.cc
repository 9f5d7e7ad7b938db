#include "app/export_commands.h"

#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <utility>

#include "app/archive_commands.h"
#include "app/config/config_loader.h"
#include "app/config/progress.h"
#include "app/log_map.h"
#include "maps/export.h"
#include "maps/map_file.h"
#include "maps/map_merge.h"
#include "maps/sim_truth.h"
#include "telemetry/log.h"

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

struct ExportArgs {
  std::vector<std::string> inputs;
  std::string out;
  std::string formats;
  std::string origin;
  std::optional<double> heading_deg;
  int epsg = 0;
  double resolution_m = 0.02;
  double rate_l_per_ha = 200.0;
  double isoxml_cell_m = 0.0;
  bool quiet = false;
  // The season archive (--to): docs/cli/archive.md.
  std::string to, field;
  int bed = 0;
  double match_m = 0.05;
};

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, ',')) items.push_back(item);
  return items;
}

maps::GeoAnchorOptions ParseOrigin(const std::string& text) {
  const std::vector<std::string> parts = SplitList(text);
  maps::GeoAnchorOptions a;
  try {
    size_t end0 = 0, end1 = 0;
    if (parts.size() != 2) throw std::invalid_argument("two numbers");
    a.latitude_deg = std::stod(parts[0], &end0);
    a.longitude_deg = std::stod(parts[1], &end1);
    if (end0 != parts[0].size() || end1 != parts[1].size()) throw std::invalid_argument("junk");
  } catch (const std::exception&) {
    throw ConfigError("--origin", "origin", "expected LAT,LON in degrees (got '" + text + "')");
  }
  return a;
}

// The map's own anchor (written by a previous export into map.psmap).
std::optional<maps::GeoAnchorOptions> StoredAnchor(const maps::CropMap& map) {
  const auto& m = map.metadata();
  if (!m.count("origin_lat_deg") || !m.count("origin_lon_deg")) return std::nullopt;
  maps::GeoAnchorOptions a;
  a.latitude_deg = std::stod(m.at("origin_lat_deg"));
  a.longitude_deg = std::stod(m.at("origin_lon_deg"));
  if (m.count("heading_deg")) a.heading_deg = std::stod(m.at("heading_deg"));
  return a;
}

// An LCM log starts with the event sync word 0xEDA1DA01 (big-endian).
bool IsLcmLog(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[4] = {0, 0, 0, 0};
  in.read(reinterpret_cast<char*>(magic), 4);
  return in.gcount() == 4 && magic[0] == 0xED && magic[1] == 0xA1 && magic[2] == 0xDA && magic[3] == 0x01;
}

maps::CropMap LoadInput(const std::string& input, const ExportArgs& args) {
  const fs::path path(input);
  if (maps::IsSimulatorOutput(path)) {
    maps::SimTruthOptions options;
    options.resolution_m = args.resolution_m;
    ProgressBar bar(std::cerr, "read " + path.filename().string(), 1000, !args.quiet);
    maps::CropMap map = maps::LoadSimulatorTruth(path, options, [&bar](size_t done, size_t all) {
      bar.Update(static_cast<int>(1000.0 * static_cast<double>(done) / std::max<double>(all, 1)));
    });
    bar.Finish();
    return map;
  }
  if (!fs::exists(path)) throw ConfigError(input, "LOG_OR_MAP", "no such file or folder");
  if (IsLcmLog(path)) {
    ProgressBar bar(std::cerr, "read " + path.filename().string(), 1000, !args.quiet);
    LogMapReport report;
    maps::CropMap map = CropMapFromLog(path, report, [&bar](int64_t done, int64_t all) {
      bar.Update(static_cast<int>(1000.0 * static_cast<double>(done) / std::max<double>(static_cast<double>(all), 1)));
    });
    bar.Finish();
    for (const std::string& p : report.problems) std::cerr << "plantscale: warning: " << p << "\n";
    if (!args.quiet) {
      std::cerr << "read " << path.string() << ": " << report.events << " events, " << report.tiles
                << " map tiles, " << report.plants << " plants";
      if (report.bad_messages > 0) std::cerr << ", " << report.bad_messages << " bad messages skipped";
      std::cerr << "\n";
    }
    return map;
  }
  if (fs::is_regular_file(path)) {
    std::ifstream in(path, std::ios::binary);
    std::string head(14, '\0');
    in.read(head.data(), 14);
    if (head != "plantscale-map") {
      throw ConfigError(input, "LOG_OR_MAP",
                        "neither an LCM log (no LCM sync word at byte 0) nor a plantscale map file (no "
                        "'plantscale-map' header)");
    }
    return maps::LoadMap(path);  // DataError when the map is corrupt
  }
  throw ConfigError(input, "LOG_OR_MAP",
                    "neither an LCM log, a map file (.psmap) nor a simulator output folder "
                    "(DIR/truth/plants.csv)");
}

maps::ExportOptions MakeOptions(const ExportArgs& args, const maps::CropMap& map) {
  maps::ExportOptions o;
  if (!args.formats.empty()) o.formats = SplitList(args.formats);
  o.anchor = args.origin.empty() ? StoredAnchor(map) : ParseOrigin(args.origin);
  if (o.anchor) {
    if (args.heading_deg) o.anchor->heading_deg = *args.heading_deg;
    o.anchor->epsg = args.epsg;
  }
  o.isoxml.rate_l_per_ha = args.rate_l_per_ha;
  o.isoxml.cell_size_m = args.isoxml_cell_m;
  return o;
}

void PrintResult(const maps::CropMap& map, const maps::ExportResult& r) {
  std::cout << "plantscale export: " << map.plants().size() << " plants, " << map.grid().cols()
            << " x " << map.grid().rows() << " cells of " << map.grid().resolution_m() << " m, "
            << map.treated_cells() << " treated cells";
  if (r.epsg != 0) {
    std::cout << "; EPSG:" << r.epsg << ", raster georeference within " << std::setprecision(2)
              << 1000.0 * r.geotransform_error_m << " mm of exact";
  }
  std::cout << "\n";
  for (const fs::path& f : r.files) std::cout << "  wrote " << f.string() << "\n";
}

// One run into the season archive.
int ExportArchive(const ExportArgs& args) {
  if (!args.out.empty()) throw ConfigError("export", "--out", "give --out (files) or --to (archive), not both");
  if (args.inputs.size() != 1) throw ConfigError("export", "LOG_OR_MAP", "--to archives one run: give one log or map");
  const maps::CropMap map = LoadInput(args.inputs[0], args);
  std::optional<maps::GeoAnchorOptions> anchor = args.origin.empty() ? StoredAnchor(map) : ParseOrigin(args.origin);
  if (anchor) {
    if (args.heading_deg) anchor->heading_deg = *args.heading_deg;
    anchor->epsg = args.epsg;
    ThrowIfInvalid("command line (--origin, --heading, --epsg)", anchor->Validate());
  }
  ArchiveExportArgs a;
  a.input = args.inputs[0];
  a.is_log = IsLcmLog(a.input);
  a.to = args.to;
  a.field = args.field;
  a.bed = args.bed;
  a.match_m = args.match_m;
  a.quiet = args.quiet;
  return ExportToArchive(a, map, anchor);
}

int Export(const ExportArgs& args) {
  if (!args.to.empty()) return ExportArchive(args);
  if (args.out.empty()) throw ConfigError("export", "--out", "give the output folder (--out DIR) or an archive (--to)");
  std::vector<maps::CropMap> inputs;
  for (const std::string& input : args.inputs) inputs.push_back(LoadInput(input, args));
  // Moved, not copied: a km-long map is hundreds of MB.
  const maps::CropMap map = inputs.size() == 1 ? std::move(inputs[0]) : maps::MergeMaps(inputs);
  const maps::ExportOptions options = MakeOptions(args, map);
  ThrowIfInvalid("command line (--format, --origin, --heading, --epsg)", options.Validate());
  ProgressBar bar(std::cerr, "export", static_cast<int>(options.formats.size()), !args.quiet);
  const maps::ExportResult result = maps::ExportMap(
      map, args.out, options, [&bar](int done, int, const std::string&) { bar.Update(done); });
  bar.Finish();
  PrintResult(map, result);
  return 0;
}

}  // namespace

void AddExportCommands(CommandRegistry& registry) {
  ExportArgs& args = registry.Keep(ExportArgs{});
  CLI::App* cmd = registry.Add(
      "export", "export crop maps (GeoTIFF, GeoPackage, GeoJSON, CSV, PNG, ISOXML, native map)",
      [&args] {
        try {
          return Export(args);
        } catch (const DataError& e) {  // corrupt or malformed input: bad input, exit 2
          throw ConfigError("export", "LOG_OR_MAP", e.what());
        } catch (const telemetry::LogError& e) {  // unreadable or not an LCM log
          throw ConfigError("export", "LOG_OR_MAP", e.what());
        }
      });
  cmd->add_option("LOG_OR_MAP", args.inputs,
                  "LCM log of a run, map file (.psmap) or simulator output folder; several are merged")
      ->required();
  cmd->add_option("--out", args.out, "output folder");
  cmd->add_option("--to", args.to,
                  "season archive instead of files: postgresql://USER:PASSWORD@HOST:PORT/DB or FILE.gpkg "
                  "(docs/cli/archive.md)");
  cmd->add_option("--field", args.field, "field name of the run (with --to)");
  cmd->add_option("--bed", args.bed, "bed number of the run (with --to)")->capture_default_str();
  cmd->add_option("--match-m", args.match_m,
                  "plants of two runs closer than this are one plant (with --to), metres")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--format", args.formats,
                  "comma-separated: gtiff,northup,gpkg,geojson,csv,png,isoxml,map (default: all)");
  cmd->add_option("--origin", args.origin, "WGS84 LAT,LON of the field-frame origin (degrees)");
  cmd->add_option("--heading", args.heading_deg,
                  "direction of the field +y axis (along the rows), degrees clockwise from "
                  "true north (default " + HelpNumber(maps::GeoAnchorOptions{}.heading_deg) + ")");
  cmd->add_option("--epsg", args.epsg, "projected CRS of the exports (default: UTM zone)");
  cmd->add_option("--resolution-m", args.resolution_m, "map cell size for simulator input")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--rate-l-ha", args.rate_l_per_ha, "ISOXML setpoint of treated cells, L/ha")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--isoxml-cell-m", args.isoxml_cell_m,
                  "ISOXML grid cell size, metres (default: the map's resolution)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--quiet", args.quiet, "no progress");
}

}  // namespace plantscale::app
