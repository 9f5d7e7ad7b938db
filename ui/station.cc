#include "ui/station.h"

#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkRenderWindowInteractor.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <sstream>
#include <thread>

#include "telemetry/transport.h"
#include "ui/palette.h"
#include "ui/station_timeline.h"

namespace plantscale::ui {
namespace {

namespace tm = plantscale::telemetry;
using Clock = std::chrono::steady_clock;

// Where the model comes from: a log with a timeline, or live LCM.
class Source {
 public:
  virtual ~Source() = default;
  virtual void Tick(double wall_s) = 0;
  virtual const RunModel& model() const = 0;
  virtual int64_t now_utime() const = 0;
  virtual double fraction() const { return -1.0; }  // timeline position, < 0 live
  virtual void Seek(double, bool) {}
  virtual void TogglePause() {}
  virtual void ScaleSpeed(double) {}
  virtual std::string Status() const = 0;
  virtual std::string LogError() const { return ""; }  // the log could not be read to its end
  std::mutex mutex;  // held while the model is read or changed
};

class LogSource : public Source {
 public:
  LogSource(const std::filesystem::path& log, double speed) : timeline_(LogTimeline::Load(log)) {
    timeline_.SetSpeed(speed);
    timeline_.Seek(0.0);
  }
  void Tick(double wall_s) override { timeline_.Advance(wall_s); }
  const RunModel& model() const override { return timeline_.model(); }
  int64_t now_utime() const override { return timeline_.now_utime(); }
  double fraction() const override {
    return timeline_.duration_s() > 0 ? timeline_.position_s() / timeline_.duration_s() : 0.0;
  }
  void Seek(double value, bool relative) override {
    timeline_.Seek(relative ? timeline_.position_s() + value : value * timeline_.duration_s());
  }
  void TogglePause() override { timeline_.SetPaused(!timeline_.paused()); }
  std::string LogError() const override { return timeline_.error(); }
  void ScaleSpeed(double f) override { timeline_.SetSpeed(std::clamp(timeline_.speed() * f, 0.125, 64.0)); }
  std::string Status() const override {
    std::ostringstream out;
    out.precision(1);
    out << std::fixed << (timeline_.paused() ? "PAUSED " : "") << "log " << timeline_.position_s() << "/"
        << timeline_.duration_s() << " s x" << timeline_.speed();
    if (!timeline_.error().empty()) out << "  LOG CUT: " << timeline_.error();
    if (timeline_.empty()) out << "  (log has no events)";
    return out.str();
  }

 private:
  LogTimeline timeline_;
};

class LiveSource : public Source {
 public:
  explicit LiveSource(const std::string& url) : transport_(url.empty() ? tm::LcmTransportOptions{}.url : url) {
    subscriber_.SetObserver([this](const std::string& ch, bool applied, const tm::TelemetrySnapshot& s) {
      std::lock_guard lock(mutex);
      model_.Observe(ch, applied, s);
    });
    subscriber_.Attach(transport_);
    thread_ = std::thread([this] {
      while (!stop_) transport_.Handle(50);
    });
  }
  ~LiveSource() override {
    stop_ = true;
    thread_.join();
  }
  void Tick(double) override {}
  const RunModel& model() const override { return model_; }
  int64_t now_utime() const override { return tm::WallUtime(); }
  std::string Status() const override { return "live " + transport_.url(); }

 private:
  tm::LcmTransport transport_;
  tm::Subscriber subscriber_;
  RunModel model_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

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
  if (fraction >= 0) timeline_.Set({{{0.0, 0.5}, {std::clamp(fraction, 0.0, 1.0), 0.5}}});
}

namespace {

std::string WhyName(int why) {
  static const char* names[] = {"undecided", "crop in its region", "outside crop region", "too small",
                                "too large", "failsafe", "spray mode"};
  return why >= 0 && why < 7 ? names[why] : "?";
}

// Keys, clicks and the per-frame update of a running station.
class Controller {
 public:
  Controller(Canvas& canvas, StationScene& scene, Source& source, const StationOptions& o)
      : canvas_(canvas), scene_(scene), source_(source), options_(o) {}

  // Updates the scene and renders when something visible changed: a new
  // message, the HUD text (heartbeat age, clock), a key or a click. An idle
  // station then costs nothing between messages (the window's swap alone is
  // ~13 ms of CPU at 1280×720 under Xvfb).
  bool Frame(double wall_s) {
    {
      std::lock_guard lock(source_.mutex);
      source_.Tick(wall_s);
      if (source_.model().messages() != last_messages_) {
        last_messages_ = source_.model().messages();
        last_message_time_ = Clock::now();
      }
      const std::string status = source_.Status() + Tools();
      const std::string hud = HudLine(source_.model(), source_.now_utime()) + status;
      const int64_t messages = source_.model().messages();
      if (!dirty_ && messages == drawn_messages_ && hud == drawn_hud_) return false;
      dirty_ = false, drawn_messages_ = messages, drawn_hud_ = hud;
      scene_.hud().SetStatus(status);
      scene_.Update(source_.model(), source_.now_utime(), source_.fraction());
    }
    canvas_.window()->Render();
    ++frames_;
    return true;
  }

  // max_seconds reached, or messages stopped close_when_quiet_s ago.
  bool ShouldClose(Clock::time_point start) const {
    const Clock::time_point now = Clock::now();
    if (options_.max_seconds > 0 && std::chrono::duration<double>(now - start).count() > options_.max_seconds) {
      return true;
    }
    return options_.close_when_quiet_s > 0 && last_messages_ > 0 &&
           std::chrono::duration<double>(now - last_message_time_).count() > options_.close_when_quiet_s;
  }

  bool Key(const std::string& key) {
    std::lock_guard lock(source_.mutex);
    dirty_ = true;
    MapView& map = scene_.map();
    const auto toggle = [&](MapLayerId id) { map.SetVisible(id, !map.Visible(id)); };
    if (key == "m") toggle(MapLayerId::kMap);
    if (key == "p") toggle(MapLayerId::kPlants);
    if (key == "g") toggle(MapLayerId::kGrid);
    if (key == "l") toggle(MapLayerId::kEllipses);
    if (key == "v") toggle(MapLayerId::kVehicle);
    if (key == "f") follow_ = !follow_, map.SetWindow(follow_ ? std::nullopt : std::optional(map.WholeRun(source_.model())));
    if (key == "c") confidence_ = (confidence_ + 1) % 4, map.ellipses().SetConfidence(kConfidences[confidence_]);
    if (key == "space") source_.TogglePause();
    if (key == "plus" || key == "equal" || key == "KP_Add") source_.ScaleSpeed(2.0);
    if (key == "minus" || key == "KP_Subtract") source_.ScaleSpeed(0.5);
    if (key == "Left") source_.Seek(-5.0, true);
    if (key == "Right") source_.Seek(5.0, true);
    if (key == "Home") source_.Seek(0.0, false);
    if (key == "r") measuring_ = !measuring_, first_.reset(), tool_text_.clear();
    return key == "q" || key == "Escape";
  }

  void Click(int x, int y) {
    std::lock_guard lock(source_.mutex);
    dirty_ = true;
    const int* size = canvas_.window()->GetSize();
    const double fx = static_cast<double>(x) / size[0], fy = static_cast<double>(y) / size[1];
    if (fy < 0.03) return source_.Seek(fx, false);
    if (!scene_.map_renderer()->IsInViewport(x, y)) return;
    const Eigen::Vector2d at = scene_.map().FieldAtDisplay(x, y);
    if (measuring_) return Measure(at);
    tool_text_ = PlantRecordText(at);
  }

  int64_t frames() const { return frames_; }

 private:
  static constexpr double kConfidences[] = {0.5, 0.9, 0.95, 0.99};

  std::string Tools() const {
    std::string s = "  ellipses " + std::to_string(static_cast<int>(kConfidences[confidence_] * 100)) + "%";
    if (measuring_) s += "  MEASURE";
    if (!tool_text_.empty()) s += "  | " + tool_text_;
    return s;
  }

  void Measure(const Eigen::Vector2d& at) {
    if (!first_) {
      first_ = at;
      tool_text_ = "measure: click the second point";
      return;
    }
    std::ostringstream out;
    out.precision(3);
    out << std::fixed << "distance " << (at - *first_).norm() << " m";
    tool_text_ = out.str();
    first_.reset();
  }

  std::string PlantRecordText(const Eigen::Vector2d& at) const {
    const PlantRecord* best = nullptr;
    double best_d = 0.15;  // clicks farther than this from any plant select nothing
    for (const auto& [id, r] : source_.model().plants()) {
      const double d = (r.plant.position_m - at).norm();
      if (d < best_d) best_d = d, best = &r;
    }
    if (best == nullptr) return "no plant within 0.15 m of the click";
    const tm::PlantObservation& p = best->plant;
    std::ostringstream out;
    out.precision(3);
    out << std::fixed << "plant " << p.id << ": "
        << (p.kind == tm::PlantKind::kCrop ? "crop" : p.kind == tm::PlantKind::kWeed ? "weed" : "unknown")
        << ", " << 1e4 * p.size_m2 << " cm2, " << 1e3 * p.distance_to_crop_m << " mm to predicted crop, "
        << (p.sprayed ? "sprayed" : "not sprayed") << " (" << WhyName(p.why) << ")";
    return out.str();
  }

  Canvas& canvas_;
  StationScene& scene_;
  Source& source_;
  StationOptions options_;
  bool follow_ = true, measuring_ = false;
  int confidence_ = 2;
  std::optional<Eigen::Vector2d> first_;
  std::string tool_text_;
  int64_t frames_ = 0;
  bool dirty_ = true;
  int64_t last_messages_ = 0;
  Clock::time_point last_message_time_ = Clock::now();
  int64_t drawn_messages_ = -1;
  std::string drawn_hud_;
};

void RunInteractive(Canvas& canvas, Controller& controller) {
  vtkNew<vtkRenderWindowInteractor> interactor;
  interactor->SetRenderWindow(canvas.window());
  interactor->SetInteractorStyle(nullptr);  // no camera rotation: our keys and clicks only
  interactor->Initialize();
  struct Context {
    Controller* controller;
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
  RequireDisplay("plantscale station");
  std::unique_ptr<Source> source;
  if (!options.log.empty()) {
    source = std::make_unique<LogSource>(options.log, options.speed);
  } else {
    source = std::make_unique<LiveSource>(options.lcm_url);
  }
  Canvas canvas(options.width_px, options.height_px, options.offscreen);
  canvas.window()->SetWindowName("plantscale station");
  StationScene scene(canvas, options);
  Controller controller(canvas, scene, *source, options);
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
  result.frames = controller.frames();
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.frames_per_second = result.seconds > 0 ? result.frames / result.seconds : 0.0;
  std::lock_guard lock(source->mutex);
  if (!source->LogError().empty()) result.problems.push_back("log: " + source->LogError());
  for (const std::string& p : source->model().Problems(source->now_utime())) result.problems.push_back(p);
  return result;
}

}  // namespace plantscale::ui
