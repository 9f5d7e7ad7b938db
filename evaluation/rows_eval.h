#pragma once
// `plantscale evaluate rows`: the crop-row detector of `plantscale
// detect-rows` (photo segmentation, then engine/rows) on simulator frames
// seen in perspective (low tilt, horizon in view), scored with the CRDA
// measure of Vidović, Cupec and Hocenski (Pattern Recognition 2016): per
// image row, s = max(0, 1 − ((u − u_true) / (0.1·d))²) with d the true row
// spacing in pixels, averaged over the central true row and its two
// neighbours. A second mode scores labelled real photographs (line label
// images) the same way, as an extra measurement.

#include <filesystem>
#include <string>
#include <vector>

#include "engine/rows/row_detector.h"
#include "engine/sim/simulator.h"
#include "engine/vision/learned_segmenter.h"

namespace plantscale::app {

// What `plantscale detect-rows` does with one photograph (8-bit grey or
// BGR): the plant mask of `plantscale segment --method auto`, or with a
// learned model its crop class (weeds between the rows no longer pull
// them), then the row detector.
rows::RowDetection DetectRowsInPhoto(const cv::Mat& image, rows::RowDetector& detector,
                                     vision::LearnedSegmenter* model = nullptr);

struct RowsEvalOptions {
  sim::SimulatorOptions sim;
  int seeds = 2;                 // sim.seed, sim.seed + 1, ... (ForEachSeed)
  int frames = 10;               // scored frames per seed
  double frame_spacing_m = 2.0;  // driven between scored frames
  double tilt_deg = 12.0;        // camera below the horizontal: horizon in view
  double min_true_spacing_px = 10.0;  // image rows where the true rows are closer are not scored
  double max_range_fraction = 0.8;    // ... nor beyond this fraction of the render range

  OptionErrors Validate() const;
};

// The scored view: the preset's camera and field, tilted up to `tilt_deg`.
sim::SimulatorOptions PerspectiveView(const RowsEvalOptions& options);

// One evaluation on the simulator: its figures and what it was run with
// (its JSON and table, rows_writer.h, need nothing else).
struct RowsEvaluation {
  std::string preset;
  int seeds = 0;
  double tilt_deg = 0.0;  // RowsEvalOptions'

  int frames = 0;
  int frames_with_rows = 0;
  int image_rows_scored = 0;
  double crda_mean = 0.0;
  double crda_frame_p10 = 0.0;     // 10th percentile of the per-frame mean
  double spacing_error_rel = 0.0;  // mean |d − d_true| / d_true at the bottom row
  std::vector<double> crda_per_seed;
};

RowsEvaluation EvaluateRows(const RowsEvalOptions& options);

// Labelled photographs: IMAGES/NAME.ext with LABELS/NAME.* (white lines along
// the row centres, any scale).
struct PhotoRowScore {
  std::string image;  // file name
  double crda = 0.0;  // mean over its scored image rows
  int image_rows_scored = 0;
  bool rows_found = false;
};
struct PhotoRowsEvaluation {
  bool model = false;  // the rows were found in a learned model's crop class, else excess green
  int images = 0;
  int image_rows_scored = 0;
  double crda_mean = 0.0;
  int images_with_rows = 0;
  std::vector<PhotoRowScore> per_image;  // in file order
  std::vector<std::string> errors;
};
PhotoRowsEvaluation EvaluateRowsOnPhotos(const std::filesystem::path& images,
                                         const std::filesystem::path& labels,
                                         vision::LearnedSegmenter* model = nullptr);

// CRDA of one image row: detected u of the three true rows against the true
// u (left, central, right), with the true spacing d; a missing detection
// scores 0.
double CrdaScore(double u, double u_true, double d);

}  // namespace plantscale::app
