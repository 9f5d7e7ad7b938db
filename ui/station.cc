#include "ui/station.h"

#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkRenderWindowInteractor.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>

#include "telemetry/command_auth.h"
#include "telemetry/transport.h"
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
  RequireInRange(e, "speed", speed, 0.125, 64.0);
  RequireNonNegative(e, "max_seconds", max_seconds);
  RequireNonNegative(e, "close_when_quiet_s", close_when_quiet_s);
  if (offscreen && max_seconds <= 0.0 && close_when_quiet_s <= 0.0) {
    e.push_back({"offscreen", "needs max_seconds or close_when_quiet_s (nothing would close it)"});
  }
  return e;
}

StationScene::StationScene(Canvas& canvas, const StationOptions& options)
    : map_([&] {
        MapViewParams p;
        p.ellipses.confidence = options.ellipse_confidence;
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
      timeline_(palette::kNozzleOpen, 12.0, 0.1) {
  hud_.AddTo(Add(canvas, kHud, palette::kHudOk));
  map_renderer_ = Add(canvas, kMap, palette::kBackground);
  map_.AddTo(map_renderer_);
  nozzles_.AddTo(Add(canvas, kNozzles, {0.12, 0.12, 0.13}));
  camera_.AddTo(Add(canvas, kCamera, palette::kBackground));
  trace_.AddTo(Add(canvas, kTrace, {1, 1, 1}));
  timeline_renderer_ = Add(canvas, kTimeline, {0.2, 0.2, 0.22});
  timeline_.AddTo(timeline_renderer_);
  vtkCamera* c = timeline_renderer_->GetActiveCamera();
  c->ParallelProjectionOn();
  c->SetFocalPoint(0.5, 0.5, 0), c->SetPosition(0.5, 0.5, 10), c->SetParallelScale(0.5);
}

void StationScene::Update(const RunModel& model, int64_t now_utime, double fraction) {
  map_.Update(model);
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
    if (event == vtkCommand::KeyPressEvent) {
      if (c->controller->Key(c->interactor->GetKeySym() ? c->interactor->GetKeySym() : "")) {
        c->interactor->TerminateApp();
      }
    } else if (event == vtkCommand::LeftButtonPressEvent) {
      const int* p = c->interactor->GetEventPosition();
      c->controller->Click(p[0], p[1]);
    } else if (event == vtkCommand::TimerEvent) {
      const Clock::time_point now = Clock::now();
      c->controller->Frame(std::chrono::duration<double>(now - c->last).count());
      c->last = now;
      if (c->controller->ShouldClose(c->start)) c->interactor->TerminateApp();
    }
  };
  vtkNew<vtkCallbackCommand> callback;
  callback->SetCallback(on_event);
  callback->SetClientData(&context);
  for (unsigned long e : {vtkCommand::KeyPressEvent, vtkCommand::LeftButtonPressEvent, vtkCommand::TimerEvent}) {
    interactor->AddObserver(e, callback);
  }
  interactor->CreateRepeatingTimer(15);
  interactor->Start();
}

}  // namespace

StationResult RunStation(const StationOptions& options) {
  ThrowIfInvalid("station options", options.Validate());
  std::optional<tm::CommandKey> command_key;
  if (!options.command_key.empty() && options.log.empty()) command_key = tm::ReadCommandKey(options.command_key);
  RequireDisplay("plantscale station");
  std::unique_ptr<Source> source;
  if (!options.log.empty()) {
    source = std::make_unique<LogSource>(options.log, options.speed);
  } else {
    source = std::make_unique<LiveSource>(options.lcm_url, std::move(command_key));
  }
  Canvas canvas(options.width_px, options.height_px, options.offscreen);
  canvas.window()->SetWindowName("plantscale station");
  StationScene scene(canvas, options);
  StationController controller(canvas, scene, *source, options);
  const Clock::time_point start = Clock::now();
  if (options.offscreen) {
    Clock::time_point last = start;
    while (!controller.ShouldClose(start)) {
      const Clock::time_point now = Clock::now();
      if (!controller.Frame(std::chrono::duration<double>(now - last).count())) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));  // nothing changed
      }
      last = now;
    }
  } else {
    RunInteractive(canvas, controller);
  }
  StationResult result;
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
  return result;
}

}  // namespace plantscale::ui
