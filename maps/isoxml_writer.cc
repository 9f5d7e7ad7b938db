// ISO 11783-10 (ISOXML) task with a type-2 grid of the treated area.
//
// What we write (ISO 11783-10:2015, v4 data dictionary; element and
// attribute letters as the standard's XML schema names them):
//   TASKDATA/TASKDATA.XML
//     ISO11783_TaskData VersionMajor=4 VersionMinor=2 DataTransferOrigin=1 (FMIS)
//       PDT A=PDT1 B="spot spray"                      product
//       TSK A=TSK1 B=<designator> G=1 (planned)        task
//         TZN A=1 B="treated area rate"                template zone of the grid
//           PDV A=0001 B=<rate> C=PDT1                 DDI 1: setpoint volume per
//                                                      area, mm³/m²
//         GRD A=<min north °> B=<min east °> C=<cell north °> D=<cell east °>
//             E=<columns> F=<rows> G=GRD00001 H=<file bytes> I=2 J=1
//   TASKDATA/GRD00001.BIN
//     grid type 2: per cell one little-endian int32 per PDV of TZN J (here
//     one: the rate), rows from the southern-most northwards, columns west
//     to east.
// The field frame is rotated by the heading, an ISOXML grid is aligned
// with north and east (WGS84 degrees): we write the north-aligned bounding
// grid of the map, cells of cell_size_m converted to degrees at the origin,
// and a cell is treated when its centre falls in a treated map cell.
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "maps/export.h"
#include "maps/map_errors.h"
#include "maps/writers.h"

namespace plantscale::maps {
namespace fs = std::filesystem;
namespace {

struct IsoGrid {
  double min_lat = 0.0;
  double min_lon = 0.0;
  double cell_lat = 0.0;
  double cell_lon = 0.0;
  int cols = 0;
  int rows = 0;
};

IsoGrid BoundingGrid(const MapGrid& g, const Georeference& georef, double cell_m) {
  double lat0 = 90.0, lat1 = -90.0, lon0 = 180.0, lon1 = -180.0;
  for (const Eigen::Vector2d& c :
       {g.origin_m(), g.max_m(), Eigen::Vector2d(g.origin_m().x(), g.max_m().y()),
        Eigen::Vector2d(g.max_m().x(), g.origin_m().y())}) {
    const Eigen::Vector2d ll = georef.FieldToWgs84(c);
    lon0 = std::min(lon0, ll.x()), lon1 = std::max(lon1, ll.x());
    lat0 = std::min(lat0, ll.y()), lat1 = std::max(lat1, ll.y());
  }
  // Degrees per metre at the origin along true north and east.
  const Eigen::Vector2d o = georef.FieldToWgs84({0.0, 0.0});
  const Eigen::Vector2d north = georef.FieldToWgs84(georef.LocalToField({0.0, 1.0})) - o;
  const Eigen::Vector2d east = georef.FieldToWgs84(georef.LocalToField({1.0, 0.0})) - o;
  IsoGrid grid{lat0, lon0, cell_m * north.y(), cell_m * east.x(), 0, 0};
  grid.cols = static_cast<int>(std::ceil((lon1 - lon0) / grid.cell_lon));
  grid.rows = static_cast<int>(std::ceil((lat1 - lat0) / grid.cell_lat));
  return grid;
}

// One grid row (west to east) of setpoints: the rate where the cell centre
// lies in a treated map cell, else 0, as little-endian int32.
void RowBytes(const CropMap& map, const Georeference& georef, const IsoGrid& iso, int32_t rate, int r,
              std::vector<char>& out) {
  std::vector<Eigen::Vector2d> centres(static_cast<size_t>(iso.cols));
  for (int c = 0; c < iso.cols; ++c) {
    centres[static_cast<size_t>(c)] = {iso.min_lon + (c + 0.5) * iso.cell_lon, iso.min_lat + (r + 0.5) * iso.cell_lat};
  }
  out.clear();
  for (const Eigen::Vector2d& f : georef.Wgs84ToField(centres)) {
    const auto cell = map.grid().FindCell(f);
    const bool treated = cell && map.layers().treated[map.grid().Index(*cell)] != 0;
    const auto u = static_cast<uint32_t>(treated ? rate : 0);
    for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<char>((u >> shift) & 0xff));
  }
}

// Streams the grid row by row (southern-most first): a km-long grid never
// sits in memory whole.
size_t WriteBinary(const fs::path& file, const CropMap& map, const Georeference& georef, const IsoGrid& iso,
                   int32_t rate) {
  std::ofstream out(file, std::ios::binary);
  if (!out) throw MapIoError(file.string(), "cannot be created");
  std::vector<char> row;
  size_t bytes = 0;
  for (int r = 0; r < iso.rows && out; ++r) {
    RowBytes(map, georef, iso, rate, r, row);
    out.write(row.data(), static_cast<std::streamsize>(row.size()));
    bytes += row.size();
  }
  out.close();
  if (!out) throw MapIoError(file.string(), "write failed (disk full?)");
  return bytes;
}

std::string Escape(const std::string& text) {
  std::string out;
  for (char ch : text) {
    if (ch == '&')
      out += "&amp;";
    else if (ch == '<')
      out += "&lt;";
    else if (ch == '>')
      out += "&gt;";
    else if (ch == '"')
      out += "&quot;";
    else
      out += ch;
  }
  return out;
}

std::string TaskXml(const CropMap& map, const IsoGrid& g, int32_t rate, size_t bytes) {
  const auto src = map.metadata().find("source");
  const std::string name =
      "plantscale treated area" + (src != map.metadata().end() ? " (" + src->second + ")" : "");
  std::ostringstream x;
  x << std::fixed << std::setprecision(9) << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<ISO11783_TaskData VersionMajor=\"4\" VersionMinor=\"2\" "
       "ManagementSoftwareManufacturer=\"plantscale\" ManagementSoftwareVersion=\"0.1.0\" "
       "DataTransferOrigin=\"1\">\n"
    << "  <PDT A=\"PDT1\" B=\"spot spray\"/>\n"
    << "  <TSK A=\"TSK1\" B=\"" << Escape(name) << "\" G=\"1\">\n"
    << "    <TZN A=\"1\" B=\"treated area rate\">\n"
    << "      <PDV A=\"0001\" B=\"" << rate << "\" C=\"PDT1\"/>\n"
    << "    </TZN>\n"
    << "    <GRD A=\"" << g.min_lat << "\" B=\"" << g.min_lon << "\" C=\"" << std::setprecision(14)
    << g.cell_lat << "\" D=\"" << g.cell_lon << "\" E=\"" << g.cols << "\" F=\"" << g.rows
    << "\" G=\"GRD00001\" H=\"" << bytes << "\" I=\"2\" J=\"1\"/>\n"
    << "  </TSK>\n</ISO11783_TaskData>\n";
  return x.str();
}

// A long run at a heading far from north or east has a huge north-aligned
// bounding grid (5 km at 45 degrees and 1.33 cm: 7e10 cells): refused with
// the cell size that would fit, instead of filling the disk.
void CheckGridSize(const IsoGrid& grid, double cell_m) {
  constexpr double kMaxCells = 2e8;  // 800 MB of int32 setpoints
  const double cells = static_cast<double>(grid.cols) * grid.rows;
  if (cells <= kMaxCells) return;
  const double fits = cell_m * std::sqrt(cells / kMaxCells) * 1.01;
  std::ostringstream why;
  why << "the ISOXML grid would be " << grid.cols << " x " << grid.rows << " cells of " << cell_m
      << " m (more than 2e8); give --isoxml-cell-m " << std::setprecision(3) << fits << " or more";
  ThrowIfInvalid("ISOXML export", {{"isoxml.cell_size_m", why.str()}});
}

}  // namespace

void WriteIsoxml(const CropMap& map, const Georeference& georef, const IsoxmlOptions& options,
                 const fs::path& folder) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw MapIoError(folder.string(), "cannot create folder: " + ec.message());
  const double cell_m = options.cell_size_m > 0 ? options.cell_size_m : map.grid().resolution_m();
  const IsoGrid grid = BoundingGrid(map.grid(), georef, cell_m);
  CheckGridSize(grid, cell_m);
  const auto rate = static_cast<int32_t>(std::lround(options.rate_l_per_ha * 100.0));
  const size_t bytes = WriteBinary(folder / "GRD00001.BIN", map, georef, grid, rate);
  const fs::path xml = folder / "TASKDATA.XML";
  std::ofstream out(xml, std::ios::binary);
  if (!out) throw MapIoError(xml.string(), "cannot be created");
  out << TaskXml(map, grid, rate, bytes);
  out.close();
  if (!out) throw MapIoError(xml.string(), "write failed (disk full?)");
}

}  // namespace plantscale::maps
