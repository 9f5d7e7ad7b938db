#pragma once
// The operator station: one window composing the scene pieces (HUD strip,
// map with overlays, nozzle bar, camera view, offset trace, timeline), fed
// live from LCM or from a log with a timeline to scrub, pause and speed up.
//
// Keys: m map, p plants, g grid, l ellipses, v vehicle, f follow/free camera,
// c ellipse confidence (50/90/95/99 %), space pause, + / − speed, ← / → seek
// 5 s, Home restart, r measure tool, q or Esc quit; to the vehicle (live):
// S start, P pause, C spray the crop, W spray the weeds, O spraying off. A left click on the map
// shows the nearest plant's record (or, with the measure tool, the ground
// distance between two clicks); a click on the timeline seeks there.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "engine/common/options.h"
#include "ui/camera_view.h"
#include "ui/canvas.h"
#include "ui/hud.h"
#include "ui/map_view.h"
#include "ui/offset_trace.h"

namespace plantscale::ui {

struct StationOptions {
  std::string lcm_url;         // live (empty: LCM's default)
  std::filesystem::path log;   // non-empty: replay this log with a timeline
  int width_px = 1280, height_px = 720;
  double ellipse_confidence = 0.95;
  double speed = 1.0;          // log replay speed
  double max_seconds = 0.0;    // > 0: close after this long (demo, tests)
  double close_when_quiet_s = 0.0;  // > 0: close this long after the last message (demo)
  bool offscreen = false;      // no window: render into the back buffer only
  std::filesystem::path screenshot;  // non-empty: the last frame as PNG on closing
  std::filesystem::path command_key;  // live: sign vehicle commands with this key file
  CameraViewParams camera;

  OptionErrors Validate() const;
};

// The composed scene, usable without the event loop (the report bench and
// tests render it directly).
class StationScene {
 public:
  StationScene(Canvas& canvas, const StationOptions& options);
  void Update(const RunModel& model, int64_t now_utime, double timeline_fraction);
  MapView& map() { return map_; }
  Hud& hud() { return hud_; }
  vtkRenderer* map_renderer() { return map_renderer_; }
  vtkRenderer* timeline_renderer() { return timeline_renderer_; }

 private:
  MapView map_;
  Hud hud_;
  NozzleBarView nozzles_;
  CameraView camera_;
  OffsetTrace trace_;
  LineLayer timeline_;
  double timeline_end_ = -1.0;  // fraction the timeline bar was drawn to
  vtkRenderer* map_renderer_ = nullptr;
  vtkRenderer* timeline_renderer_ = nullptr;
};

struct StationResult {
  int64_t frames = 0;
  double seconds = 0.0;
  double frames_per_second = 0.0;
  std::vector<std::string> problems;  // what was wrong when it closed
  std::string link;                   // the link when it closed (LinkStatus::text)
};

// Runs until the window closes, max_seconds pass or, with close_when_quiet_s,
// messages have stopped for that long. Throws DisplayError
// without an X display, InvalidOptionsError, telemetry::LogError,
// telemetry::TransportError or telemetry::CommandAuthError (the key file,
// read before anything else is opened).
StationResult RunStation(const StationOptions& options);

}  // namespace plantscale::ui
