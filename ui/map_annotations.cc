#include "ui/map_annotations.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCoordinate.h>
#include <vtkPoints.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkProperty2D.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <utility>

#include "ui/palette.h"

namespace plantscale::ui {
namespace {

constexpr int kFont = 12;
constexpr double kSwatchPx = 10.0;
constexpr double kMaxBarPx = 160.0;

// The legend: colour and words; the plant ellipses' words come from Update.
const std::vector<std::pair<Rgb, std::string>>& LegendEntries() {
  static const std::vector<std::pair<Rgb, std::string>> entries = {
      {palette::kCrop, "crop"},          {palette::kWeed, "weed"},          {palette::kTreated, "treated"},
      {palette::kSoil, "soil"},          {palette::kRowLine, "rows"},       {palette::kPlantLine, "plant lines"},
      {palette::kVehicle, "vehicle"},    {palette::kPlantEllipse, ""},      {palette::kPick, "pick / measure"}};
  return entries;
}

void StyleLabel(vtkTextActor* t, int size) {
  vtkTextProperty* p = t->GetTextProperty();
  p->SetFontSize(size);
  p->SetFontFamilyToCourier();
  p->SetColor(1.0, 1.0, 1.0);
  p->BoldOn();
  p->SetBackgroundColor(0.0, 0.0, 0.0);
  p->SetBackgroundOpacity(0.55);
  t->GetPositionCoordinate()->SetCoordinateSystemToViewport();
}

unsigned char Byte(double v) { return static_cast<unsigned char>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); }

void SetUpActor2D(vtkPolyData* data, vtkActor2D* actor, double line_width) {
  vtkNew<vtkPolyDataMapper2D> mapper;
  mapper->SetInputData(data);
  vtkNew<vtkCoordinate> viewport;
  viewport->SetCoordinateSystemToViewport();
  mapper->SetTransformCoordinate(viewport);
  mapper->SetScalarModeToUseCellData();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetLineWidth(static_cast<float>(line_width));
}

}  // namespace

double RoundScaleLength(double max_m) {
  if (!(max_m > 0.0)) return 0.0;
  const double decade = std::pow(10.0, std::floor(std::log10(max_m)));
  for (const double f : {5.0, 2.0, 1.0}) {
    if (f * decade <= max_m * (1.0 + 1e-9)) return f * decade;
  }
  return decade;
}

std::string LengthText(double m) {
  std::ostringstream out;
  if (m >= 1000.0) {
    out << m / 1000.0 << " km";
  } else if (m >= 1.0) {
    out << m << " m";
  } else if (m >= 0.01) {
    out << std::lround(m * 100.0) << " cm";
  } else {
    out << std::lround(m * 1000.0) << " mm";
  }
  return out.str();
}

MapAnnotations::MapAnnotations() : labels_(LegendEntries().size()) {
  for (auto& l : labels_) StyleLabel(l, kFont);
  StyleLabel(bar_label_, kFont);
  StyleLabel(help_, 13);
  help_->GetTextProperty()->SetBackgroundOpacity(0.85);
  help_->GetTextProperty()->SetVerticalJustificationToTop();
  help_->VisibilityOff();
  SetUpActor2D(swatches_, swatch_actor_, 1.0);
  SetUpActor2D(bar_, bar_actor_, 3.0);
}

void MapAnnotations::AddTo(vtkRenderer* renderer) {
  renderer_ = renderer;
  renderer->AddActor2D(swatch_actor_);
  for (auto& l : labels_) renderer->AddActor2D(l);
  renderer->AddActor2D(bar_actor_);
  renderer->AddActor2D(bar_label_);
  renderer->AddActor2D(help_);
}

void MapAnnotations::SetHelp(const std::string& text) {
  help_text_ = text;
  help_->SetInput(text.c_str());
  help_->SetVisibility(!text.empty());
  if (renderer_ != nullptr) help_->SetPosition(8.0, renderer_->GetSize()[1] - 8.0);
}

void MapAnnotations::Update(double metres_per_pixel, const std::string& ellipses) {
  if (renderer_ == nullptr) return;
  const int* size = renderer_->GetSize();
  const bool resized = size[0] != width_px_ || size[1] != height_px_;
  width_px_ = size[0], height_px_ = size[1];
  if (resized || ellipses != ellipses_) {
    ellipses_ = ellipses;
    PlaceLegend();
    if (help_visible()) help_->SetPosition(8.0, height_px_ - 8.0);
  }
  if (resized || std::abs(metres_per_pixel - scale_mpp_) > 1e-9 * metres_per_pixel) PlaceScaleBar(metres_per_pixel);
}

// Swatch and label after swatch and label along the top of the map, on a
// second line when the first is full.
void MapAnnotations::PlaceLegend() {
  vtkNew<vtkPoints> points;
  vtkNew<vtkCellArray> quads;
  vtkNew<vtkUnsignedCharArray> colours;
  colours->SetNumberOfComponents(3);
  double x = 8.0, y = height_px_ - 18.0;
  const auto& entries = LegendEntries();
  for (size_t i = 0; i < entries.size(); ++i) {
    const std::string text = entries[i].second.empty() ? ellipses_ : entries[i].second;
    labels_[i]->SetInput(text.c_str());
    labels_[i]->SetVisibility(!text.empty());
    if (text.empty()) continue;
    double label[2] = {0.0, 0.0};
    labels_[i]->GetSize(renderer_, label);
    if (x + kSwatchPx + 4 + label[0] > width_px_ - 8 && x > 8.0) x = 8.0, y -= 18.0;
    const vtkIdType p0 = points->InsertNextPoint(x, y, 0), p1 = points->InsertNextPoint(x + kSwatchPx, y, 0);
    const vtkIdType p2 = points->InsertNextPoint(x + kSwatchPx, y + kSwatchPx, 0);
    const vtkIdType p3 = points->InsertNextPoint(x, y + kSwatchPx, 0);
    const vtkIdType quad[] = {p0, p1, p2, p3};
    quads->InsertNextCell(4, quad);
    const Rgb c = entries[i].first;
    colours->InsertNextTuple3(Byte(c.r), Byte(c.g), Byte(c.b));
    labels_[i]->SetPosition(x + kSwatchPx + 4.0, y - 1.0);
    x += kSwatchPx + 4.0 + label[0] + 12.0;
  }
  swatches_->Initialize();
  swatches_->SetPoints(points);
  swatches_->SetPolys(quads);
  swatches_->GetCellData()->SetScalars(colours);
  swatches_->Modified();
}

// A bar of a round length, at most kMaxBarPx long, bottom left, with end ticks.
void MapAnnotations::PlaceScaleBar(double mpp) {
  scale_mpp_ = mpp;
  const double length_m = RoundScaleLength(mpp * kMaxBarPx);
  const double px = mpp > 0 ? length_m / mpp : 0.0;
  const double x0 = 10.0, y0 = 10.0;
  vtkNew<vtkPoints> points;
  vtkNew<vtkCellArray> lines;
  vtkNew<vtkUnsignedCharArray> colours;
  colours->SetNumberOfComponents(3);
  const auto segment = [&](double xa, double ya, double xb, double yb) {
    const vtkIdType ids[] = {points->InsertNextPoint(xa, ya, 0), points->InsertNextPoint(xb, yb, 0)};
    lines->InsertNextCell(2, ids);
    colours->InsertNextTuple3(255, 255, 255);
  };
  segment(x0, y0, x0 + px, y0);
  segment(x0, y0 - 4, x0, y0 + 6);
  segment(x0 + px, y0 - 4, x0 + px, y0 + 6);
  bar_->Initialize();
  bar_->SetPoints(points);
  bar_->SetLines(lines);
  bar_->GetCellData()->SetScalars(colours);
  bar_->Modified();
  bar_label_->SetInput(LengthText(length_m).c_str());
  bar_label_->SetPosition(x0 + px + 8.0, y0 - 5.0);
}

}  // namespace plantscale::ui
