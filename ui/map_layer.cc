#include "ui/map_layer.h"

#include <vtkImageData.h>
#include <vtkImageMapper3D.h>
#include <vtkNew.h>

#include <algorithm>

#include "telemetry/convert.h"
#include "ui/palette.h"

namespace plantscale::ui {
namespace {

Rgb CellColour(uint8_t cell) {
  switch (cell) {
    case plantscale_map_tile_t::CELL_SOIL:
      return palette::kSoil;
    case plantscale_map_tile_t::CELL_CROP:
      return palette::kCrop;
    case plantscale_map_tile_t::CELL_WEED:
      return palette::kWeed;
    case plantscale_map_tile_t::CELL_TREATED:
      return palette::kTreated;
    default:
      return palette::kUnknownCell;
  }
}

// Cells row-major from the tile origin, row j at y = origin_y + j·resolution;
// image points sit at cell centres.
vtkSmartPointer<vtkImageData> TileImage(const telemetry::MapTileDelta& t) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(t.width, t.height, 1);
  image->SetSpacing(t.resolution_m, t.resolution_m, 1.0);
  image->SetOrigin(t.origin_m.x() + 0.5 * t.resolution_m, t.origin_m.y() + 0.5 * t.resolution_m,
                   0.0);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(image->GetScalarPointer());
  const size_t n = std::min(t.cells.size(), static_cast<size_t>(t.width) * t.height);
  for (size_t i = 0; i < static_cast<size_t>(t.width) * t.height; ++i) {
    const Rgb c = CellColour(i < n ? t.cells[i] : 0);
    out[3 * i] = static_cast<unsigned char>(c.r * 255.0 + 0.5);
    out[3 * i + 1] = static_cast<unsigned char>(c.g * 255.0 + 0.5);
    out[3 * i + 2] = static_cast<unsigned char>(c.b * 255.0 + 0.5);
  }
  return image;
}

}  // namespace

void MapLayer::Update(const RunModel& model) {
  if (renderer_ == nullptr || model.tile_revision_sum() == seen_revisions_) return;
  seen_revisions_ = model.tile_revision_sum();
  // Tiles the model no longer has (the station sought back in its log: the
  // model was replayed from the start) leave the map, so that a log time
  // shows the map as it was then, however one got there.
  for (auto it = tiles_.begin(); it != tiles_.end();) {
    if (model.tiles().count(it->first) == 0) {
      renderer_->RemoveActor(it->second.actor);
      it = tiles_.erase(it);
    } else {
      ++it;
    }
  }
  for (const auto& [key, tile] : model.tiles()) {
    Tile& slot = tiles_[key];
    if (slot.revision == tile.revision && slot.actor) continue;
    if (!slot.actor) {
      slot.actor = vtkSmartPointer<vtkImageActor>::New();
      slot.actor->InterpolateOff();
      slot.actor->GetMapper()->BorderOn();  // whole edge cells: no seams between tiles
      slot.actor->SetVisibility(visible_);
      renderer_->AddActor(slot.actor);
    }
    slot.actor->GetMapper()->SetInputData(TileImage(tile));
    slot.actor->Modified();
    slot.revision = tile.revision;
    slot.y0_m = tile.origin_m.y();
    slot.y1_m = tile.origin_m.y() + tile.height * tile.resolution_m;
  }
}

void MapLayer::SetVisible(bool visible) {
  visible_ = visible;
  for (auto& [key, tile] : tiles_) tile.actor->SetVisibility(visible);
}

void MapLayer::Cull(const FieldWindow& view) {
  const double margin = 0.5 * (view.y1_m - view.y0_m);
  for (auto& [key, tile] : tiles_) {
    const bool near = tile.y1_m >= view.y0_m - margin && tile.y0_m <= view.y1_m + margin;
    tile.actor->SetVisibility(visible_ && near);
  }
}

bool MapLayer::Bounds(double b[4]) const {
  if (tiles_.empty()) return false;
  b[0] = b[2] = 1e300;
  b[1] = b[3] = -1e300;
  for (const auto& [key, tile] : tiles_) {
    const double* tb = tile.actor->GetBounds();
    b[0] = std::min(b[0], tb[0]), b[1] = std::max(b[1], tb[1]);
    b[2] = std::min(b[2], tb[2]), b[3] = std::max(b[3], tb[3]);
  }
  return true;
}

}  // namespace plantscale::ui
