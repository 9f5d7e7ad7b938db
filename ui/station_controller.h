#pragma once
// Keys, clicks, the mouse wheel and drags, and the per-frame update of a
// running station (the keys are listed by StationKeysHelp()). Separate from
// the event loop so tests can drive it.

#include <Eigen/Core>
#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "ui/station.h"
#include "ui/station_sources.h"

namespace plantscale::ui {

// plantscale_plant_t::WHY_* in words.
std::string WhyName(int why);
// `value` with `decimals` decimals.
std::string Rounded(double value, int decimals);
// "12.3 s" under two minutes, else "m:ss" or "h:mm:ss".
std::string ClockText(double seconds);
// A plant's record in words: what it is, how big (cm², 2 significant
// figures), how far from the predicted crop (whole mm), where, sprayed and why.
std::string PlantRecordText(const review::PlantRecord& record);

class StationController {
 public:
  StationController(Canvas& canvas, StationScene& scene, Source& source, const StationOptions& o)
      : canvas_(canvas), scene_(scene), source_(source), options_(o) {}

  // Updates the scene and renders when something visible changed: a new
  // message, the HUD text (heartbeat age, clock), a key, a click or a drag.
  // An idle station then costs nothing between messages (copying the window
  // to the screen alone is ~5 ms of CPU at 1280×720 under Xvfb).
  bool Frame(double wall_s);
  // Presses the keys of options.press that are due at this time after `start`.
  void PressDue(std::chrono::steady_clock::time_point start);
  // max_seconds reached, messages stopped close_when_quiet_s ago, or a
  // pressed key (--press q) asked to quit.
  bool ShouldClose(std::chrono::steady_clock::time_point start) const;
  // One key (VTK key symbol); true when it asks to quit.
  bool Key(const std::string& key);
  // A left click at display pixel (x, y), VTK's (y up).
  void Click(int x, int y);
  // Mouse wheel: `steps` notches (> 0: closer) about the pointer.
  void Wheel(int x, int y, int steps);
  // A drag (right or middle button) pans: the ground under the pointer follows it.
  void DragStart(int x, int y);
  void DragTo(int x, int y);
  void DragEnd() { drag_.reset(); }

  // Frame `i` of a tour of the bed (a frame-time measurement): 50 frames
  // each at 6 m, 40 m, 300 m and the whole bed, panning a tenth of the view
  // a frame from a new place along the bed each time.
  void TourStep(int i);

  int64_t frames() const { return frames_; }
  // What the last click or measurement said (shown on the HUD's second line).
  const std::string& tool_text() const { return tool_text_; }
  std::optional<int64_t> picked() const { return pick_; }
  // What each command key did (sent, or why not), in order.
  const std::vector<std::string>& command_replies() const { return command_replies_; }

 private:
  std::string Tools() const;
  void NextMagnification();
  void Seek(double value, bool relative);  // and clears the pick and the measurement
  void ClearTools();
  std::string TimelineLeft() const;
  std::string TimelineRight() const;
  void Measure(const Eigen::Vector2d& at);
  void Pick(const Eigen::Vector2d& at);
  std::optional<Eigen::Vector2d> PickPosition() const;
  void ViewKey(const std::string& key);
  void PlayKey(const std::string& key);
  void CommandKey(const std::string& key);
  void GoToMetre(double fraction);  // review: the view moves to that fraction of the bed

  Canvas& canvas_;
  StationScene& scene_;
  Source& source_;
  StationOptions options_;
  bool measuring_ = false;
  bool placed_ = false;  // review: the whole run framed on the first frame
  int confidence_ = 2;
  std::vector<Eigen::Vector2d> measure_;  // the measure tool's clicks (0, 1 or 2)
  std::optional<int64_t> pick_;           // the picked plant's id
  std::optional<Eigen::Vector2d> drag_;   // the pointer where a pan drag last was
  std::string tool_text_;
  std::vector<Rgb> strip_;  // review: the bed's weed strip (WeedStrip), made once
  int64_t frames_ = 0;
  size_t pressed_ = 0;  // keys of options_.press pressed so far
  bool quit_ = false;
  std::vector<std::string> command_replies_;
  bool dirty_ = true;
  int64_t last_messages_ = 0;
  std::chrono::steady_clock::time_point last_message_time_ = std::chrono::steady_clock::now();
  int64_t drawn_messages_ = -1;
  std::string drawn_hud_;
};

}  // namespace plantscale::ui
