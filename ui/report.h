#pragma once
// `plantscale report`: replays an LCM log through the subscriber into a run
// model once, then writes DIR/index.html with the run summary and the
// agronomic summary (review/agronomy.h, per run and per row; also
// DIR/summary.csv and DIR/summary.json) and the pictures of
// ui/report_pictures.h: the overview heat maps, the bed as 10 m strips, the
// ellipse close-ups (at warning/error events and at the largest offset
// error, a bounded number however long the run), the offset trace, the
// plant-size histograms, and the camera view at warning/error events (VTK:
// drawn only with an X display, else the page says so). The cost is linear
// in the log's length. Nothing in the output depends on the wall clock, so
// the same log gives the same bytes.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "engine/common/options.h"
#include "review/agronomy.h"
#include "review/run_model.h"
#include "ui/camera_view.h"
#include "ui/report_pictures.h"

namespace plantscale::ui {

struct ReportOptions {
  PictureOptions pictures;
  review::AgronomyOptions agronomy;
  int max_event_closeups = 6;  // close-ups at warning/error events
  double settle_m = 2.0;       // the largest offset error is looked for past this distance
  int camera_width_px = 320, camera_height_px = 240;
  CameraViewParams camera;
  // Simulator truth over the stand, given the text of the log's run_config
  // event (the app rebuilds the field); may return nothing or throw.
  std::function<std::optional<review::AgronomyTruth>(const std::string& run_config, const review::StandWindow& stand)> truth;

  OptionErrors Validate() const;
};

struct ReportResult {
  review::RunSummary summary;
  review::AgronomySummary agronomy;
  std::optional<review::AgronomyTruth> truth;
  std::vector<std::string> pictures;  // file names inside the output folder
  std::vector<std::string> problems;  // what was wrong with the log
  std::filesystem::path index;
};

// Throws InvalidOptionsError, telemetry::LogError (cannot open the log) or
// std::runtime_error (cannot write DIR). A log that is empty, cut off or of
// another program gives a report of what could be read, the problem stated.
ReportResult WriteReport(const std::filesystem::path& log, const std::filesystem::path& out_dir,
                         const ReportOptions& options = {});

}  // namespace plantscale::ui
