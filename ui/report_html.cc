#include "ui/report_html.h"

#include <iomanip>
#include <sstream>

namespace plantscale::ui {
namespace {

std::string Fixed(double v, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << v;
  return out.str();
}

void Row(std::ostringstream& out, const std::string& name, const std::string& value) {
  out << "<tr><th>" << HtmlEscape(name) << "</th><td>" << HtmlEscape(value) << "</td></tr>\n";
}

void SummaryTable(std::ostringstream& out, const RunSummary& s) {
  out << "<h2>Summary</h2>\n<table class=\"summary\">\n";
  Row(out, "distance", Fixed(s.distance_m, 2) + " m");
  Row(out, "mean offset (" + s.offset_source + ")", Fixed(1e3 * s.mean_offset_m, 1) + " mm");
  Row(out, "RMS offset (" + s.offset_source + ")", Fixed(1e3 * s.rms_offset_m, 1) + " mm");
  if (s.rms_offset_error_m) {
    Row(out, "RMS offset error (tracker − simulator truth)", Fixed(1e3 * *s.rms_offset_error_m, 1) + " mm");
  }
  Row(out, "plants seen", std::to_string(s.plants_seen) + " (" + std::to_string(s.crop_seen) +
                              " crop, " + std::to_string(s.weeds_seen) + " weeds)");
  const auto treated = [](int n, int not_reached) {
    return std::to_string(n) + (not_reached > 0 ? " (" + std::to_string(not_reached) +
                                                      " more the bar had not reached when the run ended)"
                                                : std::string());
  };
  Row(out, "crop treated", treated(s.crop_treated, s.crop_not_reached));
  Row(out, "weeds treated", treated(s.weeds_treated, s.weeds_not_reached));
  Row(out, "nozzle shots", std::to_string(s.shots));
  Row(out, "area treated",
      s.area_treated_m2 ? Fixed(*s.area_treated_m2, 3) + " m²" : std::string("n/a (no map tiles in log)"));
  Row(out, "faults", s.faults.empty() ? std::string("none") : std::to_string(s.faults.size()));
  Row(out, "vehicle restarts", std::to_string(s.vehicle_restarts));
  Row(out, "messages", std::to_string(s.messages));
  out << "</table>\n";
}

void List(std::ostringstream& out, const std::string& title, const std::vector<std::string>& lines) {
  out << "<h2>" << title << "</h2>\n";
  if (lines.empty()) {
    out << "<p>none</p>\n";
    return;
  }
  out << "<ul>\n";
  for (const std::string& l : lines) out << "<li>" << HtmlEscape(l) << "</li>\n";
  out << "</ul>\n";
}

void Figure(std::ostringstream& out, const std::string& file, const std::string& caption) {
  out << "<figure><img src=\"" << HtmlEscape(file) << "\" alt=\"" << HtmlEscape(caption)
      << "\"><figcaption>" << HtmlEscape(caption) << "</figcaption></figure>\n";
}

}  // namespace

std::vector<std::string> ReportPictures::AllFiles() const {
  std::vector<std::string> all{map, trace};
  all.insert(all.end(), closeups.begin(), closeups.end());
  for (const auto& [file, caption] : cameras) all.push_back(file);
  return all;
}

std::string HtmlEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string ReportHtml(const std::string& log_name, const RunSummary& s,
                       const std::vector<std::string>& problems,
                       const std::vector<plantscale_event_t>& events, const ReportPictures& p) {
  std::ostringstream out;
  out << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
      << "<title>plantscale run report: " << HtmlEscape(log_name) << "</title>\n"
      << "<style>body{font-family:sans-serif;margin:2em;max-width:1250px}"
         "table.summary th{text-align:left;padding-right:2em}figure{display:inline-block;margin:0.5em}"
         "figcaption{font-size:0.9em;color:#444}table.events td{padding-right:1em}</style>\n"
      << "</head><body>\n<h1>Run report: " << HtmlEscape(log_name) << "</h1>\n";
  SummaryTable(out, s);
  List(out, "Faults", s.faults);
  List(out, "Problems with the log", problems);
  out << "<h2>Map</h2>\n";
  Figure(out, p.map, "Bed map: crop green, weeds red, treated blue, soil brown; plants as dots, "
                     "vehicle path grey, predicted grid yellow/cyan at the end of the run");
  out << "<h2>Row offset</h2>\n";
  Figure(out, p.trace, "Lateral offset and bearing against distance with ±2σ bands");
  out << "<h2>Ellipse close-ups</h2>\n";
  if (p.closeups.empty()) out << "<p>none (run shorter than the close-up spacing)</p>\n";
  for (const std::string& c : p.closeups) Figure(out, c, Fixed(100.0 * p.ellipse_confidence, 0) + " % ellipses: vehicle (magenta), plants (white); " + c);
  out << "<h2>Camera at events</h2>\n";
  if (p.cameras.empty()) out << "<p>no warning or error events</p>\n";
  for (const auto& [file, caption] : p.cameras) Figure(out, file, caption);
  out << "<h2>Events</h2>\n<table class=\"events\">\n";
  for (const plantscale_event_t& e : events) {
    const char* level = e.severity >= 2 ? "error" : e.severity == 1 ? "warning" : "info";
    out << "<tr><td>" << level << "</td><td>" << HtmlEscape(e.kind) << "</td><td>" << HtmlEscape(e.text)
        << "</td></tr>\n";
  }
  out << "</table>\n</body></html>\n";
  return out.str();
}

}  // namespace plantscale::ui
