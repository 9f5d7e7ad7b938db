#include "evaluation/segmentation_writer.h"

#include <fstream>
#include <iomanip>
#include <stdexcept>

namespace plantscale::app {
namespace {

nlohmann::json MethodJson(const MethodEvaluation& m) {
  nlohmann::json j{{"method", m.method},
                   {"plant_pixel_recall", m.rates.recall},
                   {"plant_pixel_precision", m.rates.precision},
                   {"soil_pixel_accuracy", m.rates.soil_accuracy},
                   {"fpr", m.rates.fpr}};
  if (!m.curve.points.empty()) j["auc"] = m.auc;
  if (!m.parameter_name.empty()) j[m.parameter_name] = m.parameter;
  return j;
}

}  // namespace

nlohmann::json ToJson(const SegmentationEvaluation& e) {
  nlohmann::json j{{"preset", e.preset},
                   {"image", e.image_kind},
                   {"seeds", e.seeds},
                   {"frames", e.frames},
                   {"plant_pixel_fraction", e.plant_fraction},
                   {"threshold_method", e.ours.method},
                   {"auc", e.ours.auc},
                   {"plant_pixel_recall", e.ours.rates.recall},
                   {"plant_pixel_precision", e.ours.rates.precision},
                   {"soil_pixel_accuracy", e.ours.rates.soil_accuracy}};
  if (e.image_kind == "rgb") j["colour_index"] = e.colour_index;
  j["baseline_thesis"] = {{"fixed", MethodJson(e.thesis_fixed)},
                          {"adaptive", MethodJson(e.thesis_adaptive)}};
  j["crop"] = e.crop;
  j["vehicle"] = e.vehicle;
  return j;
}

namespace {

void PrintFigures(const SegmentationEvaluation& e, std::ostream& out) {
  out << std::fixed << std::setprecision(4) << "segmentation on preset " << e.preset << " ("
      << e.image_kind << (e.image_kind == "rgb" ? std::string(" ") + e.colour_index : "")
      << ", " << e.seeds << " seeds, " << e.frames << " frames, plant pixels "
      << 100.0 * e.plant_fraction << " %)\n"
      << "  method              AUC     recall  precision  soil acc  parameter\n";
  for (const MethodEvaluation* m : {&e.ours, &e.thesis_fixed, &e.thesis_adaptive}) {
    out << "  " << std::left << std::setw(18)
        << (m == &e.ours ? "ours: " + m->method : "thesis " + m->method) << std::right
        << std::setw(7) << m->auc << std::setw(9) << m->rates.recall << std::setw(11)
        << m->rates.precision << std::setw(10) << m->rates.soil_accuracy << "  "
        << m->parameter_name << (m->parameter_name.empty() ? "" : " = ") << m->parameter << '\n';
  }
}

// Southall's published figures (tables 2.1 and 2.2) for the sequence of the
// same name, printed beside ours with --baseline thesis.
void PrintThesisFigures(const std::string& preset, std::ostream& out) {
  struct Row {
    const char* name;
    double fixed_auc, adaptive_auc, tpr, fpr;
  };
  static const Row kRows[] = {{"A", 0.9958, 0.9957, 0.95623, 0.00311},
                              {"B", 0.9749, 0.9779, 0.82434, 0.00073},
                              {"C", 0.9816, 0.9846, 0.83421, 0.00409},
                              {"D", 0.8835, 0.9241, 0.28627, 0.00135}};
  for (const Row& r : kRows) {
    if (preset != r.name) continue;
    out << std::setprecision(4) << "  thesis, published  fixed AUC " << r.fixed_auc
        << ", adaptive AUC " << r.adaptive_auc << ", adaptive at Φ = 3.644: recall " << r.tpr
        << ", FPR " << r.fpr << " (tables 2.1, 2.2)\n";
    return;
  }
  out << "  thesis, published  no sequence named " << preset << " (tables 2.1/2.2 have A-D)\n";
}

}  // namespace

void WriteTable(const SegmentationEvaluation& e, std::ostream& out) {
  PrintFigures(e, out);
  if (e.published_thesis) PrintThesisFigures(e.preset, out);
}

void WriteRocCsv(const std::string& path, const SegmentationEvaluation& e) {
  std::ofstream out(path);
  out << "method,threshold,tpr,fpr\n";
  for (const MethodEvaluation* m : {&e.ours, &e.thesis_fixed, &e.thesis_adaptive}) {
    const std::string name = m == &e.ours ? "ours_" + m->method : "thesis_" + m->method;
    for (const vision::RocPoint& p : m->curve.points) {
      out << name << ',' << p.threshold << ',' << p.tpr << ',' << p.fpr << '\n';
    }
  }
  if (!out.flush()) throw std::runtime_error("cannot write ROC curve to " + path);
}

}  // namespace plantscale::app
