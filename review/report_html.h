#pragma once
// The report's index.html: a summary table, the problems found, the events
// and the pictures. Plain HTML with inline CSS; no dates or host names, so
// the same run gives the same bytes.

#include <string>
#include <utility>
#include <vector>

#include "review/agronomy.h"
#include "review/run_model.h"

namespace plantscale::review {

struct ReportPictures {
  std::string overview, trace, histogram;  // empty: not drawn
  std::vector<std::pair<std::string, std::string>> strips;    // file, the stretches it shows
  int strips_total = 0, strips_shown = 0;
  std::vector<std::string> strips_why;  // how the strips were picked when not all are shown
  std::vector<std::pair<std::string, std::string>> closeups;  // file, caption
  std::vector<std::pair<std::string, std::string>> cameras;   // file, caption
  double ellipse_confidence = 0.95;
  double magnification = 20.0;
  std::vector<std::string> AllFiles() const;
};

std::string ReportHtml(const std::string& log_name, const RunSummary& summary, const AgronomySummary& agronomy,
                       const std::optional<AgronomyTruth>& truth, const std::vector<std::string>& problems,
                       const std::vector<plantscale_event_t>& events, const ReportPictures& pictures);

// summary.json and `report --json`: {"log", "run": {…}, "agronomy": {…,
// "rows": […]}, "truth": {…} or null, "problems": […]}.
std::string ReportJson(const std::string& log_name, const RunSummary& summary, const AgronomySummary& agronomy,
                       const std::optional<AgronomyTruth>& truth, const std::vector<std::string>& problems);

// `text` with &, <, > and " escaped.
std::string HtmlEscape(const std::string& text);

}  // namespace plantscale::review
