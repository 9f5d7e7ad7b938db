#pragma once
// The raster geometry of a crop map (the Cartographer habit: one value type
// owns resolution, origin and extent, and all cell↔world maths).
//
// Field frame (docs/design.md §3): x right, across the rows; y forward, along the
// rows; metres; fixed at run start. Cell (col, row) covers
//   x ∈ [origin_x + col·res, origin_x + (col+1)·res),
//   y ∈ [origin_y + row·res, origin_y + (row+1)·res),
// so row 0 is the southern-most (smallest y) row of cells and the origin is
// the corner of cell (0, 0), not its centre.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "engine/common/options.h"

namespace plantscale::maps {

struct Cell {
  int col = 0;
  int row = 0;
  bool operator==(const Cell&) const = default;
};

struct MapGridOptions {
  static constexpr int kMaxCols = 1 << 15;
  static constexpr int kMaxRows = 1 << 22;
  static constexpr int64_t kMaxCells = int64_t{1} << 30;

  double resolution_m = 0.02;          // edge of a square cell
  Eigen::Vector2d origin_m{0.0, 0.0};  // field-frame corner of cell (0, 0)
  int cols = 1;                        // cells along x
  int rows = 1;                        // cells along y

  OptionErrors Validate() const;
};

class MapGrid {
 public:
  // Throws InvalidOptionsError (keys: resolution_m, origin_m, cols, rows).
  explicit MapGrid(const MapGridOptions& options);
  // The smallest grid of `resolution_m` whose cells are aligned on multiples
  // of the resolution and which covers [min, max] (field frame).
  static MapGrid Covering(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m,
                          double resolution_m);

  double resolution_m() const { return options_.resolution_m; }
  const Eigen::Vector2d& origin_m() const { return options_.origin_m; }
  int cols() const { return options_.cols; }
  int rows() const { return options_.rows; }
  size_t size() const { return static_cast<size_t>(cols()) * static_cast<size_t>(rows()); }
  const MapGridOptions& options() const { return options_; }
  Eigen::Vector2d extent_m() const { return {cols() * resolution_m(), rows() * resolution_m()}; }
  Eigen::Vector2d max_m() const { return origin_m() + extent_m(); }

  // Cell containing a field point (floor); no bounds check.
  Cell CellAt(const Eigen::Vector2d& field_m) const;
  // Cell containing a field point, or nothing when outside the grid.
  std::optional<Cell> FindCell(const Eigen::Vector2d& field_m) const;
  Eigen::Vector2d CellCentre(const Cell& cell) const;
  Eigen::Vector2d CellCorner(const Cell& cell) const;  // min x, min y corner
  bool Contains(const Cell& cell) const;
  // Row-major index, row 0 first: index = row·cols + col.
  size_t Index(const Cell& cell) const;
  Cell CellOf(size_t index) const;

  bool operator==(const MapGrid& other) const;

 private:
  MapGridOptions options_;
};

}  // namespace plantscale::maps
