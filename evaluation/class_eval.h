#pragma once
// `plantscale evaluate classes`: soil, crop and weed IoU of a learned model
// on labelled photographs (the confusion matrix summed over the set, so a
// photograph counts by its pixels), beside the thesis's size rule where it
// applies to photographs: plant pixels from the excess-green (colour) or
// local soil-level (grey) segmenter, each blob crop when it covers at least
// a share θ of the photograph and weed otherwise. The thesis's rule also
// takes the grid's predicted crop positions, which photographs do not have;
// θ is chosen on the set itself (the best of a ladder), so the rule's figure
// is an upper bound for it.

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace plantscale::app {

struct ClassEvalRequest {
  std::filesystem::path images;
  std::filesystem::path labels;
  std::filesystem::path model;  // empty: the size rule only
  bool size_rule = true;
  bool progress = true;
};

struct ClassFigures {
  std::string method;
  std::vector<int64_t> confusion;  // 3 × 3, rows truth, columns predicted
  std::vector<double> iou;         // soil, crop, weed (NaN: absent)
  double miou = 0.0;
  double parameter = 0.0;          // the size rule's θ
};

// One evaluation: its figures and what it was run on (its JSON and table
// need nothing else).
struct ClassEvaluation {
  std::string images, labels, model_file;  // the request's (model_file empty: none)
  int photographs = 0;
  int64_t pixels = 0;
  std::vector<ClassFigures> methods;  // the model first, then the size rule
  double model_ms_per_megapixel = 0.0;
};

// Throws DataError naming the file (no label, another size, ids outside
// 0–2, an empty folder, a model that does not load).
ClassEvaluation EvaluateClasses(const ClassEvalRequest& request, std::ostream& log);

// Its JSON and table (evaluation/writer.h: the one place they are written).
nlohmann::json ToJson(const ClassEvaluation& e);
void WriteTable(const ClassEvaluation& e, std::ostream& out);
// The JSON of an empty evaluation of a model beside the size rule: the keys
// `plantscale figures` may quote.
nlohmann::json ClassEvaluationJsonShape();

}  // namespace plantscale::app
