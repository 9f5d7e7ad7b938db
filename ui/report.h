#pragma once
// `plantscale report`: replays an LCM log through the subscriber into a run
// model, renders off-screen (the map with overlays, ellipse close-ups along
// the run, the offset trace, camera snapshots at warning/error events) and
// writes DIR/index.html with a summary table and the pictures. Nothing in
// the output depends on the wall clock, so the same log gives the same bytes.

#include <filesystem>
#include <string>
#include <vector>

#include "engine/common/options.h"
#include "ui/camera_view.h"
#include "ui/run_model.h"

namespace plantscale::ui {

struct ReportOptions {
  double closeup_every_m = 10.0;  // an ellipse close-up each time the run passes a multiple
  double closeup_length_m = 3.0;  // field length of a close-up
  double ellipse_confidence = 0.95;
  int map_width_px = 1200, map_height_px = 240;
  int closeup_width_px = 400, closeup_height_px = 300;
  int trace_width_px = 900, trace_height_px = 320;
  int camera_width_px = 320, camera_height_px = 240;
  CameraViewParams camera;

  OptionErrors Validate() const;
};

struct ReportResult {
  RunSummary summary;
  std::vector<std::string> pictures;  // file names inside the output folder
  std::vector<std::string> problems;  // what was wrong with the log
  std::filesystem::path index;
};

// Throws InvalidOptionsError, telemetry::LogError (cannot open the log),
// DisplayError (no X display) or std::runtime_error (cannot write DIR).
ReportResult WriteReport(const std::filesystem::path& log, const std::filesystem::path& out_dir,
                         const ReportOptions& options = {});

}  // namespace plantscale::ui
