#include "maps/map_grid.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/common/check.h"

namespace plantscale::maps {

OptionErrors MapGridOptions::Validate() const {
  OptionErrors errors;
  RequirePositive(errors, "resolution_m", resolution_m);
  RequireFinite(errors, "origin_m.x", origin_m.x());
  RequireFinite(errors, "origin_m.y", origin_m.y());
  // Across the rows 2^15 cells (437 m at the vehicle's 1.333 cm: wider than
  // any bed); along them 2^22 (55.9 km): a day's run of one bed. The cell
  // count is capped so a map's layers (6 bytes a cell) stay within memory.
  RequireInRange(errors, "cols", cols, 1, kMaxCols);
  RequireInRange(errors, "rows", rows, 1, kMaxRows);
  if (cols >= 1 && rows >= 1 && static_cast<double>(cols) * rows > static_cast<double>(kMaxCells)) {
    errors.push_back({"cells", std::to_string(cols) + " x " + std::to_string(rows) +
                                   " cells exceed the limit of " + std::to_string(kMaxCells) +
                                   " (use coarser cells)"});
  }
  return errors;
}

MapGrid::MapGrid(const MapGridOptions& options) : options_(options) {
  ThrowIfInvalid("map grid", options_.Validate());
}

MapGrid MapGrid::Covering(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m,
                          double resolution_m) {
  MapGridOptions o;
  o.resolution_m = resolution_m;
  const double x0 = std::floor(min_m.x() / resolution_m);
  const double y0 = std::floor(min_m.y() / resolution_m);
  o.origin_m = {x0 * resolution_m, y0 * resolution_m};
  // Clamped before the cast so an absurd extent is refused by Validate, not overflowed.
  auto count = [](double cells) {
    return std::isfinite(cells) ? static_cast<int>(std::clamp(cells, 0.0, 2147483647.0)) : 0;
  };
  o.cols = count(std::floor(max_m.x() / resolution_m) - x0 + 1);
  o.rows = count(std::floor(max_m.y() / resolution_m) - y0 + 1);
  return MapGrid(o);
}

Cell MapGrid::CellAt(const Eigen::Vector2d& field_m) const {
  const Eigen::Vector2d local = (field_m - origin_m()) / resolution_m();
  return {static_cast<int>(std::floor(local.x())), static_cast<int>(std::floor(local.y()))};
}

std::optional<Cell> MapGrid::FindCell(const Eigen::Vector2d& field_m) const {
  if (!field_m.allFinite()) return std::nullopt;
  const Eigen::Vector2d local = (field_m - origin_m()) / resolution_m();
  if (local.x() < 0 || local.y() < 0 || local.x() >= cols() || local.y() >= rows()) {
    return std::nullopt;
  }
  return CellAt(field_m);
}

Eigen::Vector2d MapGrid::CellCorner(const Cell& cell) const {
  return origin_m() + resolution_m() * Eigen::Vector2d(cell.col, cell.row);
}

Eigen::Vector2d MapGrid::CellCentre(const Cell& cell) const {
  return origin_m() + resolution_m() * Eigen::Vector2d(cell.col + 0.5, cell.row + 0.5);
}

bool MapGrid::Contains(const Cell& cell) const {
  return cell.col >= 0 && cell.row >= 0 && cell.col < cols() && cell.row < rows();
}

size_t MapGrid::Index(const Cell& cell) const {
  PLANTSCALE_CHECK(Contains(cell), "cell outside the map grid");
  return static_cast<size_t>(cell.row) * static_cast<size_t>(cols()) +
         static_cast<size_t>(cell.col);
}

Cell MapGrid::CellOf(size_t index) const {
  PLANTSCALE_CHECK(index < size(), "cell index outside the map grid");
  const size_t c = static_cast<size_t>(cols());
  return {static_cast<int>(index % c), static_cast<int>(index / c)};
}

bool MapGrid::operator==(const MapGrid& other) const {
  return resolution_m() == other.resolution_m() && origin_m() == other.origin_m() &&
         cols() == other.cols() && rows() == other.rows();
}

}  // namespace plantscale::maps
