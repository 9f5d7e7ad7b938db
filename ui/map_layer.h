#pragma once
// The live crop/weed map: one image actor per map tile (crop, weed, soil,
// treated, unknown cells), in field metres, rebuilt only when a tile's
// revision changes so that a 100 m bed stays cheap to draw.

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
  void AddTo(vtkRenderer* renderer) { renderer_ = renderer; }
  void Update(const RunModel& model);
  void SetVisible(bool visible);
  // Shows only tiles that overlap `view` (along the bed, with a margin).
  void Cull(const FieldWindow& view);
  // Field-frame bounds of every tile (x0, x1, y0, y1); false when none.
  bool Bounds(double bounds[4]) const;

 private:
  struct Tile {
    int revision = -1;
    double y0_m = 0.0, y1_m = 0.0;  // along-bed extent of the tile's cells
    vtkSmartPointer<vtkImageActor> actor;
  };
  vtkRenderer* renderer_ = nullptr;
  std::map<std::pair<int, int>, Tile> tiles_;
  bool visible_ = true;
  int seen_revisions_ = -1;
};

}  // namespace plantscale::ui
