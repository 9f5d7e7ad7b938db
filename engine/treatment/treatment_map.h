#pragma once
// The treatment map (thesis §8.2, after Hague): a grid of counters over the
// bed in the bed frame (bed_frame.h), 13.33 mm cells by default. Each frame,
// every classified blob's footprint adds one to the crop or the weed counter
// of the cells whose centre it covers, so a plant seen in many frames
// accumulates. A cell's class is the larger counter when it reaches its
// class's threshold (a tie goes to crop: the crop is what must not be
// wronged), and soil otherwise; a crop cell must also tie or outvote the
// weed and doubt counters together (CellCounts::doubt). The map grows
// along the bed as the vehicle drives, and keeps a window of it: rows behind
// the bar are final, and ForgetBefore lets them go (a day's run of bed in
// bounded memory). Rows are numbered from start_y_m over the whole bed.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/common/options.h"
#include "engine/common/plant_class.h"
#include "engine/treatment/bed_frame.h"

namespace plantscale::treatment {

// A cell of the map: soil, crop or weed (engine/common/plant_class.h).
using CellClass = SoilCropWeed;
using plantscale::ToString;

struct TreatmentMapOptions {
  double cell_m = 0.01333;   // thesis: 256 × 3000 cells of 13.33 mm
  double width_m = 3.4;      // across, centred on the central row
  double start_y_m = -5.0;   // bed y of the first cell row (behind the start)
  int majority_threshold = 3;  // counts a class needs before a cell is not soil
  // ... and a weed cell (0: majority_threshold). Spray-weed mode sprays
  // weed cells, and a weed missed costs more than a drop of herbicide;
  // weed votes come from weed-sized blobs and from merged blobs' plant
  // matter beyond every crop (TreatmentOptions::merged_weed_parts_only).
  // One vote hits the most weeds for a little more bed treated
  // (docs/results/2026-11-27-option-choices.md). Spray-crop mode is
  // untouched: a crop cell still needs majority_threshold and to tie or
  // outvote the weed and doubt counters together.
  int weed_majority_threshold = 1;

  OptionErrors Validate() const;
};

struct CellCounts {
  uint16_t crop = 0;
  uint16_t weed = 0;
  // Votes against crop that are no weed's: the box of touching plants
  // merged into one blob, beyond the footprints of the crops in it.
  uint16_t doubt = 0;
};

// A footprint as the cells of each map column it covers: the y range of
// cell centres inside it, so that it can be counted anywhere along the bed
// without testing every cell against the quad again (a plant's footprints
// that follow it along, TreatmentOptions::crop_footprint_follows_plant).
struct ColumnSpan {
  int column = 0;
  double y0_m = 0.0, y1_m = 0.0;  // bed y of the column's edge inside the footprint, relative
};

class TreatmentMap {
 public:
  // Throws InvalidOptionsError.
  explicit TreatmentMap(const TreatmentMapOptions& options);

  // Adds one vote to every cell whose centre lies inside the convex quad
  // (bed frame). Returns the number of cells counted.
  int AddFootprint(const Quad& bed_quad, bool crop);
  // Adds one doubt vote (CellCounts::doubt) to the same cells.
  int AddDoubt(const Quad& bed_quad);
  // The quad's spans, its bed y measured from `along_m`: where the line
  // down the middle of each column it reaches crosses it.
  void AppendSpans(const Quad& bed_quad, double along_m, std::vector<ColumnSpan>& out) const;
  // Adds `votes` (negative: takes back) to the cells whose centres lie in
  // the spans moved to `along_m`, counters kept within [0, 65535]. The same
  // spans at the same along_m count the same cells as AddFootprint of the
  // quad, but for centres on its boundary.
  int AddSpans(std::span<const ColumnSpan> spans, double along_m, int votes, bool crop);
  void Clear();
  // Lets the rows before `row` go: they read as unobserved soil from then on
  // and are never counted again. The map keeps at most 100 000 rows (1.3 km
  // at 13 mm cells) at once; beyond them nothing is counted.
  void ForgetBefore(int row);
  int first_row() const { return first_row_; }

  // Cell (column, row) of a bed point; false outside the map across or
  // behind its start (ahead it grows on demand when counting).
  bool CellOf(const Eigen::Vector2d& bed_m, int& column, int& row) const;
  Eigen::Vector2d CellCentre(int column, int row) const;
  CellCounts Counts(int column, int row) const;
  CellClass ClassOf(int column, int row) const;
  CellClass ClassAt(const Eigen::Vector2d& bed_m) const;
  // Is any cell of `cls` in the bed rectangle [x0, x1] × [y0, y1]? Cells count
  // when their centre lies inside; a rectangle narrower than a cell tests the
  // cell under its centre.
  bool AnyIn(double x0, double x1, double y0, double y1, CellClass cls) const;
  // A nozzle sprayed the bed rectangle: its cells (as AnyIn picks them) are treated.
  void MarkTreated(double x0, double x1, double y0, double y1);
  bool Treated(int column, int row) const { return (Flags(column, row) & kTreatedFlag) != 0; }
  // The camera saw the convex quad (bed frame): cells whose centre lies in
  // it are observed, so soil there is soil; never-observed cells are unknown.
  void MarkObserved(const Quad& bed_quad);
  bool Observed(int column, int row) const { return (Flags(column, row) & kObservedFlag) != 0; }

  int columns() const { return columns_; }
  // One past the last row held (rows are numbered over the whole bed).
  int rows() const { return first_row_ + static_cast<int>(counts_.size()) / columns_; }
  const TreatmentMapOptions& options() const { return options_; }
  double origin_x_m() const { return -0.5 * options_.width_m; }

 private:
  void GrowTo(int row);
  int LastRow() const;  // the last row the map may grow to
  size_t Index(int column, int row) const {
    return static_cast<size_t>(row - first_row_) * columns_ + column;
  }
  // Adds `votes` (negative: takes back) to one counter, kept within [0, 65535].
  void Vote(uint16_t& counter, int votes);
  void Vote(size_t cell, int votes, bool crop) {
    Vote(crop ? counts_[cell].crop : counts_[cell].weed, votes);
  }
  // Calls f(index) for every cell whose centre lies inside the convex quad,
  // growing the map to it; returns the number of cells.
  template <typename F>
  int ForCellsIn(const Quad& q, F&& f);
  uint8_t Flags(int column, int row) const;
  static constexpr uint8_t kTreatedFlag = 1, kObservedFlag = 2;
  struct CellRange {
    int c0, c1, r0, r1;  // inclusive; empty when c0 > c1 or r0 > r1
  };
  CellRange RangeOf(double x0, double x1, double y0, double y1) const;

  TreatmentMapOptions options_;
  int columns_ = 0;
  int first_row_ = 0;                // the first row held
  std::vector<CellCounts> counts_;  // row-major, from first_row_
  std::vector<uint8_t> flags_;       // same layout: kTreatedFlag | kObservedFlag
};

}  // namespace plantscale::treatment
