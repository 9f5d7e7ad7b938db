#include "app/rows_commands.h"

#include "app/config/learned_model.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "app/config/config_loader.h"
#include "app/config/learned_model.h"
#include "app/config/photo_segmentation.h"
#include "app/segment_commands.h"
#include "evaluation/rows_eval.h"
#include "evaluation/rows_writer.h"
#include "evaluation/writer.h"
#include "maps/staged_output.h"

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

// Image rows (indices) the rows are reported on: from the bottom up to the
// highest one the detector still tells them apart on.
int TopRowIndex(const rows::RowDetection& det) {
  return std::clamp(static_cast<int>(std::ceil(det.top_v_px - 0.5)), 0, det.height_px - 1);
}

void WriteCsv(const fs::path& path, const rows::RowDetection& det) {
  maps::WriteStaged(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp);
    out << "row,v,u\n";
    out << std::fixed << std::setprecision(2);
    if (!det.rows.empty()) {
      for (int v = det.height_px - 1; v >= TopRowIndex(det); --v) {
        for (size_t i = 0; i < det.rows.size(); ++i) {
          out << i << ',' << v << ',' << det.U(det.rows[i].n, v + 0.5) << '\n';
        }
      }
    }
    if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
  });
}

nlohmann::json DetectionJson(const fs::path& file, const rows::RowDetection& det) {
  nlohmann::json j;
  j["image"] = file.filename().string();
  j["width"] = det.width_px;
  j["height"] = det.height_px;
  j["confidence"] = det.confidence;
  const bool found = det.confidence > 0.0;
  nlohmann::json rows = nlohmann::json::array();
  for (size_t i = 0; i < det.rows.size(); ++i) {
    rows.push_back({{"row", i}, {"u_bottom", det.rows[i].bottom_u_px},
                    {"occupancy", det.rows[i].occupancy}});
  }
  j["rows"] = rows;
  j["row_count"] = det.rows.size();
  if (found) {
    const auto vp = det.VanishingPoint();
    j["vanishing_point"] = vp ? nlohmann::json{{"u", vp->x()}, {"v", vp->y()}} : nlohmann::json();
    j["spacing_bottom_px"] = det.spacing_px;
    j["central_row_offset_px"] = det.CentralOffsetPx();
    j["top_v"] = det.top_v_px;
  } else {
    j["vanishing_point"] = nullptr;
    j["spacing_bottom_px"] = nullptr;
    j["central_row_offset_px"] = nullptr;
    j["top_v"] = nullptr;
    j["reason"] = det.reason;
  }
  // The rows as curves: c(v) (the central row, row "central_row" in the
  // list) and d(v) at each knot; u_n(v) = c(v) + n·d(v) between them.
  j["model"] = det.curve.empty() ? "straight" : "curved";
  if (found && !det.curve.empty()) {
    nlohmann::json knots = nlohmann::json::array();
    for (const rows::CurveKnot& k : det.curve) {
      knots.push_back({{"v", k.v_px}, {"u_central", k.centre_u_px}, {"spacing", k.spacing_px}});
    }
    j["curve"] = knots;
    for (size_t i = 0; i < det.rows.size(); ++i) {
      if (det.rows[i].n == 0) j["central_row"] = i;
    }
  }
  j["curve_coherence"] = det.curve_coherence;
  j["coherence"] = det.coherence;
  j["alignment"] = det.alignment;
  j["contrast"] = det.contrast;
  j["streak_support"] = det.streak_support;
  return j;
}

cv::Mat Overlay(const cv::Mat& image, const rows::RowDetection& det) {
  cv::Mat out;
  if (image.channels() == 1) cv::cvtColor(image, out, cv::COLOR_GRAY2BGR);
  else out = image.clone();
  const int thickness = std::max(1, out.cols / 320);
  constexpr int kShift = 4;  // sub-pixel drawing
  const auto at = [](double u, double v) {
    return cv::Point(static_cast<int>(std::lround(u * (1 << kShift))),
                     static_cast<int>(std::lround(v * (1 << kShift))));
  };
  const double top = det.top_v_px;
  const double bottom = det.height_px;
  for (size_t i = 0; i < det.rows.size(); ++i) {
    const int n = det.rows[i].n;
    const cv::Scalar colour = n == 0 ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 0, 255);
    const int steps = std::max(16, static_cast<int>((bottom - top) / 4.0));  // the curve, 4 px a step
    for (int k = 0; k < steps; ++k) {
      const double v0 = bottom - (bottom - top) * k / steps;
      const double v1 = bottom - (bottom - top) * (k + 1) / steps;
      cv::line(out, at(det.U(n, v0), v0), at(det.U(n, v1), v1), colour, thickness, cv::LINE_AA,
               kShift);
    }
  }
  if (const auto vp = det.VanishingPoint(); vp && det.confidence > 0.0 && det.curve.empty()) {
    cv::drawMarker(out, cv::Point(static_cast<int>(vp->x()), static_cast<int>(vp->y())),
                   cv::Scalar(0, 255, 255), cv::MARKER_CROSS, 6 * thickness, thickness);
  }
  std::ostringstream text;
  text << std::fixed << std::setprecision(2);
  if (det.confidence > 0.0) text << det.rows.size() << " rows, confidence " << det.confidence;
  else text << "no rows";
  const double scale = 0.4 * thickness;
  cv::putText(out, text.str(), cv::Point(4 * thickness, 14 * thickness), cv::FONT_HERSHEY_SIMPLEX,
              scale, cv::Scalar(0, 0, 0), 3 * thickness, cv::LINE_AA);
  cv::putText(out, text.str(), cv::Point(4 * thickness, 14 * thickness), cv::FONT_HERSHEY_SIMPLEX,
              scale, cv::Scalar(255, 255, 255), thickness, cv::LINE_AA);
  return out;
}

bool DetectOne(const fs::path& file, const fs::path& out, rows::RowDetector& detector,
               vision::LearnedSegmenter* model) {
  const cv::Mat image = ReadImage(file);
  const rows::RowDetection det = DetectRowsInPhoto(image, detector, model);
  const std::string stem = file.stem().string();
  WriteCsv(out / (stem + "_rows.csv"), det);
  const fs::path png = out / (stem + "_rows.png");
  maps::WriteStaged(png, [&](const fs::path& tmp) {
    if (!cv::imwrite(tmp.string(), Overlay(image, det))) {
      throw std::runtime_error("cannot write " + png.string());
    }
  });
  const fs::path json = out / (stem + "_rows.json");
  maps::WriteStaged(json, [&](const fs::path& tmp) {
    std::ofstream o(tmp);
    o << DetectionJson(file, det).dump(2) << '\n';
    if (!o.flush()) throw std::runtime_error("cannot write " + json.string());
  });
  return det.confidence > 0.0;
}

int DetectRowsCommand(const DetectRowsRequest& request) {
  DetectRowsResult r;
  try {
    r = DetectRows(request, std::cerr);
  } catch (const DataError& e) {  // the model: nothing was detected
    std::cerr << "plantscale detect-rows: error: " << e.what() << '\n';
    return 2;
  }
  for (const std::string& e : r.errors) std::cerr << "plantscale detect-rows: error: " << e << '\n';
  std::cout << "plantscale detect-rows: " << r.images << " image(s) into " << request.out.string()
            << "/, rows found in " << r.with_rows;
  if (r.failed > 0) std::cout << ", " << r.failed << " failed";
  std::cout << '\n';
  // 0 when any image was processed (the failures are reported per file),
  // 2 when none could be.
  return r.images > 0 ? 0 : 2;
}

struct RowsEvalArgs {
  std::string preset = "field";
  int seeds = 2;
  int frames = 10;
  std::optional<int64_t> seed;
  double tilt_deg = 12.0;
  std::string images;
  std::string labels;
  std::string model;
  bool json = false;
};

int EvaluateRowsCommand(const RowsEvalArgs& a, const GlobalOptions& global) {
  if (!a.images.empty()) {
    const fs::path images = a.images;
    const fs::path labels =
        a.labels.empty() ? images.parent_path() / "label" : fs::path(a.labels);
    std::optional<vision::LearnedSegmenter> model;
    if (!a.model.empty()) {
      try {
        model.emplace(LoadSegmenter(ReadLearnedModel(a.model)));
      } catch (const DataError& x) {
        std::cerr << "plantscale evaluate rows: error: " << x.what() << '\n';
        return 2;
      }
    }
    const PhotoRowsEvaluation e = EvaluateRowsOnPhotos(images, labels, model ? &*model : nullptr);
    for (const std::string& err : e.errors) {
      std::cerr << "plantscale evaluate rows: error: " << err << '\n';
    }
    WriteEvaluation(e, a.json, std::cout);
    return e.images > 0 ? 0 : 1;
  }
  RowsEvalOptions o;
  o.sim = LoadSimulatorPreset(a.preset, global.ConfigDir());
  if (a.seed) o.sim.seed = static_cast<uint64_t>(*a.seed);
  o.seeds = a.seeds;
  o.frames = a.frames;
  o.tilt_deg = a.tilt_deg;
  WriteEvaluation(EvaluateRows(o), a.json, std::cout);
  return 0;
}

}  // namespace

DetectRowsResult DetectRows(const DetectRowsRequest& request, std::ostream& log) {
  DetectRowsResult result;
  rows::RowDetector detector{rows::RowDetectorOptions{}};
  std::optional<vision::LearnedSegmenter> model;
  if (!request.model.empty()) model.emplace(LoadSegmenter(ReadLearnedModel(request.model)));
  ForEachImage(request.inputs, request.out, "detect-rows", request.progress, log, result,
               [&](const fs::path& file) {
                 if (DetectOne(file, request.out, detector, model ? &*model : nullptr)) ++result.with_rows;
               });
  return result;
}

void AddRowsCommands(CommandRegistry& registry) {
  const GlobalOptions& global = registry.global();
  DetectRowsRequest& req = registry.Keep(DetectRowsRequest{});
  std::string& out = registry.Keep(std::string{});
  std::vector<std::string>& inputs = registry.Keep(std::vector<std::string>{});
  bool& quiet = registry.Keep(false);
  std::string& model = registry.Keep(std::string{});
  CLI::App* detect = registry.Add(
      "detect-rows", "crop rows in photographs from unknown cameras (PNG/JPEG, any size)", [&] {
        req.inputs.assign(inputs.begin(), inputs.end());
        req.out = out;
        req.progress = !quiet;
        req.model = model;
        return DetectRowsCommand(req);
      });
  detect->add_option("inputs", inputs, "image files or folders of images")->required();
  detect->add_option("--out", out, "output folder (NAME_rows.csv, NAME_rows.png, NAME_rows.json)")
      ->required();
  detect->add_flag("--quiet", quiet, "no progress bar");
  detect->add_option("--model", model,
                     "a learned crop/weed model (MODEL.onnx, MODEL.json beside it): rows in its crop class, "
                     "not in every plant");

  RowsEvalArgs& args = registry.Keep(RowsEvalArgs{});
  CLI::App* cmd = registry.Add(
      "rows", "crop-row detection (CRDA) on perspective simulator views, or labelled photographs",
      [&args, &global] { return EvaluateRowsCommand(args, global); }, EvaluateCommand(registry));
  AddRunOptions(cmd, args.preset, args.seeds, args.seed);
  cmd->add_option("--frames", args.frames, "scored frames per seed")->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--tilt-deg", args.tilt_deg, "camera tilt below the horizontal")
      ->check(CLI::Range(1.0, 89.0))->capture_default_str();
  cmd->add_option("--images", args.images,
                  "score labelled photographs in this folder instead (extra measurement)");
  cmd->add_option("--labels", args.labels, "their label images (default: IMAGES/../label)");
  cmd->add_option("--model", args.model, "with --images: rows in this learned model's crop class");
  cmd->add_flag("--json", args.json, "print one JSON object");
}

}  // namespace plantscale::app
