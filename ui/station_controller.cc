#include "ui/station_controller.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iterator>
#include <mutex>
#include <sstream>

namespace plantscale::ui {
namespace {

constexpr double kConfidences[] = {0.5, 0.9, 0.95, 0.99};
constexpr double kMagnifications[] = {1.0, 5.0, 20.0, 50.0};
constexpr double kZoomStep = 1.5;    // Up / Down
constexpr double kWheelStep = 1.25;  // one wheel notch
constexpr int kStripColumns = 640;    // review: the bed's weed strip along the bottom bar

}  // namespace

std::string WhyName(int why) {
  static const char* names[] = {"undecided", "crop in its region", "outside crop region", "too small",
                                "too large", "failsafe", "spray mode", "run ended before the bar",
                                "the grower's model"};  // plantscale_plant_t::WHY_*
  return why >= 0 && why < static_cast<int>(std::size(names)) ? names[why] : "?";
}

std::string Rounded(double value, int decimals) {
  std::ostringstream out;
  out.precision(decimals);
  out << std::fixed << value;
  return out.str();
}

std::string ClockText(double seconds) {
  if (seconds < 120.0) return Rounded(seconds, 1) + " s";
  const int64_t s = static_cast<int64_t>(seconds);
  std::ostringstream out;
  out.fill('0');
  if (s >= 3600) out << s / 3600 << ':' << std::setw(2) << (s / 60) % 60 << ':';
  else out << s / 60 << ':';
  out << std::setw(2) << s % 60;
  return out.str();
}

std::string PlantRecordText(const review::PlantRecord& r) {
  const telemetry::PlantObservation& p = r.plant;
  const double cm2 = 1e4 * p.size_m2;
  std::ostringstream out;
  out << "plant " << p.id << ": "
      << (p.kind == telemetry::PlantKind::kCrop ? "crop" : p.kind == telemetry::PlantKind::kWeed ? "weed" : "unknown")
      << ", " << Rounded(cm2, cm2 >= 10.0 ? 0 : 1) << " cm2, ";
  if (r.why_text.empty()) out << Rounded(1e3 * p.distance_to_crop_m, 0) << " mm to predicted crop, ";
  out << "at " << Rounded(p.position_m.y(), 2) << " m along, " << (p.sprayed ? "sprayed" : "not sprayed") << " ("
      << (r.why_text.empty() ? WhyName(p.why) : r.why_text) << ")";
  return out.str();
}

bool StationController::Frame(double wall_s) {
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
    if (source_.review() && !placed_) placed_ = true, scene_.map().SetWindow(scene_.map().WholeRun(source_.model()));
    scene_.hud().SetStatus(status);
    scene_.map().SetMarks(PickPosition(), measure_);
    scene_.Update(source_.model(), source_.now_utime(), source_.review() ? -1.0 : source_.fraction());
    // After the update: the view it framed.
    scene_.SetTimelineText(TimelineLeft(), TimelineRight());
    if (source_.review()) {
      const FieldWindow whole = scene_.map().WholeRun(source_.model()), &view = scene_.map().view();
      const double length = std::max(1e-6, whole.y1_m - whole.y0_m);
      if (strip_.empty()) strip_ = WeedStrip(source_.model(), whole, kStripColumns);
      scene_.SetOverview(strip_, (view.y0_m - whole.y0_m) / length, (view.y1_m - whole.y0_m) / length);
    }
  }
  canvas_.window()->Render();
  ++frames_;
  return true;
}

void StationController::PressDue(std::chrono::steady_clock::time_point start) {
  const double at = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  while (pressed_ < options_.press.size() && options_.press[pressed_].first <= at) {
    quit_ = Key(options_.press[pressed_++].second) || quit_;
  }
}

bool StationController::ShouldClose(std::chrono::steady_clock::time_point start) const {
  if (quit_) return true;
  const std::chrono::steady_clock::time_point now = std::chrono::steady_clock::now();
  if (options_.max_seconds > 0 && std::chrono::duration<double>(now - start).count() > options_.max_seconds) {
    return true;
  }
  return options_.close_when_quiet_s > 0 && last_messages_ > 0 &&
         std::chrono::duration<double>(now - last_message_time_).count() > options_.close_when_quiet_s;
}

bool StationController::Key(const std::string& key) {
  std::lock_guard lock(source_.mutex);
  dirty_ = true;
  ViewKey(key);
  PlayKey(key);
  CommandKey(key);
  return key == "q" || key == "Escape";
}

void StationController::ViewKey(const std::string& key) {
  MapView& map = scene_.map();
  const auto toggle = [&](MapLayerId id) { map.SetVisible(id, !map.Visible(id)); };
  if (key == "m") toggle(MapLayerId::kMap);
  if (key == "p") toggle(MapLayerId::kPlants);
  if (key == "g") toggle(MapLayerId::kGrid);
  if (key == "l") toggle(MapLayerId::kEllipses);
  if (key == "v") toggle(MapLayerId::kVehicle);
  if (key == "f") map.SetWindow(map.following() ? std::optional(map.WholeRun(source_.model())) : std::nullopt);
  if (key == "c") confidence_ = (confidence_ + 1) % 4, map.ellipses().SetConfidence(kConfidences[confidence_]);
  if (key == "x") NextMagnification();
  if (key == "h" || key == "question") {
    scene_.annotations().SetHelp(scene_.annotations().help_visible() ? "" : StationKeysHelp());
  }
  if (key == "Up") map.Zoom(kZoomStep);
  if (key == "Down") map.Zoom(1.0 / kZoomStep);
  if (key == "bracketleft" || key == "bracketright") {
    map.Pan((key == "bracketleft" ? -0.5 : 0.5) * (map.view().y1_m - map.view().y0_m), 0.0);
  }
  if (key == "r") measuring_ = !measuring_, ClearTools();
}

void StationController::PlayKey(const std::string& key) {
  if (key == "space") source_.TogglePause();
  if (key == "plus" || key == "equal" || key == "KP_Add") source_.ScaleSpeed(2.0);
  if (key == "minus" || key == "KP_Subtract") source_.ScaleSpeed(0.5);
  if (key == "Left") Seek(-5.0, true);
  if (key == "Right") Seek(5.0, true);
  if (key == "Home") Seek(0.0, false);
}

// Commands to the vehicle: upper case, so that no view key sends one by mistake.
void StationController::CommandKey(const std::string& key) {
  using C = plantscale_command_t;
  if (key == "S") tool_text_ = source_.SendCommand(C::COMMAND_START, 0);
  if (key == "P") tool_text_ = source_.SendCommand(C::COMMAND_PAUSE, 0);
  if (key == "C") tool_text_ = source_.SendCommand(C::COMMAND_SET_MODE, C::MODE_SPRAY_CROP);
  if (key == "W") tool_text_ = source_.SendCommand(C::COMMAND_SET_MODE, C::MODE_SPRAY_WEED);
  if (key == "O") tool_text_ = source_.SendCommand(C::COMMAND_SET_MODE, C::MODE_SPRAY_OFF);
  if (key == "S" || key == "P" || key == "C" || key == "W" || key == "O") command_replies_.push_back(tool_text_);
}

void StationController::Click(int x, int y) {
  std::lock_guard lock(source_.mutex);
  dirty_ = true;
  const int* size = canvas_.window()->GetSize();
  const double fx = static_cast<double>(x) / size[0], fy = static_cast<double>(y) / size[1];
  if (fy < 0.03) return source_.review() ? GoToMetre(fx) : Seek(fx, false);
  if (!scene_.map_renderer()->IsInViewport(x, y)) return;
  const Eigen::Vector2d at = scene_.map().FieldAtDisplay(x, y);
  if (measuring_) return Measure(at);
  Pick(at);
}

void StationController::Wheel(int x, int y, int steps) {
  std::lock_guard lock(source_.mutex);
  if (!scene_.map_renderer()->IsInViewport(x, y)) return;
  dirty_ = true;
  scene_.map().Zoom(std::pow(kWheelStep, steps), scene_.map().FieldAtDisplay(x, y).y());
}

void StationController::DragStart(int x, int y) {
  std::lock_guard lock(source_.mutex);
  if (scene_.map_renderer()->IsInViewport(x, y)) drag_ = Eigen::Vector2d(x, y);
}

void StationController::DragTo(int x, int y) {
  std::lock_guard lock(source_.mutex);
  if (!drag_) return;
  const MapView& map = scene_.map();
  const Eigen::Vector2d moved = map.FieldAtDisplay(drag_->x(), drag_->y()) - map.FieldAtDisplay(x, y);
  scene_.map().Pan(moved.y(), moved.x());
  drag_ = Eigen::Vector2d(x, y);
  dirty_ = true;
}

std::string StationController::Tools() const {
  std::string s = "  ellipses " + std::to_string(static_cast<int>(std::lround(kConfidences[confidence_] * 100))) +
                  "% x" + Rounded(scene_.map().ellipses().params().magnification, 0);
  if (measuring_) s += "  MEASURE";
  if (!tool_text_.empty()) s += "  | " + tool_text_;
  return s;
}

void StationController::NextMagnification() {
  const double now = scene_.map().ellipses().params().magnification;
  double next = kMagnifications[0];
  for (const double m : kMagnifications) {
    if (m > now + 1e-9) {
      next = m;
      break;
    }
  }
  scene_.map().ellipses().SetMagnification(next);
}

void StationController::Seek(double value, bool relative) {
  source_.Seek(value, relative);
  ClearTools();
}

void StationController::ClearTools() {
  tool_text_.clear();
  measure_.clear();
  pick_.reset();
}

void StationController::GoToMetre(double fraction) {
  MapView& map = scene_.map();
  const FieldWindow whole = map.WholeRun(source_.model());
  const double y = whole.y0_m + std::clamp(fraction, 0.0, 1.0) * (whole.y1_m - whole.y0_m);
  const double half = 0.5 * std::min(map.view().y1_m - map.view().y0_m, 20.0);
  map.SetWindow(FieldWindow{y - half, y + half, map.view().x_centre_m});
}

void StationController::TourStep(int i) {
  std::lock_guard lock(source_.mutex);
  dirty_ = true;
  MapView& map = scene_.map();
  const FieldWindow whole = map.WholeRun(source_.model());
  const double bed = std::max(1.0, whole.y1_m - whole.y0_m);
  const double lengths[] = {6.0, 40.0, 300.0, bed};
  const int leg = i / 50;
  const double length = std::min(bed, lengths[leg % 4]);
  const double golden = 0.6180339887, place = leg * golden - std::floor(leg * golden);
  // The whole bed pans too (by 1 % a frame), so that every frame redraws the map.
  const double start = length >= bed ? whole.y0_m : whole.y0_m + place * (bed - length);
  const double y0 = start + (i % 50) * (length >= bed ? 0.01 : 0.1) * length;
  map.SetWindow(FieldWindow{y0, y0 + length, 0.0});
}

std::string StationController::TimelineLeft() const {
  if (source_.review()) {
    const FieldWindow whole = scene_.map().WholeRun(source_.model());
    return "bed " + Rounded(whole.y0_m, 1) + " to " + Rounded(whole.y1_m, 1) + " m: click to go there";
  }
  const double at = source_.position_s();
  if (at < 0) return "";
  return ClockText(at) + "  " + Rounded(source_.model().distance_m(), 1) + " m";
}

std::string StationController::TimelineRight() const {
  if (source_.review()) {
    const FieldWindow& view = scene_.map().view();
    return "view " + Rounded(view.y0_m, 1) + " to " + Rounded(view.y1_m, 1) + " m";
  }
  const double end = source_.duration_s();
  return end < 0 ? "" : "log " + ClockText(end);
}

void StationController::Measure(const Eigen::Vector2d& at) {
  if (measure_.size() != 1) {
    measure_ = {at};
    tool_text_ = "measure: click the second point";
    return;
  }
  measure_.push_back(at);
  const Eigen::Vector2d d = measure_[1] - measure_[0];
  tool_text_ = "distance " + Rounded(d.norm(), 2) + " m (along " + Rounded(std::abs(d.y()), 2) + ", across " +
               Rounded(std::abs(d.x()), 2) + ")";
}

std::optional<Eigen::Vector2d> StationController::PickPosition() const {
  if (!pick_) return std::nullopt;
  const auto it = source_.model().plants().find(*pick_);
  if (it == source_.model().plants().end()) return std::nullopt;
  return it->second.plant.position_m;
}

// The nearest plant within 0.15 m of the click (or 15 pixels, zoomed out).
void StationController::Pick(const Eigen::Vector2d& at) {
  const double limit = std::max(0.15, 15.0 * scene_.map().metres_per_pixel());
  const review::PlantRecord* best = nullptr;
  double best_d = limit;
  for (const auto& [id, r] : source_.model().plants()) {
    const double d = (r.plant.position_m - at).norm();
    if (d < best_d) best_d = d, best = &r;
  }
  pick_.reset();
  if (best == nullptr) {
    tool_text_ = "no plant within " + Rounded(limit, 2) + " m of the click";
    return;
  }
  pick_ = best->plant.id;
  tool_text_ = PlantRecordText(*best);
}

}  // namespace plantscale::ui
