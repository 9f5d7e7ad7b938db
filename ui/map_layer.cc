#include "ui/map_layer.h"

#include <vtkImageData.h>
#include <vtkImageMapper3D.h>
#include <vtkNew.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "telemetry/convert.h"
#include "ui/palette.h"

namespace plantscale::ui {
namespace {

using Cell = plantscale_map_tile_t;

Rgb CellColour(uint8_t cell) {
  switch (cell) {
    case Cell::CELL_SOIL:
      return palette::kSoil;
    case Cell::CELL_CROP:
      return palette::kCrop;
    case Cell::CELL_WEED:
      return palette::kWeed;
    case Cell::CELL_TREATED:
      return palette::kTreated;
    default:
      return palette::kUnknownCell;
  }
}

// Which class a far-view cell shows when its tile cells differ: weeds first.
int Rank(uint8_t cell) {
  switch (cell) {
    case Cell::CELL_WEED:
      return 4;
    case Cell::CELL_TREATED:
      return 3;
    case Cell::CELL_CROP:
      return 2;
    case Cell::CELL_SOIL:
      return 1;
    default:
      return 0;
  }
}

// An RGB image of `cells` (row-major, row j along y), points at cell centres
// from `origin` (the first cell's corner).
vtkSmartPointer<vtkImageData> Image(const std::vector<uint8_t>& cells, int width, int height, double cell_m,
                                    const Eigen::Vector2d& origin) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(width, height, 1);
  image->SetSpacing(cell_m, cell_m, 1.0);
  image->SetOrigin(origin.x() + 0.5 * cell_m, origin.y() + 0.5 * cell_m, 0.0);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  std::array<std::array<unsigned char, 3>, 256> lut{};  // cell value -> RGB bytes
  for (size_t v = 0; v < lut.size(); ++v) {
    const Rgb c = CellColour(static_cast<uint8_t>(v));
    lut[v] = {static_cast<unsigned char>(c.r * 255.0 + 0.5), static_cast<unsigned char>(c.g * 255.0 + 0.5),
              static_cast<unsigned char>(c.b * 255.0 + 0.5)};
  }
  auto* out = static_cast<unsigned char*>(image->GetScalarPointer());
  const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
  for (size_t i = 0; i < n; ++i) {
    const auto& c = lut[i < cells.size() ? cells[i] : 0];
    std::copy(c.begin(), c.end(), out + 3 * i);
  }
  return image;
}

bool Overlaps(double y0, double y1, const BuiltRange& r) { return y1 >= r.y0_m && y0 <= r.y1_m; }

// A far level's block length and cell edge.
double BlockM(int level) { return level > 1 ? MapLayer::kBlockM * MapLayer::kCoarseBlocks : MapLayer::kBlockM; }
double BlockCellM(int level) {
  return level > 1 ? MapLayer::kBlockCellM * MapLayer::kCoarseCells : MapLayer::kBlockCellM;
}

int BlockOf(double y, int level) { return static_cast<int>(std::floor(y / BlockM(level))); }

int ChunkOf(int tile_y) {
  return static_cast<int>(std::floor(static_cast<double>(tile_y) / MapLayer::kChunkRows));
}

// Paints `tile` into an image of `nx` × `ny` cells of `cell` metres from
// `origin`, each cell keeping its highest-ranked class (at the tile's own
// resolution, from a tile corner: a copy).
void Paint(const telemetry::MapTileDelta& t, const Eigen::Vector2d& origin, double cell, int nx, int ny,
           std::vector<uint8_t>& cells) {
  const auto to_cell = [&](double at, double from, int i, int count) {
    const int b = static_cast<int>(std::floor((at + (i + 0.5) * t.resolution_m - from) / cell));
    return b >= 0 && b < count ? b : -1;
  };
  std::vector<int> bx(static_cast<size_t>(std::max(0, t.width)));
  for (int i = 0; i < t.width; ++i) bx[static_cast<size_t>(i)] = to_cell(t.origin_m.x(), origin.x(), i, nx);
  const size_t width = bx.size();
  for (int j = 0; j < t.height && (static_cast<size_t>(j) + 1) * width <= t.cells.size(); ++j) {
    const int by = to_cell(t.origin_m.y(), origin.y(), j, ny);
    if (by < 0) continue;
    uint8_t* row = &cells[static_cast<size_t>(by) * static_cast<size_t>(nx)];
    const uint8_t* in = &t.cells[static_cast<size_t>(j) * width];
    for (size_t i = 0; i < width; ++i) {
      if (bx[i] >= 0 && Rank(in[i]) > Rank(row[bx[i]])) row[bx[i]] = in[i];
    }
  }
}

}  // namespace

void MapLayer::Update(const review::RunModel& model, const FieldWindow& view) {
  if (renderer_ == nullptr) return;
  const double length = std::max(1e-3, view.y1_m - view.y0_m);
  const int level = length <= kDetailMaxM ? 0 : length <= kFarMaxM ? 1 : 2;
  const bool changed = model.tile_revision_sum() != seen_revisions_;
  if (changed) Index(model);
  if (!changed && level == level_ && built_.Covers(view)) return;
  seen_revisions_ = model.tile_revision_sum();
  if (level != level_) {
    for (auto& [index, d] : pieces_) Drop(d.actor);
    pieces_.clear();
  }
  level_ = level;
  built_ = BuiltRange::Around(view, length);
  ShowPieces(model, built_);
}

// The extents of the model's tiles; tiles it no longer has (the station
// sought back and replayed from the start) leave the index.
void MapLayer::Index(const review::RunModel& model) {
  for (const auto& [key, t] : model.tiles()) {
    Extent& e = index_[key];
    if (e.revision == t.revision) continue;
    e = {t.revision, t.origin_m.x(), t.origin_m.x() + t.width * t.resolution_m, t.origin_m.y(),
         t.origin_m.y() + t.height * t.resolution_m, t.resolution_m};
  }
  if (index_.size() == model.tiles().size()) return;
  for (auto it = index_.begin(); it != index_.end();) {
    it = model.tiles().count(it->first) ? std::next(it) : index_.erase(it);
  }
}

std::map<int, MapLayer::Piece> MapLayer::Wanted(const BuiltRange& near) const {
  std::map<int, Piece> wanted;
  for (const auto& [key, e] : index_) {
    if (!Overlaps(e.y0_m, e.y1_m, near)) continue;
    const int first = level_ == 0 ? ChunkOf(key.second) : BlockOf(e.y0_m, level_);
    const int last = level_ == 0 ? first : BlockOf(e.y1_m - 1e-9, level_);
    for (int b = first; b <= last; ++b) {
      Piece& p = wanted[b];
      p.stamp += e.revision + 1;
      p.x0 = std::min(p.x0, e.x0_m), p.x1 = std::max(p.x1, e.x1_m);
      p.y0 = std::min(p.y0, e.y0_m), p.y1 = std::max(p.y1, e.y1_m);
      p.cell = std::min(p.cell, e.cell_m);
      p.tiles.push_back(key);
    }
  }
  return wanted;
}

void MapLayer::ShowPieces(const review::RunModel& model, const BuiltRange& near) {
  const std::map<int, Piece> wanted = Wanted(near);
  for (auto it = pieces_.begin(); it != pieces_.end();) {
    if (wanted.count(it->first)) {
      ++it;
      continue;
    }
    Drop(it->second.actor);
    it = pieces_.erase(it);
  }
  for (const auto& [index, piece] : wanted) {
    Drawn& slot = pieces_[index];
    if (slot.stamp != piece.stamp || !slot.actor) Draw(model, index, piece, slot);
  }
}

void MapLayer::Draw(const review::RunModel& model, int index, const Piece& p, Drawn& slot) {
  BlockCells& b = level_ == 0 ? chunk_cells_ : far_cells_[{level_, index}];
  const std::vector<uint8_t>& cells = Cells(model, index, p, b);
  if (!slot.actor) slot.actor = NewActor();
  slot.actor->GetMapper()->SetInputData(Image(cells, b.nx, b.ny, level_ == 0 ? p.cell : BlockCellM(level_), b.origin));
  slot.actor->Modified();
  slot.stamp = p.stamp;
}

// A chunk at its finest tile's resolution from its tiles' corner; a block
// in its level's cells over its level's length of bed.
const std::vector<uint8_t>& MapLayer::Cells(const review::RunModel& model, int index, const Piece& p, BlockCells& b) const {
  const bool chunk = level_ == 0;
  if (!chunk && b.stamp == p.stamp && b.tiles == p.tiles.size() && b.y0 == p.y0 && b.y1 == p.y1) return b.cells;
  const double cell = chunk ? p.cell : BlockCellM(level_);
  b.origin = chunk ? Eigen::Vector2d(p.x0, p.y0) : Eigen::Vector2d(std::floor(p.x0 / cell) * cell, index * BlockM(level_));
  const double y1 = chunk ? p.y1 : b.origin.y() + BlockM(level_);
  b.nx = static_cast<int>(std::ceil((p.x1 - b.origin.x()) / cell - 1e-6));
  b.ny = static_cast<int>(std::ceil((y1 - b.origin.y()) / cell - 1e-6));
  b.cells.assign(static_cast<size_t>(b.nx) * static_cast<size_t>(b.ny), Cell::CELL_UNKNOWN);
  for (const TileKey& key : p.tiles) Paint(model.tiles().at(key), b.origin, cell, b.nx, b.ny, b.cells);
  b.stamp = p.stamp, b.tiles = p.tiles.size(), b.y0 = p.y0, b.y1 = p.y1;
  return b.cells;
}

vtkSmartPointer<vtkImageActor> MapLayer::NewActor() {
  auto actor = vtkSmartPointer<vtkImageActor>::New();
  actor->InterpolateOff();
  actor->GetMapper()->BorderOn();  // whole edge cells: no seams between tiles
  actor->SetVisibility(visible_);
  renderer_->AddActor(actor);
  return actor;
}

void MapLayer::Drop(vtkImageActor* actor) {
  if (actor != nullptr) renderer_->RemoveActor(actor);
}

void MapLayer::SetVisible(bool visible) {
  visible_ = visible;
  for (auto& [index, d] : pieces_) d.actor->SetVisibility(visible);
}

bool MapLayer::Bounds(double b[4]) const {
  if (index_.empty()) return false;
  b[0] = b[2] = 1e300;
  b[1] = b[3] = -1e300;
  for (const auto& [key, e] : index_) {
    b[0] = std::min(b[0], e.x0_m), b[1] = std::max(b[1], e.x1_m);
    b[2] = std::min(b[2], e.y0_m), b[3] = std::max(b[3], e.y1_m);
  }
  return true;
}

}  // namespace plantscale::ui
