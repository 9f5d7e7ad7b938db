#pragma once
// The report's pictures that stay readable at any run length (issue 36),
// drawn with OpenCV (no display needed, cost linear in what is drawn):
//  - the overview: crop stand and weed pressure per 1 m × row cell as heat
//    maps, the run folded into lines of fixed length;
//  - the bed as strips of fixed length (10 m), several per picture, from
//    the map tiles and the plant records, with distance labels, a scale bar
//    and a legend (crop green, weed red, treated blue, soil brown);
//  - ellipse close-ups as the run passed there, the covariance ellipses
//    magnified (the factor written on the picture);
//  - the offset trace, one column per pixel (mean, ±2σ band, truth);
//  - the plant-size histograms.

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "review/agronomy.h"
#include "review/run_model.h"

namespace plantscale::ui {

// What a close-up shows, taken while the log is replayed.
struct CloseupSnapshot {
  std::string reason;       // "event: …", "largest offset error 21 mm"
  double distance_m = 0.0;  // driven when taken
  double y_m = 0.0;         // field y at the centre of the window
  std::optional<telemetry::Pose> pose;
  std::optional<telemetry::GridEstimate> grid;
  std::vector<telemetry::PlantObservation> plants;  // in the window, as estimated then
  std::vector<telemetry::MapTileDelta> tiles;       // in the window
};

struct PictureOptions {
  double strip_length_m = 10.0;
  int strips_per_picture = 5;
  int max_strip_pictures = 4;  // a long run shows the strips that matter (events, gaps, weeds)
  int strip_width_px = 1100;
  double closeup_length_m = 2.0;
  double ellipse_magnification = 20.0;
  double ellipse_confidence = 0.95;
  int closeup_width_px = 640;
  int overview_width_px = 1000;
  int max_overview_lines = 25;  // the run folds into at most this many lines
  int trace_width_px = 1100, trace_height_px = 320;
};

// The overview heat maps; the metres per line are chosen from the run length.
cv::Mat DrawOverview(const review::AgronomySummary& a, const PictureOptions& o);
// Strips starting at `strip_starts_m` (field y), one picture.
cv::Mat DrawStrips(const review::RunModel& model, const review::AgronomySummary& a, const std::vector<double>& strip_starts_m,
                   double x_lo_m, double x_hi_m, const PictureOptions& o);
cv::Mat DrawCloseup(const CloseupSnapshot& s, double x_lo_m, double x_hi_m, const PictureOptions& o);
cv::Mat DrawOffsetTrace(const review::RunModel& model, const PictureOptions& o);
cv::Mat DrawSizeHistograms(const review::AgronomySummary& a);

// Takes a snapshot of the model around field y `y_m`.
CloseupSnapshot TakeCloseup(const review::RunModel& model, double y_m, double half_length_m, std::string reason);

}  // namespace plantscale::ui
