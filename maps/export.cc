#include "maps/export.h"

#include <algorithm>
#include <charconv>

#include "maps/map_file.h"
#include "maps/staged_output.h"
#include "maps/writers.h"

namespace plantscale::maps {
namespace fs = std::filesystem;

std::string ExactText(double value) {
  char buf[32];
  const auto result = std::to_chars(buf, buf + sizeof buf, value);
  return std::string(buf, result.ptr);
}

OptionErrors IsoxmlOptions::Validate() const {
  OptionErrors errors;
  RequireNonNegative(errors, "rate_l_per_ha", rate_l_per_ha);
  RequireNonNegative(errors, "cell_size_m", cell_size_m);
  return errors;
}

const std::vector<std::string>& AllExportFormats() {
  static const std::vector<std::string> all{"gtiff", "northup", "gpkg", "geojson",
                                            "csv",   "png",     "isoxml", "map"};
  return all;
}

bool NeedsGeoreference(const std::string& format) { return format != "png" && format != "map"; }

OptionErrors ExportOptions::Validate() const {
  OptionErrors errors;
  if (formats.empty()) errors.push_back({"formats", "no format requested"});
  bool needs_anchor = false;
  for (const std::string& f : formats) {
    const auto& all = AllExportFormats();
    if (std::find(all.begin(), all.end(), f) == all.end()) {
      errors.push_back({"formats", "unknown format '" + f +
                                       "' (known: gtiff, northup, gpkg, geojson, csv, png, isoxml, map)"});
    }
    needs_anchor = needs_anchor || NeedsGeoreference(f);
  }
  if (anchor) {
    for (OptionError& e : Prefixed("anchor", anchor->Validate())) errors.push_back(e);
  } else if (needs_anchor) {
    errors.push_back({"anchor", "georeferenced formats need an origin (--origin LAT,LON)"});
  }
  for (OptionError& e : Prefixed("isoxml", isoxml.Validate())) errors.push_back(e);
  return errors;
}

namespace {

const char* FileOf(const std::string& format) {
  if (format == "gtiff") return "map.tif";
  if (format == "northup") return "map_northup.tif";
  if (format == "gpkg") return "map.gpkg";
  if (format == "geojson") return "plants.geojson";
  if (format == "csv") return "plants.csv";
  if (format == "png") return "map.png";
  if (format == "isoxml") return "TASKDATA";
  return "map.psmap";
}

CropMap WithAnchor(const CropMap& map, const Georeference& georef) {
  CropMap copy = map;
  const GeoAnchorOptions& a = georef.options();
  copy.SetMetadata("origin_lat_deg", ExactText(a.latitude_deg));
  copy.SetMetadata("origin_lon_deg", ExactText(a.longitude_deg));
  copy.SetMetadata("heading_deg", ExactText(a.heading_deg));
  return copy;
}

void WriteFormat(const std::string& format, const CropMap& map, const Georeference* georef,
                 const ExportOptions& options, const fs::path& path) {
  if (format == "gtiff") WriteGeoTiff(map, *georef, path);
  if (format == "northup") WriteNorthUpGeoTiff(map, *georef, path);
  if (format == "gpkg") WriteGeoPackage(map, *georef, path);
  if (format == "geojson") WriteGeoJson(map, *georef, path);
  if (format == "csv") WritePlantsCsv(map, *georef, path);
  if (format == "png") WritePng(map, georef, path);
  if (format == "isoxml") WriteIsoxml(map, *georef, options.isoxml, path);
  if (format == "map") SaveMap(georef != nullptr ? WithAnchor(map, *georef) : map, path);
}

}  // namespace

ExportResult ExportMap(const CropMap& map, const fs::path& dir, const ExportOptions& options,
                       const ExportProgress& progress) {
  ThrowIfInvalid("export options", options.Validate());
  std::optional<Georeference> georef;
  if (options.anchor) georef.emplace(*options.anchor);  // checks the EPSG code
  ExportResult result;
  StagedFolder staged(dir);
  const int total = static_cast<int>(options.formats.size());
  for (int i = 0; i < total; ++i) {
    const std::string& format = options.formats[static_cast<size_t>(i)];
    if (progress) progress(i, total, format);
    WriteFormat(format, map, georef ? &*georef : nullptr, options, staged.Stage(FileOf(format)));
  }
  if (progress) progress(total, total, "");
  result.files = staged.Commit();
  if (georef) {
    result.epsg = georef->epsg();
    georef->GeoTransform(map.grid(), &result.geotransform_error_m);
  }
  return result;
}

}  // namespace plantscale::maps
