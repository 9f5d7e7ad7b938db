#pragma once
// The operator station: one window composing the scene pieces (HUD strip,
// map with overlays, nozzle bar, camera view, offset trace, timeline), fed
// live from LCM or from a log with a timeline to scrub, pause and speed up.
//
// The keys are listed by StationKeysHelp() (shown on `h` or `?` and by
// `plantscale station --help`). A left click on the map shows the nearest
// plant's record, ringed (or, with the measure tool, the ground distance
// between two clicks, drawn); a click on the timeline seeks there; the
// mouse wheel zooms about the pointer and a right or middle drag pans.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <vtkImageActor.h>

#include "engine/common/options.h"
#include "telemetry/gateway/client.h"
#include "ui/camera_view.h"
#include "ui/canvas.h"
#include "ui/hud.h"
#include "ui/map_annotations.h"
#include "ui/map_view.h"
#include "ui/offset_trace.h"

namespace plantscale::ui {

struct StationOptions {
  std::string lcm_url;         // live (empty: LCM's default)
  std::filesystem::path log;   // non-empty: replay this log with a timeline
  // Set: review this finished run, whole (no replay): a log's (review::LoadReviewRun
  // in review/log_timeline.h) or an exported map's plants (app/), named
  // review_name; review_error says what could not be read.
  std::shared_ptr<const review::RunModel> review_model;
  std::string review_name, review_error;
  int width_px = 1280, height_px = 720;
  double ellipse_confidence = 0.95;
  double ellipse_magnification = 20.0;  // covariance ellipses drawn this many times their size
  double speed = 1.0;          // log replay speed
  double max_seconds = 0.0;    // > 0: close after this long (demo, tests)
  double close_when_quiet_s = 0.0;  // > 0: close this long after the last message (demo)
  bool offscreen = false;      // no window: render into the back buffer only
  std::filesystem::path screenshot;  // non-empty: the last frame as PNG on closing
  std::filesystem::path command_key;  // live: sign vehicle commands with this key file
  // Set: live over the gateway (`station --connect`) instead of LCM.
  std::optional<telemetry::gateway::GatewayClientOptions> gateway;
  double gateway_wait_s = 5.0;  // for the first connection before the window opens
  // Keys pressed this many seconds after the start, in order (a scripted
  // session: --press KEY@SECONDS; VTK key symbols, e.g. C, space, Up).
  std::vector<std::pair<double, std::string>> press;
  // > 0: after the first frame, draw this many frames touring the bed (see
  // StationController::TourStep) as fast as it can, and time each.
  int tour_frames = 0;
  CameraViewParams camera;

  OptionErrors Validate() const;
};

// The bed from `whole.y0_m` to `y1_m` in `columns` columns, each coloured
// from soil brown (no weed) to weed red (the most weeds per metre of any
// column, or more), grey where no plant was seen: where the weed pressure is,
// readable at any length.
std::vector<Rgb> WeedStrip(const review::RunModel& model, const FieldWindow& whole, int columns);

// Every key of the station and what it does, one per line (for `h` and --help).
std::string StationKeysHelp();

// The composed scene, usable without the event loop (the report bench and
// tests render it directly).
class StationScene {
 public:
  StationScene(Canvas& canvas, const StationOptions& options);
  void Update(const review::RunModel& model, int64_t now_utime, double timeline_fraction);
  // Words at the timeline's two ends (position, and the whole run).
  void SetTimelineText(const std::string& left, const std::string& right);
  // Review: the bottom bar is the whole bed, coloured by `columns` (from its
  // start to its end), with the part in view [from, to] (fractions) marked.
  void SetOverview(const std::vector<Rgb>& columns, double from, double to);
  MapView& map() { return map_; }
  MapAnnotations& annotations() { return annotations_; }
  Hud& hud() { return hud_; }
  vtkRenderer* map_renderer() { return map_renderer_; }
  vtkRenderer* timeline_renderer() { return timeline_renderer_; }

 private:
  MapView map_;
  MapAnnotations annotations_;
  Hud hud_;
  NozzleBarView nozzles_;
  CameraView camera_;
  OffsetTrace trace_;
  LineLayer timeline_;
  vtkNew<vtkTextActor> timeline_left_, timeline_right_;
  vtkNew<vtkImageActor> overview_;
  LineLayer view_span_;
  size_t overview_columns_ = 0;
  std::pair<double, double> view_span_at_{-1.0, -1.0};
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
  std::vector<std::string> link_changes;    // over the gateway: "UNIX_SECONDS TEXT" per change
  std::vector<std::string> command_replies;  // what each command key did
  // What the run model holds when it closed.
  int64_t messages = 0;
  size_t grid_states = 0;  // the offset trace's samples
  size_t map_tiles = 0;
  int tile_revisions = 0;
  size_t plants = 0;
  std::vector<std::string> events;  // every event received, "KIND: TEXT"
  // Live: per grid message, its reception minus its stamp (RunModel::grid_lag_ms).
  std::vector<float> grid_lag_ms;
  int64_t thumbnails = 0;  // thumbnail messages received
  int64_t link_bytes = -1;  // over the gateway: LCM message bytes received (-1: not over it)
  // With tour_frames: the time of each toured frame (update and render), ms.
  std::vector<double> tour_frame_ms;
  double tour_cpu_ms = 0.0;  // process CPU time (all threads, llvmpipe's too) over the tour
};

// Runs until the window closes, max_seconds pass or, with close_when_quiet_s,
// messages have stopped for that long. Throws DisplayError
// without an X display, InvalidOptionsError, telemetry::LogError,
// telemetry::TransportError, telemetry::CommandAuthError (the key file,
// read before anything else is opened) or
// telemetry::gateway::GatewayClientError (--connect: the token refused, the
// certificate not trusted, the CA file).
StationResult RunStation(const StationOptions& options);

}  // namespace plantscale::ui
