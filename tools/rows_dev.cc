// rows_dev: the detector of `plantscale detect-rows` (photo segmentation,
// then engine/rows) on a folder of photographs, without the rest of the
// program: NAME_rows.csv (row,v,u) and NAME_rows.json (width, height,
// confidence) as detect-rows writes them, for crda_score, plus
// NAME_rows.png overlays with --overlays. A development aid for tuning
// (quick to build); the figures in docs/results come from detect-rows.
// usage: rows_dev IMAGES OUT [--overlays [--labels DIR]] [--masks] [--straight] [--set key=value]...
// --masks: NAME_mask.png, the plant mask the detector was given.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/config/photo_segmentation.h"
#include "engine/rows/row_detector.h"

namespace fs = std::filesystem;
using namespace plantscale;

namespace {

// Tuning: --set key=value on the detector's options.
void SetOption(rows::RowDetectorOptions& options, const std::string& kv) {
  const auto eq = kv.find('=');
  const std::string key = kv.substr(0, eq);
  const double value = std::stod(kv.substr(eq + 1));
  if (key == "min_row_occupancy") options.min_row_occupancy = value;
  else if (key == "min_gap_row_occupancy") options.min_gap_row_occupancy = value;
  else if (key == "min_alignment") options.min_alignment = value;
  else if (key == "min_streak_alignment") options.min_streak_alignment = value;
  else if (key == "min_streak_support") options.min_streak_support = value;
  else if (key == "min_coherence") options.min_coherence = value;
  else if (key == "min_contrast") options.min_contrast = value;
  else if (key == "max_convergence") options.max_convergence = value;
  else if (key == "convergence_steps") options.convergence_steps = static_cast<int>(value);
  else if (key == "max_lean") options.max_lean = value;
  else if (key == "lean_steps") options.lean_steps = static_cast<int>(value);
  else if (key == "strips") options.strips = static_cast<int>(value);
  else if (key == "work_width_px") options.work_width_px = static_cast<int>(value);
  else if (key == "candidates") options.candidates = static_cast<int>(value);
  else if (key == "max_spacing_fraction") options.max_spacing_fraction = value;
  else if (key == "min_curve_coherence") options.min_curve_coherence = value;
  else if (key == "phase_smoothness") options.curve.phase_smoothness = value;
  else if (key == "scale_smoothness") options.curve.scale_smoothness = value;
  else if (key == "scale_prior") options.curve.scale_prior = value;
  else if (key == "half_comb_weight") options.curve.half_comb_weight = value;
  else if (key == "curve_degree") options.curve.curve_degree = static_cast<int>(value);
  else if (key == "min_curve_gain") options.min_curve_gain = value;
  else if (key == "curve_gain_per_confidence") options.curve_gain_per_confidence = value;
  else if (key == "curve_free_prior") options.curve_free_prior = static_cast<int>(value);
  else if (key == "min_free_spacing_fraction") options.curve.min_free_spacing_fraction = value;
  else if (key == "free_max_scale") options.curve.free_max_scale = value;
  else if (key == "bands") options.curve.bands = static_cast<int>(value);
  else if (key == "max_scale") options.curve.max_scale = value;
  else if (key == "max_phase_jump") options.curve.max_phase_jump = static_cast<int>(value);
  else if (key == "centring") options.centring.enabled = value != 0.0;
  else if (key == "centring_bands") options.centring.bands = static_cast<int>(value);
  else if (key == "window_fraction") options.centring.window_fraction = value;
  else if (key == "centring_iterations") options.centring.iterations = static_cast<int>(value);
  else if (key == "max_shift") options.centring.max_shift = value;
  else if (key == "centring_degree") options.centring.degree = static_cast<int>(value);
  else if (key == "spacing_degree") options.centring.spacing_degree = static_cast<int>(value);
  else if (key == "row_ridge") options.centring.row_ridge = value;
  else if (key == "shared_ridge") options.centring.shared_ridge = value;
  else if (key == "min_band_matter") options.centring.min_band_matter = value;
  else if (key == "min_row_bands") options.centring.min_row_bands = static_cast<int>(value);
  else if (key == "outlier_scale") options.centring.outlier_scale = value;
  else if (key == "robust_iterations") options.centring.robust_iterations = static_cast<int>(value);
  else throw std::runtime_error("unknown key " + key);
}

int TopRow(const rows::RowDetection& det) {
  return std::clamp(static_cast<int>(std::ceil(det.top_v_px - 0.5)), 0, det.height_px - 1);
}

// NAME_rows.csv and NAME_rows.json as detect-rows writes them.
void WriteRows(const rows::RowDetection& det, const std::string& out) {
  std::ofstream csv(out + "_rows.csv");
  csv << "row,v,u\n" << std::fixed << std::setprecision(2);
  const int top = TopRow(det);
  if (!det.rows.empty()) {
    for (int v = det.height_px - 1; v >= top; --v) {
      for (size_t i = 0; i < det.rows.size(); ++i) {
        csv << i << ',' << v << ',' << det.U(det.rows[i].n, v + 0.5) << '\n';
      }
    }
  }
  std::ofstream json(out + "_rows.json");
  json << "{\"width\": " << det.width_px << ", \"height\": " << det.height_px
       << ", \"confidence\": " << det.confidence << ", \"curve_coherence\": " << det.curve_coherence
       << ", \"coherence\": " << det.coherence << ", \"alignment\": " << det.alignment
       << ", \"contrast\": " << det.contrast << ", \"streak_support\": " << det.streak_support
       << ", \"reason\": \"" << det.reason << "\"}\n";
}

// NAME_rows.png: the photograph, its label lines in green, the rows found
// (the central one red).
void WriteOverlay(const cv::Mat& image, const fs::path& label_file, const rows::RowDetection& det,
                  const std::string& out) {
  cv::Mat o = image.clone();
  if (o.channels() == 1) cv::cvtColor(o, o, cv::COLOR_GRAY2BGR);
  if (!label_file.empty()) {
    cv::Mat label = cv::imread(label_file.string(), cv::IMREAD_GRAYSCALE);
    if (!label.empty()) {
      cv::resize(label, label, o.size(), 0, 0, cv::INTER_NEAREST);
      o.setTo(cv::Scalar(0, 255, 0), label > 128);
    }
  }
  const int top = TopRow(det);
  for (const rows::DetectedRow& r : det.rows) {
    for (int v = det.height_px - 1; v > top; v -= 4) {
      cv::line(o, cv::Point(static_cast<int>(det.U(r.n, v + 0.5)), v),
               cv::Point(static_cast<int>(det.U(r.n, v - 3.5)), v - 4),
               r.n == 0 ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 0, 255), 2);
    }
  }
  cv::imwrite(out + "_rows.png", o);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: rows_dev IMAGES OUT [--overlays [--labels DIR]] [--masks] [--straight] [--set key=value]...\n";
    return 2;
  }
  bool overlays = false, masks = false;
  fs::path labels;
  rows::RowDetectorOptions options;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--overlays") overlays = true;
    if (a == "--masks") masks = true;
    if (a == "--straight") options.curves = false;
    if (a == "--labels" && i + 1 < argc) labels = argv[++i];
    if (a == "--set" && i + 1 < argc) SetOption(options, argv[++i]);
  }
  fs::create_directories(argv[2]);
  std::vector<std::string> errors;
  const std::vector<fs::path> files = app::CollectImages({fs::path(argv[1])}, errors);
  rows::RowDetector detector(options);
  double seconds = 0.0;
  int found = 0, n = 0;
  for (const fs::path& file : files) {
    try {
      const cv::Mat image = app::ReadImage(file);
      const auto t0 = std::chrono::steady_clock::now();
      const cv::Mat mask = app::PlantMaskOfPhoto(image);
      const rows::RowDetection det = detector.Detect(mask);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      ++n;
      const std::string out = (fs::path(argv[2]) / file.stem()).string();
      WriteRows(det, out);
      if (det.confidence > 0.0) ++found;
      if (masks) cv::imwrite(out + "_mask.png", mask);
      if (overlays) WriteOverlay(image, labels.empty() ? fs::path() : labels / file.filename(), det, out);
    } catch (const std::exception& e) {
      std::cerr << file << ": " << e.what() << '\n';
    }
  }
  std::cout << n << " images, rows found in " << found << ", " << std::setprecision(3)
            << 1000.0 * seconds / std::max(1, n) << " ms per image (segmentation + detection)\n";
  return n > 0 ? 0 : 2;
}
