#pragma once
// The JSON, the table and the ROC curves' CSV of `evaluate segmentation`
// (writer.h): the one place its keys, rows and columns are written.

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "evaluation/segmentation_eval.h"

namespace plantscale::app {

nlohmann::json ToJson(const SegmentationEvaluation& evaluation);
// The table; with published_thesis the thesis's published figures after it.
void WriteTable(const SegmentationEvaluation& evaluation, std::ostream& out);
// method,threshold,tpr,fpr: every method's ROC curve. Throws
// std::runtime_error when the file cannot be written.
void WriteRocCsv(const std::string& path, const SegmentationEvaluation& evaluation);

}  // namespace plantscale::app
