#include "evaluation/rows_eval.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "app/config/photo_segmentation.h"
#include "engine/common/stats.h"
#include "engine/rows/label_lines.h"
#include "engine/vision/segmenter.h"
#include "evaluation/seeds.h"

namespace plantscale::app {
namespace fs = std::filesystem;

rows::RowDetection DetectRowsInPhoto(const cv::Mat& image, rows::RowDetector& detector,
                                     vision::LearnedSegmenter* model) {
  if (model != nullptr) {
    const cv::Mat crop = model->Classify(image).classes == static_cast<int>(vision::PixelClass::kCrop);
    return detector.Detect(crop);
  }
  return detector.Detect(PlantMaskOfPhoto(image));
}

OptionErrors RowsEvalOptions::Validate() const {
  OptionErrors e = sim.Validate();
  if (seeds < 1) e.push_back({"seeds", "must be >= 1"});
  if (frames < 1) e.push_back({"frames", "must be >= 1"});
  RequirePositive(e, "frame_spacing_m", frame_spacing_m);
  RequireInRange(e, "tilt_deg", tilt_deg, 0.0, 90.0, false);
  RequirePositive(e, "min_true_spacing_px", min_true_spacing_px);
  RequireInRange(e, "max_range_fraction", max_range_fraction, 0.0, 1.0, false);
  return e;
}

sim::SimulatorOptions PerspectiveView(const RowsEvalOptions& options) {
  sim::SimulatorOptions s = options.sim;
  s.camera.tilt_rad = options.tilt_deg * std::numbers::pi / 180.0;
  return s;
}

double CrdaScore(double u, double u_true, double d) {
  const double e = (u - u_true) / (0.1 * d);
  return std::max(0.0, 1.0 - e * e);
}

namespace {

// True u of rows −1, 0, 1 of the bed per image row (NaN where not scored).
struct TrueRows {
  std::vector<std::array<double, 3>> u;  // per image row index
};

// The camera of this frame, as the simulator rendered it (with the bump).
geometry::CameraModel FrameCamera(const sim::SimulatorOptions& s, const sim::CameraBounce& b) {
  geometry::CameraOptions o = s.camera;
  o.tilt_rad = std::min(o.tilt_rad + b.pitch_rad, std::numbers::pi / 2.0);
  o.roll_rad += b.roll_rad;
  o.height_m += b.height_m;
  return geometry::CameraModel(o);
}

// Row n's line (at height z) projected into the frame, sampled every 2 cm
// ahead of the vehicle, written into column k of `rows` per image row.
void ProjectRowLine(const sim::Simulator& sim, const sim::FrameTruth& truth,
                    const geometry::CameraModel& camera, double z, double max_range, int k,
                    TrueRows& rows) {
  const int H = camera.height();
  std::vector<Eigen::Vector2d> points;  // (u, v), v decreasing with range
  for (double ahead = 0.0; ahead <= max_range; ahead += 0.02) {
    const double y_field = truth.pose.y_m + ahead;  // rows run along field y
    const Eigen::Vector2d g = sim::FieldToVehicle(truth.pose, {sim.field().RowX(k - 1, y_field), y_field});
    if (g.y() <= 0.0 || std::hypot(g.x(), g.y()) > max_range) continue;
    const auto uv = camera.Project({g.x(), g.y(), z});
    if (uv) points.push_back(*uv);
  }
  for (size_t i = 1; i < points.size(); ++i) {
    const Eigen::Vector2d& a = points[i - 1];
    const Eigen::Vector2d& b = points[i];
    if (!(b.y() < a.y())) continue;
    for (int vi = static_cast<int>(std::ceil(b.y() - 0.5)); vi <= static_cast<int>(std::floor(a.y() - 0.5)); ++vi) {
      if (vi < 0 || vi >= H) continue;
      const double v = vi + 0.5;
      rows.u[static_cast<size_t>(vi)][static_cast<size_t>(k)] = a.x() + (v - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
    }
  }
}

// A human labels the centre of the plants as seen, not a line on the soil:
// where the frame shows enough of row k's crop plants, its true line is the
// least-squares line u = a + b·v through their visible centroids.
void FitVisibleCentroids(const sim::FrameTruth& truth, const geometry::CameraModel& camera, int k,
                         TrueRows& rows) {
  const int H = camera.height();
  Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  int count = 0;
  for (const sim::PlantTruth& p : truth.plants) {
    if (p.cls != sim::PlantClass::kCrop || p.row != k - 1 || p.area_px < 30) continue;
    const Eigen::Vector2d& c = p.centroid_px;
    if (c.x() < 10.0 || c.x() > camera.width() - 10.0 || c.y() > H - 10.0) continue;
    const Eigen::Vector2d row(1.0, c.y());
    a += row * row.transpose();
    b += c.x() * row;
    ++count;
  }
  if (count < 4 || std::abs(a.determinant()) < 1e-6) return;
  const Eigen::Vector2d line = a.ldlt().solve(b);
  for (int vi = 0; vi < H; ++vi) {
    double& u = rows.u[static_cast<size_t>(vi)][static_cast<size_t>(k)];
    if (!std::isnan(u)) u = line(0) + line(1) * (vi + 0.5);
  }
}

// The bed's central three row lines (at half the crop's rim height, where
// the plant matter is seen) projected into the frame.
TrueRows TrueRowsInFrame(const sim::Simulator& sim, const sim::FrameTruth& truth,
                         const RowsEvalOptions& o) {
  const sim::SimulatorOptions& s = sim.options();
  const geometry::CameraModel camera = FrameCamera(s, truth.bounce);
  const double z = 0.5 * s.field.crop_height_ratio * s.field.crop_radius_m;
  const double max_range = o.max_range_fraction * s.render.max_range_m;
  TrueRows rows;
  rows.u.assign(static_cast<size_t>(camera.height()), {std::nan(""), std::nan(""), std::nan("")});
  for (int k = 0; k < 3; ++k) ProjectRowLine(sim, truth, camera, z, max_range, k, rows);
  for (int k = 0; k < 3; ++k) FitVisibleCentroids(truth, camera, k, rows);
  return rows;
}

struct FrameScore {
  double sum = 0.0;
  int rows = 0;
  double spacing_error_rel = std::nan("");
};

// Detected rows matched to the true rows by the central one: the detected
// row nearest the true central row at the lowest scored image row.
FrameScore ScoreFrame(const rows::RowDetection& det, const TrueRows& truth,
                      const RowsEvalOptions& o) {
  FrameScore score;
  int bottom = -1;
  for (int vi = static_cast<int>(truth.u.size()) - 1; vi >= 0; --vi) {
    const auto& t = truth.u[static_cast<size_t>(vi)];
    if (std::isnan(t[0]) || std::isnan(t[1]) || std::isnan(t[2])) continue;
    if (0.5 * (t[2] - t[0]) >= o.min_true_spacing_px) {
      bottom = vi;
      break;
    }
  }
  if (bottom < 0) return score;
  std::optional<int> central;
  if (!det.rows.empty()) {
    const double v = bottom + 0.5;
    const double u_true = truth.u[static_cast<size_t>(bottom)][1];
    for (const rows::DetectedRow& r : det.rows) {
      if (!central || std::abs(det.U(r.n, v) - u_true) < std::abs(det.U(*central, v) - u_true)) {
        central = r.n;
      }
    }
    const auto& t = truth.u[static_cast<size_t>(bottom)];
    score.spacing_error_rel = std::abs(det.SpacingAt(v) - 0.5 * (t[2] - t[0])) / (0.5 * (t[2] - t[0]));
  }
  const auto has = [&](int n) {
    return std::any_of(det.rows.begin(), det.rows.end(),
                       [n](const rows::DetectedRow& r) { return r.n == n; });
  };
  for (int vi = bottom; vi >= 0; --vi) {
    const auto& t = truth.u[static_cast<size_t>(vi)];
    if (std::isnan(t[0]) || std::isnan(t[1]) || std::isnan(t[2])) continue;
    const double d = 0.5 * (t[2] - t[0]);
    if (d < o.min_true_spacing_px) continue;
    const double v = vi + 0.5;
    double s = 0.0;
    for (int k = 0; k < 3; ++k) {
      if (!central || v < det.top_v_px || !has(*central + k - 1)) continue;
      s += CrdaScore(det.U(*central + k - 1, v), t[static_cast<size_t>(k)], d);
    }
    score.sum += s / 3.0;
    ++score.rows;
  }
  return score;
}

}  // namespace

RowsEvaluation EvaluateRows(const RowsEvalOptions& options) {
  ThrowIfInvalid("evaluate rows", options.Validate());
  RowsEvaluation e;
  e.preset = options.sim.preset;
  e.seeds = options.seeds;
  e.tilt_deg = options.tilt_deg;
  rows::RowDetector detector{rows::RowDetectorOptions{}};
  std::vector<double> frame_means;
  double spacing_sum = 0.0;
  int spacing_n = 0;
  double total = 0.0;
  ForEachSeed(PerspectiveView(options), options.seeds, [&](int, const sim::SimulatorOptions& s) {
    sim::Simulator sim(s);
    sim::SimFrame frame;
    // Every `stride`-th frame is rendered and scored: frames this far apart
    // show mostly different plants.
    const double step_m = s.vehicle.speed_m_s / s.vehicle.frame_rate_hz;
    const int stride = std::max(1, static_cast<int>(std::lround(options.frame_spacing_m / step_m)));
    int scored = 0;
    double seed_sum = 0.0;
    int seed_rows = 0;
    for (int index = 0; scored < options.frames; ++index) {
      const bool render = index % stride == stride - 1;
      if (!sim.Next(frame, render)) break;
      if (!render) continue;
      const rows::RowDetection det = DetectRowsInPhoto(frame.rendered.image, detector);
      const FrameScore f = ScoreFrame(det, TrueRowsInFrame(sim, frame.truth, options), options);
      if (f.rows == 0) continue;
      ++scored;
      if (det.confidence > 0.0) ++e.frames_with_rows;
      if (!std::isnan(f.spacing_error_rel)) {
        spacing_sum += f.spacing_error_rel;
        ++spacing_n;
      }
      frame_means.push_back(f.sum / f.rows);
      seed_sum += f.sum;
      seed_rows += f.rows;
    }
    e.frames += scored;
    e.image_rows_scored += seed_rows;
    total += seed_sum;
    e.crda_per_seed.push_back(seed_rows > 0 ? seed_sum / seed_rows : 0.0);
  });
  e.crda_mean = e.image_rows_scored > 0 ? total / e.image_rows_scored : 0.0;
  e.crda_frame_p10 = Percentile(frame_means, 0.1);
  e.spacing_error_rel = spacing_n > 0 ? spacing_sum / spacing_n : std::nan("");
  return e;
}

namespace {

// The label image of a photograph: the same stem in `labels`, PNG or JPEG.
fs::path LabelFor(const fs::path& file, const fs::path& labels) {
  fs::path label_file;
  for (const char* ext : {".png", ".jpg", ".jpeg", ".PNG", ".JPG"}) {
    const fs::path candidate = labels / (file.stem().string() + ext);
    if (fs::exists(candidate)) label_file = candidate;
  }
  return label_file;
}

// CRDA of one labelled image row: the three label lines nearest the
// image's centre column (`centres` in image pixels, left to right), each
// against the detected row nearest it at height v; −1 when the row is not
// scored (fewer than three lines, or closer than 10 px).
double ScoreLabelRow(const rows::RowDetection& det, const std::vector<double>& centres, double v,
                     int width) {
  if (centres.size() < 3) return -1.0;
  size_t c = 1;
  for (size_t i = 1; i + 1 < centres.size(); ++i) {
    if (std::abs(centres[i] - 0.5 * width) < std::abs(centres[c] - 0.5 * width)) c = i;
  }
  const double d = 0.5 * (centres[c + 1] - centres[c - 1]);
  if (d < 10.0) return -1.0;
  double sum = 0.0;
  for (size_t k = c - 1; k <= c + 1; ++k) {
    if (det.rows.empty() || v < det.top_v_px) continue;
    double best = 1e18;
    for (const rows::DetectedRow& r : det.rows) {
      const double u = det.U(r.n, v);
      if (std::abs(u - centres[k]) < std::abs(best - centres[k])) best = u;
    }
    sum += CrdaScore(best, centres[k], d);
  }
  return sum / 3.0;
}

// One photograph against its label image: the sum over its scored label
// rows in `score.crda` (the caller divides), their count.
PhotoRowScore ScorePhoto(const cv::Mat& image, const cv::Mat& label, const rows::RowDetection& det,
                         const std::string& name) {
  PhotoRowScore score{name, 0.0, 0, det.confidence > 0.0};
  const double sx = static_cast<double>(image.cols) / label.cols;
  const double sy = static_cast<double>(image.rows) / label.rows;
  for (int y = 0; y < label.rows; ++y) {
    // Label lines crossing this label row: centres of the white runs.
    const std::vector<double> centres = rows::LabelLineCentres(label.ptr<uint8_t>(y), label.cols, sx);
    const double s = ScoreLabelRow(det, centres, (y + 0.5) * sy, image.cols);
    if (s < 0.0) continue;
    score.crda += s;
    ++score.image_rows_scored;
  }
  return score;
}

}  // namespace

PhotoRowsEvaluation EvaluateRowsOnPhotos(const fs::path& images, const fs::path& labels,
                                         vision::LearnedSegmenter* model) {
  PhotoRowsEvaluation e;
  e.model = model != nullptr;
  rows::RowDetector detector{rows::RowDetectorOptions{}};
  const std::vector<fs::path> files = CollectImages({images}, e.errors);
  double total = 0.0;
  for (const fs::path& file : files) {
    const fs::path label_file = LabelFor(file, labels);
    if (label_file.empty()) {
      e.errors.push_back(file.string() + ": no label image in " + labels.string());
      continue;
    }
    try {
      const cv::Mat image = ReadImage(file);
      cv::Mat label = ReadImage(label_file);
      if (label.channels() == 3) cv::cvtColor(label, label, cv::COLOR_BGR2GRAY);
      const rows::RowDetection det = DetectRowsInPhoto(image, detector, model);
      ++e.images;
      if (det.confidence > 0.0) ++e.images_with_rows;
      PhotoRowScore score = ScorePhoto(image, label, det, file.filename().string());
      total += score.crda;
      e.image_rows_scored += score.image_rows_scored;
      if (score.image_rows_scored > 0) score.crda /= score.image_rows_scored;
      e.per_image.push_back(score);
    } catch (const std::exception& ex) {
      e.errors.push_back(file.string() + ": " + ex.what());
    }
  }
  e.crda_mean = e.image_rows_scored > 0 ? total / e.image_rows_scored : 0.0;
  return e;
}

}  // namespace plantscale::app
