#include "ui/station.h"

#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkRenderWindowInteractor.h>

#include <atomic>
#include <chrono>
#include <ctime>
#include <cmath>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>

#include "telemetry/command_auth.h"
#include "telemetry/transport.h"
#include <vtkImageData.h>
#include <vtkImageMapper3D.h>
#include <vtkTextProperty.h>

#include "ui/gateway_source.h"
#include "ui/palette.h"
#include "ui/station_controller.h"
#include "ui/station_sources.h"

namespace plantscale::ui {
namespace {

namespace tm = plantscale::telemetry;
using Clock = std::chrono::steady_clock;


// Layout, normalised window coordinates (x0, y0, x1, y1), y up.
constexpr double kHud[] = {0.0, 0.92, 1.0, 1.0};
constexpr double kMap[] = {0.0, 0.46, 1.0, 0.92};
constexpr double kNozzles[] = {0.0, 0.39, 1.0, 0.46};
constexpr double kCamera[] = {0.0, 0.03, 0.4, 0.39};
constexpr double kTrace[] = {0.4, 0.03, 1.0, 0.39};
constexpr double kTimeline[] = {0.0, 0.0, 1.0, 0.03};

vtkRenderer* Add(Canvas& c, const double* v, Rgb bg) { return c.AddRenderer(v[0], v[1], v[2], v[3], bg); }

}  // namespace

OptionErrors StationOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "width_px", width_px, 320, 8192);
  RequireInRange(e, "height_px", height_px, 240, 8192);
  RequireInRange(e, "ellipse_confidence", ellipse_confidence, 0.0, 1.0, false, false);
  RequireInRange(e, "ellipse_magnification", ellipse_magnification, 1.0, 1000.0);
  RequireInRange(e, "speed", speed, 0.125, 64.0);
  RequireNonNegative(e, "max_seconds", max_seconds);
  RequireNonNegative(e, "close_when_quiet_s", close_when_quiet_s);
  RequireInRange(e, "tour_frames", tour_frames, 0, 1000000);
  if (!log.empty() && review_model) e.push_back({"review", "a log to replay or a run to review, not both"});
  if (gateway && (!log.empty() || review_model)) {
    e.push_back({"gateway", "live over the gateway, or a log or a run to review, not both"});
  }
  RequireNonNegative(e, "gateway_wait_s", gateway_wait_s);
  for (const auto& [at, key] : press) {
    if (!(at >= 0.0)) e.push_back({"press", "the time of key '" + key + "' must be >= 0 s"});
    if (key.empty()) e.push_back({"press", "an empty key"});
  }
  if (offscreen && max_seconds <= 0.0 && close_when_quiet_s <= 0.0 && tour_frames == 0) {
    e.push_back({"offscreen", "needs max_seconds or close_when_quiet_s (nothing would close it)"});
  }
  return e;
}

StationScene::StationScene(Canvas& canvas, const StationOptions& options)
    : map_([&] {
        MapViewParams p;
        p.ellipses.confidence = options.ellipse_confidence;
        p.ellipses.magnification = options.ellipse_magnification;
        return p;
      }()),
      camera_(options.camera),
      trace_([&] {
        OffsetTraceParams p;
        p.window_m = 20.0;
        p.max_points = 600;
        p.cached_width_px = static_cast<int>((kTrace[2] - kTrace[0]) * options.width_px);
        p.cached_height_px = static_cast<int>((kTrace[3] - kTrace[1]) * options.height_px);
        return p;
      }()),
      timeline_(palette::kNozzleOpen, 12.0, 0.1),
      view_span_({1.0, 1.0, 1.0}, 4.0, 0.2) {
  hud_.AddTo(Add(canvas, kHud, palette::kHudOk));
  map_renderer_ = Add(canvas, kMap, palette::kBackground);
  map_.AddTo(map_renderer_);
  annotations_.AddTo(map_renderer_);
  nozzles_.AddTo(Add(canvas, kNozzles, {0.12, 0.12, 0.13}));
  camera_.AddTo(Add(canvas, kCamera, palette::kBackground));
  trace_.AddTo(Add(canvas, kTrace, {1, 1, 1}));
  timeline_renderer_ = Add(canvas, kTimeline, {0.2, 0.2, 0.22});
  timeline_.AddTo(timeline_renderer_);
  overview_->InterpolateOff();
  overview_->VisibilityOff();
  timeline_renderer_->AddActor(overview_);
  view_span_.AddTo(timeline_renderer_);
  for (vtkTextActor* t : {timeline_left_.Get(), timeline_right_.Get()}) {
    t->GetTextProperty()->SetFontSize(11);
    t->GetTextProperty()->SetFontFamilyToCourier();
    t->GetTextProperty()->BoldOn();
    t->GetTextProperty()->SetColor(1.0, 1.0, 1.0);
    t->GetTextProperty()->SetVerticalJustificationToCentered();
    t->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
    timeline_renderer_->AddActor2D(t);
  }
  timeline_left_->SetPosition(0.005, 0.5);
  timeline_right_->GetTextProperty()->SetJustificationToRight();
  timeline_right_->SetPosition(0.995, 0.5);
  vtkCamera* c = timeline_renderer_->GetActiveCamera();
  c->ParallelProjectionOn();
  c->SetFocalPoint(0.5, 0.5, 0), c->SetPosition(0.5, 0.5, 10), c->SetParallelScale(0.5);
}

void StationScene::SetTimelineText(const std::string& left, const std::string& right) {
  const auto set = [](vtkTextActor* t, const std::string& text) {
    if (t->GetInput() == nullptr || text != t->GetInput()) t->SetInput(text.c_str());
  };
  set(timeline_left_, left);
  set(timeline_right_, right);
}

namespace {

std::string EllipseLegend(const MapView& map) {
  if (!map.Visible(MapLayerId::kEllipses)) return "ellipses off (l)";
  const CovarianceEllipses& e = map.ellipses();
  std::ostringstream out;
  out << "ellipses " << std::lround(100.0 * e.params().confidence) << "%, drawn x" << e.params().magnification;
  if (!e.drew_plants()) out << " (vehicle only: no plant covariance here)";
  return out.str();
}

}  // namespace

std::string StationKeysHelp() {
  return "Keys (h or ? shows or hides this list):\n"
         "  m map   p plants   g predicted grid   v vehicle and path   l covariance ellipses\n"
         "  c ellipse confidence 50/90/95/99 %   x ellipse magnification x1/x5/x20/x50\n"
         "  f follow the vehicle / whole bed   Up/Down zoom in/out   [ ] pan back/ahead\n"
         "  mouse wheel zoom about the pointer   right or middle drag pan\n"
         "  left click a plant: its record, ringed   r measure tool: click two points\n"
         "  log: space pause   + - speed   Left/Right seek 5 s   Home restart   click the timeline\n"
         "  live, to the vehicle: S start   P pause   C spray the crop   W spray the weeds   O spraying off\n"
         "  q or Esc quit";
}

std::vector<Rgb> WeedStrip(const review::RunModel& model, const FieldWindow& whole, int columns) {
  const double length = std::max(1e-6, whole.y1_m - whole.y0_m);
  std::vector<int> weeds(static_cast<size_t>(columns), 0), plants(static_cast<size_t>(columns), 0);
  for (const auto& [id, r] : model.plants()) {
    const int c = std::clamp(static_cast<int>((r.plant.position_m.y() - whole.y0_m) / length * columns), 0, columns - 1);
    ++plants[static_cast<size_t>(c)];
    weeds[static_cast<size_t>(c)] += r.plant.kind == telemetry::PlantKind::kWeed;
  }
  const int most = std::max(1, *std::max_element(weeds.begin(), weeds.end()));
  std::vector<Rgb> out;
  for (size_t c = 0; c < weeds.size(); ++c) {
    const double w = static_cast<double>(weeds[c]) / most;
    const Rgb a = palette::kSoil, b = palette::kWeed;
    out.push_back(plants[c] == 0 ? palette::kUnknownCell
                                 : Rgb{a.r + w * (b.r - a.r), a.g + w * (b.g - a.g), a.b + w * (b.b - a.b)});
  }
  return out;
}

void StationScene::SetOverview(const std::vector<Rgb>& columns, double from, double to) {
  if (columns.size() != overview_columns_ && !columns.empty()) {
    overview_columns_ = columns.size();
    // Two rows of the same colours: the strip's height is the bar's.
    const double aspect = std::max(1e-6, timeline_renderer_->GetTiledAspectRatio()), h = 1.0 / aspect;
    auto image = vtkSmartPointer<vtkImageData>::New();
    image->SetDimensions(static_cast<int>(columns.size()), 2, 1);
    image->SetSpacing(1.0 / static_cast<double>(columns.size()), 0.5 * h, 1.0);
    image->SetOrigin(0.5 / static_cast<double>(columns.size()), 0.5 - 0.25 * h, 0.0);
    image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
    auto* px = static_cast<unsigned char*>(image->GetScalarPointer());
    for (size_t row = 0, i = 0; row < 2; ++row) {
      for (const Rgb& c : columns) {
        for (const double v : {c.r, c.g, c.b}) px[i++] = static_cast<unsigned char>(std::lround(255.0 * v));
      }
    }
    overview_->GetMapper()->BorderOn();
    overview_->GetMapper()->SetInputData(image);
    overview_->VisibilityOn();
  }
  const std::pair<double, double> span{std::clamp(from, 0.0, 1.0), std::clamp(to, 0.0, 1.0)};
  if (span == view_span_at_) return;
  view_span_at_ = span;
  const double min_width = 2.0 / std::max(1, timeline_renderer_->GetSize()[0]);
  view_span_.Set({{{span.first, 0.5}, {std::max(span.second, span.first + min_width), 0.5}}});
}

void StationScene::Update(const review::RunModel& model, int64_t now_utime, double fraction) {
  map_.Update(model);
  annotations_.Update(map_.metres_per_pixel(), EllipseLegend(map_));
  hud_.Update(model, now_utime);
  nozzles_.Update(model, now_utime);
  camera_.Update(model);
  trace_.Update(model);
  const double aspect = std::max(1e-6, timeline_renderer_->GetTiledAspectRatio());
  timeline_renderer_->GetActiveCamera()->SetParallelScale(0.5 / aspect);
  if (fraction < 0) return;
  // The bar ends on a whole pixel, so that it changes (and its viewport is
  // redrawn) only when it grows by one.
  const double pixels = std::max(1, timeline_renderer_->GetSize()[0]);
  const double end = std::round(std::clamp(fraction, 0.0, 1.0) * pixels) / pixels;
  if (end == timeline_end_) return;
  timeline_end_ = end;
  timeline_.Set({{{0.0, 0.5}, {end, 0.5}}});
}

namespace {

void RunInteractive(Canvas& canvas, StationController& controller) {
  vtkNew<vtkRenderWindowInteractor> interactor;
  interactor->SetRenderWindow(canvas.window());
  interactor->SetInteractorStyle(nullptr);  // no camera rotation: our keys and clicks only
  interactor->Initialize();
  struct Context {
    StationController* controller;
    vtkRenderWindowInteractor* interactor;
    Clock::time_point start, last;
  } context{&controller, interactor, Clock::now(), Clock::now()};
  const auto on_event = [](vtkObject*, unsigned long event, void* data, void*) {
    auto* c = static_cast<Context*>(data);
    const int* p = c->interactor->GetEventPosition();
    switch (event) {
      case vtkCommand::KeyPressEvent:
        if (c->controller->Key(c->interactor->GetKeySym() ? c->interactor->GetKeySym() : "")) {
          c->interactor->TerminateApp();
        }
        break;
      case vtkCommand::LeftButtonPressEvent:
        return c->controller->Click(p[0], p[1]);
      case vtkCommand::MouseWheelForwardEvent:
      case vtkCommand::MouseWheelBackwardEvent:
        return c->controller->Wheel(p[0], p[1], event == vtkCommand::MouseWheelForwardEvent ? 1 : -1);
      case vtkCommand::RightButtonPressEvent:
      case vtkCommand::MiddleButtonPressEvent:
        return c->controller->DragStart(p[0], p[1]);
      case vtkCommand::MouseMoveEvent:
        return c->controller->DragTo(p[0], p[1]);
      case vtkCommand::RightButtonReleaseEvent:
      case vtkCommand::MiddleButtonReleaseEvent:
        return c->controller->DragEnd();
      case vtkCommand::TimerEvent: {
        c->controller->PressDue(c->start);
        const Clock::time_point now = Clock::now();
        c->controller->Frame(std::chrono::duration<double>(now - c->last).count());
        c->last = now;
        if (c->controller->ShouldClose(c->start)) c->interactor->TerminateApp();
        break;
      }
      default:
        break;
    }
  };
  vtkNew<vtkCallbackCommand> callback;
  callback->SetCallback(on_event);
  callback->SetClientData(&context);
  for (unsigned long e : {vtkCommand::KeyPressEvent, vtkCommand::LeftButtonPressEvent, vtkCommand::TimerEvent,
                          vtkCommand::MouseWheelForwardEvent, vtkCommand::MouseWheelBackwardEvent,
                          vtkCommand::RightButtonPressEvent, vtkCommand::RightButtonReleaseEvent,
                          vtkCommand::MiddleButtonPressEvent, vtkCommand::MiddleButtonReleaseEvent,
                          vtkCommand::MouseMoveEvent}) {
    interactor->AddObserver(e, callback);
  }
  interactor->CreateRepeatingTimer(15);
  interactor->Start();
}

// Frames touring the bed, each timed from the update to the rendered frame.
std::vector<double> RunTour(StationController& controller, int frames) {
  std::vector<double> ms;
  for (int i = 0; i < frames; ++i) {
    const Clock::time_point t0 = Clock::now();
    controller.TourStep(i);
    controller.Frame(0.0);
    ms.push_back(1e3 * std::chrono::duration<double>(Clock::now() - t0).count());
  }
  return ms;
}

}  // namespace

StationResult RunStation(const StationOptions& options) {
  ThrowIfInvalid("station options", options.Validate());
  std::optional<tm::CommandKey> command_key;
  if (!options.command_key.empty() && options.log.empty()) command_key = tm::ReadCommandKey(options.command_key);
  RequireDisplay("plantscale station");
  std::unique_ptr<Source> source;
  if (options.review_model) {
    source = std::make_unique<ReviewSource>(options.review_model, options.review_name, options.review_error);
  } else if (!options.log.empty()) {
    source = std::make_unique<LogSource>(options.log, options.speed);
  } else if (options.gateway) {
    auto gateway = std::make_unique<GatewaySource>(*options.gateway, std::move(command_key));
    gateway->WaitFirstAttempt(options.gateway_wait_s);  // a refused token: thrown before any window
    source = std::move(gateway);
  } else {
    source = std::make_unique<LiveSource>(options.lcm_url, std::move(command_key));
  }
  Canvas canvas(options.width_px, options.height_px, options.offscreen);
  canvas.window()->SetWindowName("plantscale station");
  StationScene scene(canvas, options);
  StationController controller(canvas, scene, *source, options);
  const Clock::time_point start = Clock::now();
  StationResult result;
  if (options.tour_frames > 0) {
    controller.Frame(0.0);
    const std::clock_t cpu0 = std::clock();
    result.tour_frame_ms = RunTour(controller, options.tour_frames);
    result.tour_cpu_ms = 1e3 * static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  } else if (options.offscreen) {
    Clock::time_point last = start;
    while (!controller.ShouldClose(start)) {
      controller.PressDue(start);
      const Clock::time_point now = Clock::now();
      if (!controller.Frame(std::chrono::duration<double>(now - last).count())) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));  // nothing changed
      }
      last = now;
    }
    // The time the last frame took plays too: off-screen, the log has played
    // max_seconds × speed when the station closes, however slow the frames.
    controller.Frame(std::chrono::duration<double>(Clock::now() - last).count());
  } else {
    RunInteractive(canvas, controller);
  }
  if (!options.screenshot.empty()) {
    // The window as it closed, the HUD at the closing time.
    controller.Frame(0.0);
    WritePng(canvas.Render(), options.screenshot);
  }
  result.frames = controller.frames();
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.frames_per_second = result.seconds > 0 ? result.frames / result.seconds : 0.0;
  std::lock_guard lock(source->mutex);
  if (!source->LogError().empty()) result.problems.push_back("log: " + source->LogError());
  for (const std::string& p : source->model().Problems(source->now_utime())) result.problems.push_back(p);
  result.link = source->model().Link(source->now_utime()).text;
  result.link_changes = source->LinkChanges();
  result.command_replies = controller.command_replies();
  const review::RunModel& model = source->model();
  result.messages = model.messages();
  result.grid_states = model.trace().size();
  result.map_tiles = model.tiles().size();
  result.tile_revisions = model.tile_revision_sum();
  result.plants = model.plants().size();
  for (const plantscale_event_t& e : model.events()) result.events.push_back(e.kind + ": " + e.text);
  result.grid_lag_ms = model.grid_lag_ms();
  const auto thumbnails = model.channels().find(tm::channels::kThumbnail);
  if (thumbnails != model.channels().end()) result.thumbnails = thumbnails->second.received;
  result.link_bytes = source->LinkBytes();
  return result;
}

}  // namespace plantscale::ui
