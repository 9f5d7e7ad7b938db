#pragma once
// The live crop/weed map (crop, weed, soil, treated, unknown cells) in field
// metres, drawn at two levels so that any length of bed stays cheap to draw
// and to hold:
//  - close (a view up to kDetailMaxM long): one image actor per map tile at
//    full resolution, only for the tiles within a view's length of the view
//    (actors of tiles farther away are released), rebuilt only when a tile's
//    revision changes;
//  - far: blocks of kBlockM of bed resampled to kBlockCellM cells (a weed cell
//    wins over treated, crop, soil and unknown, so weed patches stay seen),
//    again only near the view.

#include <vtkImageActor.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>

#include <map>
#include <utility>

#include "ui/field_overlays.h"
#include "ui/run_model.h"

namespace plantscale::ui {

class MapLayer {
 public:
  static constexpr double kDetailMaxM = 60.0;
  static constexpr double kBlockM = 25.0;
  static constexpr double kBlockCellM = 0.08;

  void AddTo(vtkRenderer* renderer) { renderer_ = renderer; }
  // Shows the map of `model` near `view` (a tile the model no longer has,
  // after a seek back, leaves the screen).
  void Update(const RunModel& model, const FieldWindow& view);
  void SetVisible(bool visible);
  // Field-frame bounds of every tile of the model (x0, x1, y0, y1); false when none.
  bool Bounds(double bounds[4]) const;
  int actors() const { return static_cast<int>(actors_.size() + blocks_.size()); }

 private:
  struct Extent {
    int revision = -1;
    double x0_m = 0, x1_m = 0, y0_m = 0, y1_m = 0;
  };
  struct Drawn {
    int stamp = -1;  // tile revision, or for a block the sum of its tiles' revisions
    vtkSmartPointer<vtkImageActor> actor;
  };
  using TileKey = std::pair<int, int>;

  void Index(const RunModel& model);
  void ShowTiles(const RunModel& model, const BuiltRange& near);
  void ShowBlocks(const RunModel& model, const BuiltRange& near);
  vtkSmartPointer<vtkImageActor> NewActor();
  void Drop(vtkImageActor* actor);

  vtkRenderer* renderer_ = nullptr;
  std::map<TileKey, Extent> index_;     // every tile of the model (no pixels)
  std::map<TileKey, Drawn> actors_;     // close: tiles near the view
  std::map<int, Drawn> blocks_;         // far: blocks near the view
  bool visible_ = true;
  int seen_revisions_ = -1;
  bool detail_ = true;
  BuiltRange built_;
};

}  // namespace plantscale::ui
