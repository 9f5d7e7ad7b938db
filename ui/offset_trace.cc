#include "ui/offset_trace.h"

#include <vtkAxis.h>
#include <vtkBrush.h>
#include <vtkCamera.h>
#include <vtkImageData.h>
#include <vtkImageMapper3D.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>
#include <vtkChartLegend.h>
#include <vtkContextScene.h>
#include <vtkDoubleArray.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkPlotArea.h>
#include <vtkStringArray.h>
#include <vtkTextProperty.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <string>

namespace plantscale::ui {
namespace {

constexpr const char* kColumns[] = {"distance", "offset", "offset_lo", "offset_hi",
                                    "bearing",  "bearing_lo", "bearing_hi"};

void AddColumns(vtkTable* table) {
  for (const char* name : kColumns) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name);
    table->AddColumn(a);
  }
}

void AddBand(vtkChartXY* chart, vtkTable* table, const char* lo, const char* hi, int r, int g,
             int b, int corner) {
  vtkNew<vtkPlotArea> area;
  chart->AddPlot(area);
  area->SetInputData(table);
  area->SetInputArray(0, "distance");
  area->SetInputArray(1, lo);
  area->SetInputArray(2, hi);
  area->GetBrush()->SetColor(r, g, b, 70);
  area->GetPen()->SetOpacity(0);
  area->SetLabel(std::string(lo).starts_with("offset") ? "offset ±2 sd" : "bearing ±2 sd");
  chart->SetPlotCorner(area, corner);
}

vtkPlot* AddLine(vtkChartXY* chart, vtkTable* table, const char* y, int r, int g, int b,
                 int corner) {
  vtkPlot* line = chart->AddPlot(vtkChart::LINE);
  line->SetInputData(table, "distance", y);
  line->SetColor(r, g, b, 255);
  line->SetWidth(1.5f);
  chart->SetPlotCorner(line, corner);
  return line;
}

}  // namespace

OffsetTrace::OffsetTrace(const OffsetTraceParams& params) : params_(params) {
  Build();
  vtkNew<vtkImageData> blank;  // until the first picture (VTK wants an input)
  blank->SetDimensions(1, 1, 1);
  blank->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  static_cast<unsigned char*>(blank->GetScalarPointer())[0] = 255;
  cache_actor_->GetMapper()->SetInputData(blank);
}

void OffsetTrace::Build() {
  AddColumns(estimate_);
  AddColumns(truth_);
  actor_->GetScene()->AddItem(chart_);
  chart_->SetTitle("Row offset and bearing");
  chart_->GetTitleProperties()->SetFontSize(12);
  chart_->SetShowLegend(true);
  chart_->GetLegend()->GetLabelProperties()->SetFontSize(9);
  chart_->GetLegend()->SetInline(false);
  chart_->GetLegend()->SetHorizontalAlignment(vtkChartLegend::RIGHT);
  chart_->GetLegend()->SetVerticalAlignment(vtkChartLegend::BOTTOM);
  AddBand(chart_, estimate_, "offset_lo", "offset_hi", 30, 110, 230, 0);
  AddBand(chart_, estimate_, "bearing_lo", "bearing_hi", 240, 140, 20, 1);
  AddLine(chart_, estimate_, "offset", 30, 110, 230, 0)->SetLabel("offset (mm)");
  AddLine(chart_, estimate_, "bearing", 240, 140, 20, 1)->SetLabel("bearing (deg)");
  vtkPlot* truth = AddLine(chart_, truth_, "offset", 90, 90, 90, 0);
  truth->SetLabel("true offset (mm)");
  truth->GetPen()->SetLineType(vtkPen::DASH_LINE);
  chart_->GetAxis(vtkAxis::BOTTOM)->SetTitle("distance (m)");
  chart_->GetAxis(vtkAxis::LEFT)->SetTitle("offset (mm)");
  chart_->GetAxis(vtkAxis::RIGHT)->SetTitle("bearing (deg)");
  for (int a : {vtkAxis::BOTTOM, vtkAxis::LEFT, vtkAxis::RIGHT}) {
    chart_->GetAxis(a)->GetTitleProperties()->SetFontSize(11);
    chart_->GetAxis(a)->GetLabelProperties()->SetFontSize(10);
  }
}

void OffsetTrace::AddTo(vtkRenderer* renderer) {
  renderer_ = renderer;
  if (params_.cached_width_px <= 0) return renderer->AddActor(actor_);
  cache_window_ = vtkSmartPointer<vtkRenderWindow>::New();
  cache_window_->SetOffScreenRendering(1);
  cache_window_->SetSize(params_.cached_width_px, params_.cached_height_px);
  vtkNew<vtkRenderer> chart_renderer;
  chart_renderer->SetBackground(1, 1, 1);
  chart_renderer->AddActor(actor_);
  cache_window_->AddRenderer(chart_renderer);
  cache_actor_->InterpolateOff();  // shown texel for pixel: filtering would change nothing but the cost
  renderer->AddActor(cache_actor_);
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->ParallelProjectionOn();
  const double w = params_.cached_width_px, h = params_.cached_height_px;
  camera->SetFocalPoint(0.5 * w, 0.5 * h, 0.0);
  camera->SetPosition(0.5 * w, 0.5 * h, 10.0);
  camera->SetParallelScale(0.5 * h);
  camera->SetClippingRange(1.0, 20.0);
}

void OffsetTrace::SetVisible(bool visible) {
  actor_->SetVisibility(visible);
  cache_actor_->SetVisibility(visible);
}

void OffsetTrace::Rasterise() {
  cache_window_->Render();
  const int w = params_.cached_width_px, h = params_.cached_height_px;
  vtkNew<vtkUnsignedCharArray> pixels;
  cache_window_->GetPixelData(0, 0, w - 1, h - 1, 0, pixels);
  vtkNew<vtkImageData> image;
  image->SetDimensions(w, h, 1);
  image->SetOrigin(0.5, 0.5, 0.0);
  image->GetPointData()->SetScalars(pixels);
  cache_actor_->GetMapper()->SetInputData(image);
  cache_actor_->Modified();
}

// Rows of `trace` (decimated to max_points, limited to window_m) in display
// units: offset mm, bearing degrees, bands at ±band_sigmas σ.
// The first sample within window_m of the newest (distances never fall:
// RunModel keeps the largest heard).
size_t OffsetTrace::WindowStart(const std::vector<review::TraceSample>& trace) const {
  if (params_.window_m <= 0.0 || trace.empty()) return 0;
  const double from = trace.back().distance_m - params_.window_m;
  const auto first = std::lower_bound(
      trace.begin(), trace.end(), from,
      [](const review::TraceSample& t, double d) { return t.distance_m < d; });
  return static_cast<size_t>(first - trace.begin());
}

void OffsetTrace::Fill(vtkTable* table, const std::vector<review::TraceSample>& trace) const {
  const size_t first = WindowStart(trace);
  const size_t n = trace.size() - first;
  const size_t step = std::max<size_t>(1, n / static_cast<size_t>(params_.max_points));
  const double k = params_.band_sigmas, deg = 180.0 / std::numbers::pi;
  table->SetNumberOfRows(static_cast<vtkIdType>((n + step - 1) / step));
  vtkIdType row = 0;
  for (size_t i = first; i < trace.size(); i += step, ++row) {
    const review::TraceSample& t = trace[i];
    const double values[] = {t.distance_m - origin_m_,
                             1e3 * t.offset_m,
                             1e3 * (t.offset_m - k * t.offset_sigma_m),
                             1e3 * (t.offset_m + k * t.offset_sigma_m),
                             deg * t.bearing_rad,
                             deg * (t.bearing_rad - k * t.bearing_sigma_rad),
                             deg * (t.bearing_rad + k * t.bearing_sigma_rad)};
    for (int c = 0; c < 7; ++c) table->SetValue(row, c, vtkVariant(values[c]));
  }
  table->Modified();
}

// Ticks at a round step (1, 2 or 5 × 10^k m) giving at most 8 over the
// span, at their place less the origin, labelled with the distance itself.
void OffsetTrace::SetDistanceTicks(double from_m, double to_m) {
  const double span = std::max(to_m - from_m, 1e-3);
  double step = std::pow(10.0, std::floor(std::log10(span / 8.0)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (span / (m * step) <= 8.0) {
      step *= m;
      break;
    }
  }
  vtkNew<vtkDoubleArray> positions;
  vtkNew<vtkStringArray> labels;
  const int decimals = step < 1.0 ? 1 : 0;
  for (double d = std::ceil(from_m / step) * step; d <= to_m + 1e-9; d += step) {
    positions->InsertNextValue(d - origin_m_);
    std::ostringstream label;
    label << std::fixed << std::setprecision(decimals) << d;
    labels->InsertNextValue(label.str());
  }
  chart_->GetAxis(vtkAxis::BOTTOM)->SetCustomTickPositions(positions, labels);
}

void OffsetTrace::Update(const review::RunModel& model) {
  // Without a tracker the simulator's truth stands in for the estimate.
  const bool tracker = !model.trace().empty();
  const std::vector<review::TraceSample>& estimate = tracker ? model.trace() : model.truth_trace();
  if (estimate.size() != seen_) {
    seen_ = estimate.size();
    if (!estimate.empty()) {
      const double from = estimate[WindowStart(estimate)].distance_m;
      const double origin = 10.0 * std::floor(from / 10.0);
      if (origin != origin_m_) seen_truth_ = static_cast<size_t>(-1);  // refilled below
      origin_m_ = origin;
      SetDistanceTicks(from, estimate.back().distance_m);
    }
    Fill(estimate_, estimate);
    chart_->SetTitle(tracker ? "Row offset and bearing (tracker)"
                             : "Row offset and bearing (simulator truth; no tracker in log)");
  }
  const std::vector<review::TraceSample> none;
  const std::vector<review::TraceSample>& truth = tracker ? model.truth_trace() : none;
  if (truth.size() != seen_truth_) {
    seen_truth_ = truth.size();
    Fill(truth_, truth);
  }
  // Fewer than two points is no line (VTK would complain on every render).
  for (vtkIdType i = 0; i < chart_->GetNumberOfPlots(); ++i) {
    const vtkIdType rows = (i < 4 ? estimate_ : truth_)->GetNumberOfRows();
    chart_->GetPlot(i)->SetVisible(rows >= 2);
  }
  chart_->RecalculateBounds();
  if (cache_window_ && (drawn_ == static_cast<size_t>(-1) || seen_ < drawn_ ||
                        seen_ >= drawn_ + static_cast<size_t>(params_.redraw_every))) {
    drawn_ = seen_;
    Rasterise();
  }
}

}  // namespace plantscale::ui
