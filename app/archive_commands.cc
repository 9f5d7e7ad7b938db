#include "app/archive_commands.h"

#include <algorithm>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "app/archive_run.h"
#include "app/config/config_loader.h"
#include "maps/archive.h"

namespace plantscale::app {
namespace {

using nlohmann::json;

struct QueryArgs {
  std::vector<std::string> to;  // the archive, and optionally the last date
  std::string field, from;
  bool json = false;
};

struct PlantArgs {
  int64_t id = 0;
  std::string to;
  bool json = false;
};

struct SeasonExportArgs {
  std::string to, field, out;
};

// `--to` names the archive and, given a second time as YYYY-MM-DD, the last date.
void SplitTo(const std::vector<std::string>& to, std::string& target, std::string& until) {
  static const std::regex date(R"(\d{4}-\d{2}-\d{2})");
  for (const std::string& t : to) {
    std::string& slot = std::regex_match(t, date) ? until : target;
    if (!slot.empty()) throw ConfigError("archive query", "--to", "given twice as " + std::string(&slot == &until ? "a date" : "an archive"));
    slot = t;
  }
  if (target.empty()) throw ConfigError("archive query", "--to", "no archive (postgresql://… or FILE.gpkg)");
}

json RunJson(const maps::ArchivedRun& r) {
  const maps::ArchiveFigures& f = r.figures;
  return {{"run_id", r.run_id},        {"start_time", r.start_time},   {"end_time", r.end_time},
          {"vehicle", r.vehicle},      {"crop_profile", r.crop_profile}, {"bed", r.bed},
          {"source", r.source},        {"distance_m", r.distance_m},    {"plants", f.crop},
          {"plants_per_m", f.plants_per_m}, {"gaps", f.gaps},          {"missing", f.missing},
          {"median_size_m", f.median_radius_m}, {"weeds", f.weeds},     {"weeds_per_m2", f.weeds_per_m2},
          {"area_treated_m2", f.area_treated_m2}, {"treated_plants", f.treated_plants}};
}

json BedsJson(const std::vector<maps::ArchivedRun>& runs) {
  std::map<int, std::vector<const maps::ArchivedRun*>> beds;
  for (const maps::ArchivedRun& r : runs) beds[r.bed].push_back(&r);
  json out = json::array();
  for (const auto& [bed, list] : beds) {
    double treated = 0.0;
    for (const maps::ArchivedRun* r : list) treated += r->figures.area_treated_m2;
    out.push_back({{"bed", bed}, {"runs", list.size()}, {"first", RunJson(*list.front())},
                   {"last", RunJson(*list.back())}, {"area_treated_m2", treated}});
  }
  return out;
}

std::string Fixed(double v, int decimals) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(decimals) << v;
  return o.str();
}

void PrintRunsTable(const std::vector<maps::ArchivedRun>& runs) {
  std::cout << std::left << std::setw(21) << "start" << std::setw(17) << "run" << std::setw(14) << "vehicle"
            << std::right << std::setw(4) << "bed" << std::setw(7) << "plants" << std::setw(10) << "plants/m"
            << std::setw(6) << "gaps" << std::setw(13) << "median size" << std::setw(10) << "weeds/m²"
            << std::setw(13) << "treated m²" << "\n";
  for (const maps::ArchivedRun& r : runs) {
    const maps::ArchiveFigures& f = r.figures;
    std::cout << std::left << std::setw(21) << (r.start_time.empty() ? "-" : r.start_time) << std::setw(17)
              << r.run_id << std::setw(14) << (r.vehicle.empty() ? "-" : r.vehicle) << std::right << std::setw(4)
              << r.bed << std::setw(7) << f.crop << std::setw(10) << Fixed(f.plants_per_m, 2) << std::setw(6)
              << f.gaps << std::setw(11) << Fixed(100.0 * f.median_radius_m, 1) << " cm" << std::setw(9)
              << Fixed(f.weeds_per_m2, 2) << std::setw(12) << Fixed(f.area_treated_m2, 3) << "\n";
  }
}

int Query(const QueryArgs& args) {
  std::string target, until;
  SplitTo(args.to, target, until);
  const std::vector<maps::ArchivedRun> runs = maps::QueryRuns(target, args.field, args.from, until);
  if (args.json) {
    json runs_json = json::array();
    for (const maps::ArchivedRun& r : runs) runs_json.push_back(RunJson(r));
    std::cout << json{{"field", args.field}, {"from", args.from}, {"to", until}, {"runs", runs_json},
                      {"beds", BedsJson(runs)}}.dump(2) << "\n";
    return 0;
  }
  std::cout << "field '" << args.field << "': " << runs.size() << " run(s)";
  if (!args.from.empty() || !until.empty()) std::cout << " from " << (args.from.empty() ? "the start" : args.from) << " to " << (until.empty() ? "now" : until);
  std::cout << " in " << maps::Redacted(target) << "\n";
  if (runs.empty()) return 0;
  PrintRunsTable(runs);
  std::cout << "per bed (first -> last run):\n";
  for (const json& b : BedsJson(runs)) {
    const json &f = b["first"], &l = b["last"];
    std::cout << "  bed " << b["bed"].get<int>() << ": " << b["runs"].get<int>() << " run(s); plants "
              << f["plants"].get<int>() << " -> " << l["plants"].get<int>() << ", plants/m "
              << Fixed(f["plants_per_m"], 2) << " -> " << Fixed(l["plants_per_m"], 2) << ", gaps "
              << f["gaps"].get<int>() << " -> " << l["gaps"].get<int>() << ", median size "
              << Fixed(100.0 * f["median_size_m"].get<double>(), 1) << " -> "
              << Fixed(100.0 * l["median_size_m"].get<double>(), 1) << " cm, weeds/m² "
              << Fixed(f["weeds_per_m2"], 2) << " -> " << Fixed(l["weeds_per_m2"], 2) << ", treated "
              << Fixed(b["area_treated_m2"], 3) << " m² in all\n";
  }
  return 0;
}

int Plant(const PlantArgs& args) {
  const maps::PlantHistory h = maps::QueryPlant(args.to, args.id);
  if (args.json) {
    json sightings = json::array();
    for (const maps::PlantSighting& s : h.sightings) {
      sightings.push_back({{"run_id", s.run_id}, {"start_time", s.start_time}, {"vehicle", s.vehicle},
                           {"bed", s.bed}, {"plant_id", s.plant_id}, {"class", s.cls},
                           {"size_m", s.radius_m}, {"treated", s.treated}, {"why", s.why}});
    }
    std::cout << json{{"id", h.season_id}, {"field", h.field}, {"class", h.cls}, {"lon_deg", h.lon_deg},
                      {"lat_deg", h.lat_deg}, {"field_x_m", h.field_x_m}, {"field_y_m", h.field_y_m},
                      {"times_treated", h.times_treated}, {"sightings", sightings}}.dump(2) << "\n";
    return 0;
  }
  std::cout << "plant " << h.season_id << " of field '" << h.field << "': " << h.cls << " at "
            << std::setprecision(9) << h.lat_deg << ", " << h.lon_deg << " (field x " << Fixed(h.field_x_m, 3)
            << " m, y " << Fixed(h.field_y_m, 3) << " m); seen in " << h.sightings.size() << " run(s), sprayed "
            << h.times_treated << " time(s)\n";
  for (const maps::PlantSighting& s : h.sightings) {
    std::cout << "  " << (s.start_time.empty() ? "-" : s.start_time) << "  run " << s.run_id << "  bed " << s.bed
              << "  " << s.cls << "  size " << Fixed(100.0 * s.radius_m, 1) << " cm  "
              << (s.treated ? "sprayed" : "not sprayed") << " (" << s.why << ")\n";
  }
  return 0;
}

int SeasonExport(const SeasonExportArgs& args) {
  const std::filesystem::path file = maps::ExportSeason(args.to, args.field, args.out);
  std::cout << "plantscale archive export: field '" << args.field << "'\n  wrote " << file.string() << "\n";
  return 0;
}

void AddQuery(CommandRegistry& registry, CLI::App* archive) {
  QueryArgs& args = registry.Keep(QueryArgs{});
  CLI::App* cmd = registry.Add("query", "per run and per bed: plants, plants per metre, gaps, median size, "
                               "weeds per m², area treated", [&args] { return Query(args); }, archive);
  cmd->add_option("--to", args.to, "the archive (postgresql://… or FILE.gpkg); again as YYYY-MM-DD: the last date")
      ->required();
  cmd->add_option("--field", args.field, "field name")->required();
  cmd->add_option("--from", args.from, "first date, YYYY-MM-DD (runs starting that day or later)");
  cmd->add_flag("--json", args.json, "JSON instead of a table");
}

void AddPlant(CommandRegistry& registry, CLI::App* archive) {
  PlantArgs& args = registry.Keep(PlantArgs{});
  CLI::App* cmd = registry.Add("plant", "one plant's history over the season (size, treatments)",
                               [&args] { return Plant(args); }, archive);
  cmd->add_option("ID", args.id, "season plant id (season_id in the archive)")->required();
  cmd->add_option("--to", args.to, "the archive (postgresql://… or FILE.gpkg)")->required();
  cmd->add_flag("--json", args.json, "JSON instead of text");
}

void AddSeasonExport(CommandRegistry& registry, CLI::App* archive) {
  SeasonExportArgs& args = registry.Keep(SeasonExportArgs{});
  CLI::App* cmd = registry.Add("export", "the season's maps of a field as a GeoPackage (for QGIS)",
                               [&args] { return SeasonExport(args); }, archive);
  cmd->add_option("--to", args.to, "the archive (postgresql://… or FILE.gpkg)")->required();
  cmd->add_option("--field", args.field, "field name")->required();
  cmd->add_option("--out", args.out, "output folder (gets FIELD.gpkg)")->required();
}

}  // namespace

int ExportToArchive(const ArchiveExportArgs& args, const maps::CropMap& map,
                    const std::optional<maps::GeoAnchorOptions>& anchor) {
  if (args.field.empty()) throw ConfigError("export", "--field", "--to needs the field name (--field NAME)");
  maps::ArchiveRun run = args.is_log ? ArchiveRunFromLog(args.input) : ArchiveRunFromMap(args.input, map);
  run.field = args.field;
  run.bed = args.bed;
  maps::ArchiveOptions options;
  options.match_tolerance_m = args.match_m;
  const maps::AppendResult r = maps::AppendRun(args.to, run, map, anchor, options);
  std::cout << "plantscale export: run " << run.run_id << " of field '" << run.field << "' bed " << run.bed
            << (r.replaced ? " replaced" : " added") << ": " << r.plants << " plants (" << r.matched
            << " matched to plants of earlier runs within " << args.match_m << " m, " << r.new_plants
            << " new; run aligned by " << Fixed(r.offset_m.x(), 3) << ", " << Fixed(r.offset_m.y(), 3)
            << " m), field frame " << r.field_origin << "\n  into " << maps::Redacted(args.to) << "\n";
  return 0;
}

void AddArchiveCommands(CommandRegistry& registry) {
  CLI::App* archive = registry.Add("archive", "the season archive: query runs, a plant's history, season maps",
                                   nullptr);
  archive->require_subcommand(1);
  AddQuery(registry, archive);
  AddPlant(registry, archive);
  AddSeasonExport(registry, archive);
}

}  // namespace plantscale::app
