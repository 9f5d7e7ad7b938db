#pragma once
// Keys, clicks and the per-frame update of a running station (the keys are
// listed in station.h). Separate from the event loop so tests can drive it.

#include <chrono>
#include <iterator>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>

#include "ui/station.h"
#include "ui/station_sources.h"

namespace plantscale::ui {

// plantscale_plant_t::WHY_* in words.
inline std::string WhyName(int why) {
  static const char* names[] = {"undecided", "crop in its region", "outside crop region", "too small",
                                "too large", "failsafe", "spray mode", "run ended before the bar"};
  return why >= 0 && why < static_cast<int>(std::size(names)) ? names[why] : "?";
}

class StationController {
 public:
  StationController(Canvas& canvas, StationScene& scene, Source& source, const StationOptions& o)
      : canvas_(canvas), scene_(scene), source_(source), options_(o) {}

  // Updates the scene and renders when something visible changed: a new
  // message, the HUD text (heartbeat age, clock), a key or a click. An idle
  // station then costs nothing between messages (copying the window to the
  // screen alone is ~5 ms of CPU at 1280×720 under Xvfb).
  bool Frame(double wall_s) {
    {
      std::lock_guard lock(source_.mutex);
      source_.Tick(wall_s);
      if (source_.model().messages() != last_messages_) {
        last_messages_ = source_.model().messages();
        last_message_time_ = std::chrono::steady_clock::now();
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
  bool ShouldClose(std::chrono::steady_clock::time_point start) const {
    const std::chrono::steady_clock::time_point now = std::chrono::steady_clock::now();
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
    // Commands to the vehicle: upper case, so that no view key sends one by mistake.
    using C = plantscale_command_t;
    if (key == "S") tool_text_ = source_.SendCommand(C::COMMAND_START, 0);
    if (key == "P") tool_text_ = source_.SendCommand(C::COMMAND_PAUSE, 0);
    if (key == "C") tool_text_ = source_.SendCommand(C::COMMAND_SET_MODE, C::MODE_SPRAY_CROP);
    if (key == "W") tool_text_ = source_.SendCommand(C::COMMAND_SET_MODE, C::MODE_SPRAY_WEED);
    if (key == "O") tool_text_ = source_.SendCommand(C::COMMAND_SET_MODE, C::MODE_SPRAY_OFF);
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
  // What the last click or measurement said (shown on the HUD's second line).
  const std::string& tool_text() const { return tool_text_; }

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
    const telemetry::PlantObservation& p = best->plant;
    std::ostringstream out;
    out.precision(3);
    out << std::fixed << "plant " << p.id << ": "
        << (p.kind == telemetry::PlantKind::kCrop ? "crop" : p.kind == telemetry::PlantKind::kWeed ? "weed" : "unknown")
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
  std::chrono::steady_clock::time_point last_message_time_ = std::chrono::steady_clock::now();
  int64_t drawn_messages_ = -1;
  std::string drawn_hud_;
};

}  // namespace plantscale::ui
