#pragma once
// `plantscale evaluate segmentation`: runs a simulator preset, segments
// non-overlapping frames and scores every method against the label images
// (thesis §2.3.2–2.3.6): ROC curve, AUC, and pixel rates at each method's
// operating point. Border ("doubt") pixels are excluded and only the
// trapezoid between the wheels counts, as in the thesis's hand labels.

#include <string>
#include <vector>

#include "engine/sim/simulator.h"
#include "engine/vision/segmenter.h"
#include "evaluation/roc.h"

namespace plantscale::app {

// Pixels whose ground point (z = 0, nominal camera) lies between the wheels:
// the region the thesis labelled and treated (§2.3.3, fig. 2.8).
cv::Mat WheelTrapezoid(const geometry::CameraModel& camera, double track_width_m);

struct SegmentationEvalOptions {
  sim::SimulatorOptions sim;
  int seeds = 3;              // seeds sim.seed, sim.seed + 1, ... (ForEachSeed)
  int frames_per_seed = 10;   // non-overlapping frames per seed
  int doubt_band_px = 1;      // label border excluded on each side
  double costs_ratio = 3.644; // Φ of eq. 2.23 (the thesis's, set on sequence C)
  vision::SegmenterOptions segmenter;  // the product's method and operating point
  // When set, each scored frame's errors are written there as
  // seed<k>_frame<i>_errors.png: the image in grey, plant pixels missed in
  // red (0, 0, 255 BGR), soil taken for plant in blue (255, 64, 0), plant
  // found in green (g/3, 255, g/3 of its grey g); valid pixels only.
  std::string errors_dir;
  // The engine's profiles, as the JSON names them: the segmenter uses none
  // of their settings (the command reads and checks them as every evaluate).
  std::string crop, vehicle;
  // The table also quotes the thesis's published figures (tables 2.1, 2.2).
  bool published_thesis = false;

  OptionErrors Validate() const;
};

struct PixelRates {
  double recall = 0.0;           // TPR: plant pixels found
  double precision = 0.0;        // TP / (TP + FP)
  double soil_accuracy = 0.0;    // 1 − FPR
  double fpr = 0.0;
};

struct MethodEvaluation {
  std::string method;          // "fixed", "adaptive", ...
  std::string parameter_name;  // "tau" or "alpha"
  vision::RocCurve curve;
  double auc = 0.0;
  double parameter = 0.0;      // at the operating point
  PixelRates rates;            // at the operating point
};

// One evaluation: its figures and what it was run with (its JSON and table,
// segmentation_writer.h, need nothing else).
struct SegmentationEvaluation {
  std::string preset;
  std::string crop, vehicle;     // SegmentationEvalOptions'
  bool published_thesis = false;  // SegmentationEvalOptions'

  std::string image_kind;  // "nir" or "rgb"
  std::string colour_index;  // the index rgb frames were turned into ("exg", ...)
  int seeds = 0, frames = 0;
  double plant_fraction = 0.0;  // P_P over the evaluated pixels
  MethodEvaluation ours;        // the product's segmenter at its own parameters
  // The thesis's baselines: fixed and adaptive thresholds with the operating
  // point set by the costs ratio on this preset's own curve (as table 2.2).
  MethodEvaluation thesis_fixed, thesis_adaptive;
};

SegmentationEvaluation EvaluateSegmentation(const SegmentationEvalOptions& options);

}  // namespace plantscale::app
