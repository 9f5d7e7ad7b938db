#pragma once
// The report's index.html: a summary table, the problems found, the events
// and the pictures. Plain HTML with inline CSS; no dates or host names, so
// the same run gives the same bytes.

#include <string>
#include <utility>
#include <vector>

#include "ui/run_model.h"

namespace plantscale::ui {

struct ReportPictures {
  std::string map, trace;
  std::vector<std::string> closeups;
  std::vector<std::pair<std::string, std::string>> cameras;  // file, caption
  double ellipse_confidence = 0.95;
  std::vector<std::string> AllFiles() const;
};

std::string ReportHtml(const std::string& log_name, const RunSummary& summary,
                       const std::vector<std::string>& problems,
                       const std::vector<plantscale_event_t>& events, const ReportPictures& pictures);

// `text` with &, <, > and " escaped.
std::string HtmlEscape(const std::string& text);

}  // namespace plantscale::ui
