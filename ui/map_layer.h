#pragma once
// The live crop/weed map (crop, weed, soil, treated, unknown cells) in field
// metres, drawn at two levels so that any length of bed stays cheap to draw
// and to hold, each as a few image actors (VTK's cost per actor, not per
// pixel, is what a frame pays for many small images):
//  - close (a view up to kDetailMaxM long): chunks of kChunkRows tile rows at
//    the tiles' own resolution, only near the view (a chunk's image is
//    rebuilt when one of its tiles' revisions changes, and released when the
//    view leaves it);
//  - far: blocks of kBlockM of bed resampled to kBlockCellM cells (a weed cell
//    wins over treated, crop, soil and unknown, so weed patches stay seen),
//    again only near the view; a view longer than kFarMaxM (kilometres of
//    bed, metres a pixel) in blocks kCoarseBlocks times as long, of cells
//    kCoarseCells times as big (bigger would paint a weedy bed all weed).

#include <vtkImageActor.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>

#include <map>
#include <utility>
#include <vector>

#include "review/run_model.h"
#include "ui/field_overlays.h"

namespace plantscale::ui {

class MapLayer {
 public:
  static constexpr double kDetailMaxM = 60.0;
  static constexpr double kBlockM = 25.0;
  static constexpr double kBlockCellM = 0.08;
  static constexpr int kChunkRows = 6;
  static constexpr double kFarMaxM = 600.0;
  static constexpr int kCoarseBlocks = 10;
  static constexpr int kCoarseCells = 2;

  void AddTo(vtkRenderer* renderer) { renderer_ = renderer; }
  // Shows the map of `model` near `view` (a tile the model no longer has,
  // after a seek back, leaves the screen).
  void Update(const review::RunModel& model, const FieldWindow& view);
  void SetVisible(bool visible);
  // Field-frame bounds of every tile of the model (x0, x1, y0, y1); false when none.
  bool Bounds(double bounds[4]) const;
  int actors() const { return static_cast<int>(pieces_.size()); }

 private:
  struct Extent {
    int revision = -1;
    double x0_m = 0, x1_m = 0, y0_m = 0, y1_m = 0, cell_m = 0;
  };
  struct Drawn {
    int stamp = -1;  // the sum of its tiles' revisions
    vtkSmartPointer<vtkImageActor> actor;
  };
  // A chunk or block to draw: its tiles and their extent.
  struct Piece {
    int stamp = 0;
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, cell = 1e300;
    std::vector<std::pair<int, int>> tiles;
  };
  // A far block's cells, kept when it leaves the view (25 m of bed in ~7 kB:
  // a far view goes back to a block without painting its ~100 tiles again).
  struct BlockCells {
    int stamp = -1;
    size_t tiles = 0;
    double y0 = 0, y1 = 0;
    Eigen::Vector2d origin = Eigen::Vector2d::Zero();
    int nx = 0, ny = 0;
    std::vector<uint8_t> cells;
  };
  using TileKey = std::pair<int, int>;

  void Index(const review::RunModel& model);
  // The chunks (close) or blocks (far) with a tile near the view, by index.
  std::map<int, Piece> Wanted(const BuiltRange& near) const;
  void ShowPieces(const review::RunModel& model, const BuiltRange& near);
  void Draw(const review::RunModel& model, int index, const Piece& piece, Drawn& slot);
  // The piece's cells at `cell` metres from `origin` (a far block's from
  // the kept ones when its tiles are the same).
  const std::vector<uint8_t>& Cells(const review::RunModel& model, int index, const Piece& piece, BlockCells& out) const;
  vtkSmartPointer<vtkImageActor> NewActor();
  void Drop(vtkImageActor* actor);

  vtkRenderer* renderer_ = nullptr;
  std::map<TileKey, Extent> index_;  // every tile of the model (no pixels)
  std::map<int, Drawn> pieces_;      // chunks or blocks near the view
  std::map<std::pair<int, int>, BlockCells> far_cells_;  // every block drawn, by level and index
  BlockCells chunk_cells_;               // scratch for a close chunk
  bool visible_ = true;
  int seen_revisions_ = -1;
  int level_ = 0;  // 0 close (chunks), 1 far, 2 farther (blocks)
  BuiltRange built_;
};

}  // namespace plantscale::ui
