#include "ui/hud.h"

#include <vtkCamera.h>
#include <vtkTextProperty.h>

#include <cmath>
#include <iomanip>
#include <sstream>

#include "ui/palette.h"

namespace plantscale::ui {
namespace {

namespace tm = plantscale::telemetry;

void StyleText(vtkTextActor* t, int size, double x, double y) {
  t->GetTextProperty()->SetFontSize(size);
  t->GetTextProperty()->SetFontFamilyToCourier();
  t->GetTextProperty()->SetColor(1.0, 1.0, 1.0);
  t->GetTextProperty()->BoldOn();
  t->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  t->SetPosition(x, y);
}

// A filled bar drawn as a thick vertical line (pixels of width `w`).
Polyline Bar(double x, double y0, double y1) { return {{x, y0}, {x, y1}}; }

}  // namespace

std::string FilterModeName(tm::FilterMode mode) {
  switch (mode) {
    case tm::FilterMode::kInitialising:
      return "INITIALISING";
    case tm::FilterMode::kTracking:
      return "TRACKING";
    case tm::FilterMode::kDeadReckoning:
      return "DEAD RECKONING";
    case tm::FilterMode::kLost:
      return "LOST";
    case tm::FilterMode::kTruth:
      return "TRUTH (sim)";
  }
  return "?";
}

std::string HudLine(const review::RunModel& model, int64_t now_utime) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(2) << model.speed_m_s() << " m/s  ";
  const auto* grid = model.grid() ? &*model.grid() : model.truth() ? &*model.truth() : nullptr;
  out << (grid ? FilterModeName(grid->mode) : std::string("NO GRID")) << "  ";
  const double fps = model.health() ? model.health()->frame_rate_hz : 0.0;
  out << std::setprecision(1) << fps << " fps  " << model.distance_m() << " m  ";
  const review::LinkStatus link = model.Link(now_utime);
  // Once the run finished the heartbeat's age only grows: the HUD leaves it
  // out so that the line fits a narrow window (the station's closing line
  // keeps it).
  out << (link.level == review::LinkLevel::kFinished ? link.text.substr(0, link.text.find(';')) : link.text);
  return out.str();
}

Hud::Hud(const HudParams& params) : params_(params) {
  StyleText(line1_, params_.font_size, 0.01, 0.55);
  StyleText(line2_, params_.font_size - 2, 0.01, 0.12);
}

void Hud::AddTo(vtkRenderer* renderer) {
  renderer_ = renderer;
  renderer->AddActor2D(line1_);
  renderer->AddActor2D(line2_);
}

void Hud::Update(const review::RunModel& model, int64_t now_utime) {
  const review::LinkStatus link = model.Link(now_utime);
  const Rgb bg = link.level == review::LinkLevel::kOk         ? palette::kHudOk
                 : link.level == review::LinkLevel::kLost     ? palette::kHudLost
                 : link.level == review::LinkLevel::kFinished ? palette::kHudFinished
                                                      : palette::kHudNoMessages;
  if (renderer_) renderer_->SetBackground(bg.r, bg.g, bg.b);
  line1_->SetInput(HudLine(model, now_utime).c_str());
  const std::vector<std::string> problems = model.Problems(now_utime);
  std::string second = problems.empty() ? "no problems" : problems.back();
  if (problems.size() > 1) second += "  (+" + std::to_string(problems.size() - 1) + " more)";
  if (!status_.empty()) second = status_ + "   " + second;
  line2_->SetInput(second.c_str());
}

NozzleBarView::NozzleBarView(const NozzleBarParams& params)
    : params_(params),
      closed_(palette::kNozzleClosed, 14.0, 0.1),
      open_(palette::kNozzleOpen, 14.0, 0.1),
      fault_(palette::kNozzleFault, 14.0, 0.1),
      recent_(palette::kTreated, 6.0, 0.1) {
  StyleText(label_, 11, 0.005, 0.05);
}

void NozzleBarView::AddTo(vtkRenderer* renderer) {
  renderer_ = renderer;
  for (LineLayer* l : {&closed_, &open_, &fault_, &recent_}) l->AddTo(renderer);
  renderer->AddActor2D(label_);
  renderer->GetActiveCamera()->ParallelProjectionOn();
}

void NozzleBarView::Update(const review::RunModel& model, int64_t now_utime) {
  const int n = model.nozzles() ? static_cast<int>(model.nozzles()->open.size()) : 0;
  std::vector<int> counts(static_cast<size_t>(std::max(n, 0)), 0);
  const int64_t since = now_utime - static_cast<int64_t>(params_.recent_s * 1e6);
  for (auto it = model.shots().rbegin(); it != model.shots().rend() && it->open_utime >= since; ++it) {
    if (it->nozzle >= 0 && it->nozzle < n) ++counts[static_cast<size_t>(it->nozzle)];
  }
  // What the bar shows: per nozzle its state (0 closed, 1 open, 2 fault) and
  // recent shots, then failsafe; the VTK data is rebuilt only when it changes.
  std::vector<int> shown;
  for (int i = 0; i < n; ++i) {
    const auto& bar = *model.nozzles();
    const size_t k = static_cast<size_t>(i);
    shown.push_back(bar.fault[k] != 0 ? 2 : bar.open[k] ? 1 : 0);
    shown.push_back(std::min(counts[k], params_.full_scale_shots));
  }
  shown.push_back(model.nozzles() && model.nozzles()->failsafe ? 1 : 0);
  const double aspect = renderer_ ? std::max(1e-6, renderer_->GetTiledAspectRatio()) : 1.0;
  if (shown == shown_ && aspect == aspect_) return;
  shown_ = shown, aspect_ = aspect;
  Show(n);
}

void NozzleBarView::Show(int n) {
  std::vector<Polyline> closed, open, fault, recent;
  for (int i = 0; i < n; ++i) {
    const double x = i + 0.5;
    const int state = shown_[static_cast<size_t>(2 * i)];
    (state == 2 ? fault : state == 1 ? open : closed).push_back(Bar(x, 0.1, 0.5));
    const double h = shown_[static_cast<size_t>(2 * i + 1)] / double(params_.full_scale_shots);
    if (h > 0) recent.push_back(Bar(x, 0.55, 0.55 + 0.4 * h));
  }
  closed_.Set(closed), open_.Set(open), fault_.Set(fault), recent_.Set(recent);
  std::string label = n == 0 ? "nozzle bar: no messages" : "nozzles";
  if (shown_.back() != 0) label += "  FAILSAFE (closed)";
  label_->SetInput(label.c_str());
  if (renderer_ == nullptr) return;
  vtkCamera* c = renderer_->GetActiveCamera();
  const double w = std::max(n, 8) + 2.0;  // room for the label on the left
  c->SetFocalPoint(0.5 * w - 2.0 + 0.5 * 2.0, 0.5, 0.0);
  c->SetPosition(0.5 * w - 1.0, 0.5, 10.0);
  c->SetViewUp(0, 1, 0);
  c->SetParallelScale(std::max(0.55, 0.5 * w / aspect_));
  c->SetClippingRange(1.0, 20.0);
}

}  // namespace plantscale::ui
