#include "maps/map_grid.h"

#include <cmath>

#include "engine/common/check.h"

namespace plantscale::maps {

OptionErrors MapGridOptions::Validate() const {
  OptionErrors errors;
  RequirePositive(errors, "resolution_m", resolution_m);
  RequireFinite(errors, "origin_m.x", origin_m.x());
  RequireFinite(errors, "origin_m.y", origin_m.y());
  // 2^15 cells a side: 655 m at 2 cm, far beyond one bed.
  RequireInRange(errors, "cols", cols, 1, 32768);
  RequireInRange(errors, "rows", rows, 1, 32768);
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
  o.cols = static_cast<int>(std::floor(max_m.x() / resolution_m) - x0) + 1;
  o.rows = static_cast<int>(std::floor(max_m.y() / resolution_m) - y0) + 1;
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
