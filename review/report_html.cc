#include "review/report_html.h"

#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

namespace plantscale::review {
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
  Row(out, "weeds left (seen, not treated)", std::to_string(s.weeds_left));
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


std::string Pct(double part, double whole) {
  return whole > 0.0 ? Fixed(100.0 * part / whole, 1) + " %" : std::string("–");
}

void AgronomyTables(std::ostringstream& out, const AgronomySummary& a, const std::optional<AgronomyTruth>& truth) {
  out << "<h2>Agronomic summary</h2>\n";
  if (a.crop == 0) {
    out << "<p>No crop plant records in the log: no stand, gaps or sizes.</p>\n";
  }
  out << "<table class=\"summary\">\n";
  Row(out, "time, distance", Fixed(a.duration_s, 1) + " s, " + Fixed(a.distance_m, 1) + " m");
  if (a.crop > 0) {
    Row(out, "stand along the rows", Fixed(a.y0_m, 2) + " – " + Fixed(a.y1_m, 2) + " m, " +
                                         std::to_string(a.rows.size()) + " rows at " + Fixed(100 * a.row_spacing_m, 1) +
                                         " cm (" + a.row_spacing_source + ")");
    Row(out, "crop plants", std::to_string(a.crop) + ", " + Fixed(a.plants_per_m, 2) + " per metre of row");
    std::string gaps = std::to_string(a.gaps) + " gaps, " + std::to_string(a.missing) + " plants missing (" +
                       Pct(a.missing, a.missing + a.crop) + "), longest " + std::to_string(a.longest_gap) +
                       (a.longest_gap == 1 ? " plant" : " plants");
    if (a.crops_recorded_as_weeds == 1) {
      gaps += "; 1 place in a gap holds a weed record (crop-sized, or beside the place), taken as the crop "
              "recorded as a weed";
    } else if (a.crops_recorded_as_weeds > 1) {
      gaps += "; " + std::to_string(a.crops_recorded_as_weeds) +
              " places in gaps hold a weed record each (crop-sized, or beside the place), taken as the crop "
              "recorded as a weed";
    }
    Row(out, "gaps (missing plants)", gaps);
    Row(out, "crop leaf-tip radius", "median " + Fixed(100 * a.crop_size.median_m, 1) + " cm (quartiles " +
                                         Fixed(100 * a.crop_size.q1_m, 1) + " – " + Fixed(100 * a.crop_size.q3_m, 1) +
                                         " cm)");
    Row(out, "weeds", std::to_string(a.weeds) + ", " + Fixed(a.weeds_per_m2, 2) + " per m² over " +
                          Fixed(a.surveyed_area_m2, 1) + " m²; median radius " + Fixed(100 * a.weed_size.median_m, 1) +
                          " cm; " + std::to_string(a.far_views_of_crops) +
                          " crop-sized records beside a crop not counted (far views of that crop)");
    Row(out, "weeds per m² of the ground seen",
        Fixed(a.weeds_per_m2_seen, 2) + " over the " + Fixed(a.surveyed_area_m2 - a.unseen_canopy_m2, 1) +
            " m² that the crops' canopy leaves in view: the estimate of the band's density (under a canopy "
            "weeds are unseen, not absent). A lower bound: " +
            (a.weeds_by_model > 0
                 ? "the grower's learned model classified " + std::to_string(a.weeds_by_model) +
                       " of the weeds and splits a weed touching a crop's leaves from it where it sees the weed, "
                       "but not the smallest;"
                 : std::string("a weed touching a crop's leaves is seen as part of that crop,")) +
            " and weeds 1–2 cm across are recorded only when seen in enough frames");
  }
  Row(out, "area treated", a.area_treated_m2 ? Fixed(*a.area_treated_m2, 2) + " m²" : std::string("n/a (no map tiles)"));
  Row(out, "product used", a.product_l ? Fixed(*a.product_l, 3) + " L at " + Fixed(a.rate_l_ha, 0) + " L/ha"
                                       : std::string("n/a"));
  if (a.broadcast_product_l && a.product_saved_fraction) {
    Row(out, "product saved", Fixed(100.0 * *a.product_saved_fraction, 1) + " % against " +
                                  Fixed(*a.broadcast_product_l, 3) +
                                  " L broadcast over the " +
                                  Fixed(a.surveyed_area_m2, 1) + " m² of the rows' band");
  }
  Row(out, "nozzle shots, faults", std::to_string(a.shots) + ", " + std::to_string(a.faults));
  out << "</table>\n";
  if (truth) {
    out << "<h3>Against the simulator's truth</h3>\n<p>" << HtmlEscape(truth->source)
        << "; counted over the same stand and rows.</p>\n<table class=\"rows\">\n"
        << "<tr><th></th><th>report</th><th>truth</th><th>difference</th></tr>\n";
    const auto line = [&](const std::string& name, double mine, double true_value, int decimals) {
      out << "<tr><th>" << HtmlEscape(name) << "</th><td>" << Fixed(mine, decimals) << "</td><td>"
          << Fixed(true_value, decimals) << "</td><td>"
          << (true_value != 0.0 ? Fixed(100.0 * (mine - true_value) / true_value, 1) + " %" : std::string("–"))
          << "</td></tr>\n";
    };
    line("crop plants", a.crop, truth->crop, 0);
    line("missing plants", a.missing, truth->missing, 0);
    line("gaps", a.gaps, truth->gaps, 0);
    line("median crop leaf-tip radius, cm", 100 * a.crop_size.median_m, 100 * truth->median_radius_m, 2);
    line("median weed radius (disc of its area), cm", 100 * a.weed_size.median_m, 100 * truth->median_weed_radius_m,
         2);
    line("weeds per m²", a.weeds_per_m2, truth->weeds_per_m2, 2);
    line("weeds per m² of the ground seen, as the band's", a.weeds_per_m2_seen, truth->weeds_per_m2, 2);
    out << "</table>\n";
  }
  if (a.rows.empty()) return;
  out << "<h3>Per row</h3>\n<table class=\"rows\">\n<tr><th>row</th><th>crop plants</th><th>per metre</th>"
         "<th>spacing, cm</th><th>gaps</th><th>missing</th><th>longest gap</th><th>radius median, cm</th>"
         "<th>quartiles, cm</th><th>weeds</th><th>weeds per m²</th></tr>\n";
  for (const RowAgronomy& r : a.rows) {
    out << "<tr><td>" << r.row << "</td><td>" << r.crop << "</td><td>" << Fixed(r.plants_per_m, 2) << "</td><td>"
        << Fixed(100 * r.plant_spacing_m, 1) << "</td><td>" << r.gaps << "</td><td>" << r.missing << "</td><td>"
        << r.longest_gap << (r.longest_gap > 0 ? " at " + Fixed(r.longest_gap_at_m, 1) + " m" : std::string())
        << "</td><td>" << Fixed(100 * r.crop_size.median_m, 1) << "</td><td>" << Fixed(100 * r.crop_size.q1_m, 1)
        << " – " << Fixed(100 * r.crop_size.q3_m, 1) << "</td><td>" << r.weeds << "</td><td>"
        << Fixed(r.weeds_per_m2, 2) << "</td></tr>\n";
  }
  out << "</table>\n<p><a href=\"summary.csv\">summary.csv</a> · <a href=\"summary.json\">summary.json</a></p>\n";
}

}  // namespace

std::vector<std::string> ReportPictures::AllFiles() const {
  std::vector<std::string> all;
  for (const std::string& f : {overview, trace, histogram}) {
    if (!f.empty()) all.push_back(f);
  }
  for (const auto& [file, caption] : strips) all.push_back(file);
  for (const auto& [file, caption] : closeups) all.push_back(file);
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

std::string ReportHtml(const std::string& log_name, const RunSummary& s, const AgronomySummary& a,
                       const std::optional<AgronomyTruth>& truth, const std::vector<std::string>& problems,
                       const std::vector<plantscale_event_t>& events, const ReportPictures& p) {
  std::ostringstream out;
  out << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
      << "<title>plantscale run report: " << HtmlEscape(log_name) << "</title>\n"
      << "<style>body{font-family:sans-serif;margin:2em;max-width:1250px}"
         "table.summary th{text-align:left;padding-right:2em}figure{display:inline-block;margin:0.5em}"
         "img{max-width:100%}figcaption{font-size:0.9em;color:#444}table.events td{padding-right:1em}"
         "table.rows{border-collapse:collapse}table.rows td,table.rows th{border:1px solid #ccc;padding:2px 8px;"
         "text-align:right}p.problem{color:#a00}</style>\n"
      << "</head><body>\n<h1>Run report: " << HtmlEscape(log_name) << "</h1>\n";
  for (const std::string& problem : problems) {
    out << "<p class=\"problem\">Problem: " << HtmlEscape(problem) << "</p>\n";
  }
  AgronomyTables(out, a, truth);
  if (!p.histogram.empty()) Figure(out, p.histogram, "Plant sizes: crop leaf-tip radius and weed radius; lines at the quartiles and the median");
  out << "<h2>Overview</h2>\n";
  if (p.overview.empty()) out << "<p>none (no crop rows in the log)</p>\n";
  else Figure(out, p.overview, "Crop stand (share of a full stand) and weed pressure (weeds per m²) per 1 m × row cell, the whole run");
  out << "<h2>Bed</h2>\n";
  if (p.strips.empty()) out << "<p>none (nothing mapped)</p>\n";
  if (p.strips_shown < p.strips_total) {
    std::string why;
    for (const std::string& w : p.strips_why) why += (why.empty() ? "" : ", ") + w;
    out << "<p>" << p.strips_shown << " of the run's " << p.strips_total << " strips: " << HtmlEscape(why)
        << ".</p>\n";
  }
  for (const auto& [file, caption] : p.strips) Figure(out, file, "Bed " + caption);
  out << "<h2>Row offset</h2>\n";
  Figure(out, p.trace, "Lateral offset against distance with its ±2σ band");
  out << "<h2>Ellipse close-ups</h2>\n";
  if (p.closeups.empty()) out << "<p>none (no warning or error events, no offset error to show)</p>\n";
  for (const auto& [file, caption] : p.closeups) {
    Figure(out, file, caption + "; " + Fixed(100.0 * p.ellipse_confidence, 0) + " % ellipses magnified ×" +
                          Fixed(p.magnification, 0) + ": vehicle (magenta), plants (white)");
  }
  out << "<h2>Camera at events</h2>\n";
  if (p.cameras.empty()) out << "<p>none drawn</p>\n";
  for (const auto& [file, caption] : p.cameras) Figure(out, file, caption);
  out << "<h2>Run</h2>\n";
  SummaryTable(out, s);
  List(out, "Faults", s.faults);
  List(out, "Problems with the log", problems);
  out << "<h2>Events</h2>\n<table class=\"events\">\n";
  for (const plantscale_event_t& e : events) {
    const char* level = e.severity >= 2 ? "error" : e.severity == 1 ? "warning" : "info";
    if (e.kind == "run_config") continue;  // machine text, in summary.json's log
    out << "<tr><td>" << level << "</td><td>" << HtmlEscape(e.kind) << "</td><td>" << HtmlEscape(e.text)
        << "</td></tr>\n";
  }
  out << "</table>\n</body></html>\n";
  return out.str();
}

namespace {

nlohmann::json SizeJson(const SizeStats& s) {
  return {{"count", s.count}, {"median_m", s.median_m}, {"q1_m", s.q1_m}, {"q3_m", s.q3_m},
          {"bin_m", s.bin_m}, {"histogram", s.histogram}};
}

}  // namespace

std::string ReportJson(const std::string& log_name, const RunSummary& s, const AgronomySummary& a,
                       const std::optional<AgronomyTruth>& truth, const std::vector<std::string>& problems) {
  nlohmann::json j;
  j["log"] = log_name;
  j["run"] = {{"distance_m", s.distance_m},
              {"offset_source", s.offset_source},
              {"mean_offset_m", s.mean_offset_m},
              {"rms_offset_m", s.rms_offset_m},
              {"rms_offset_error_m", s.rms_offset_error_m ? nlohmann::json(*s.rms_offset_error_m) : nlohmann::json()},
              {"plants_seen", s.plants_seen},
              {"crop_seen", s.crop_seen},
              {"weeds_seen", s.weeds_seen},
              {"crop_treated", s.crop_treated},
              {"weeds_treated", s.weeds_treated},
              {"weeds_left", s.weeds_left},
              {"shots", s.shots},
              {"faults", s.faults},
              {"vehicle_restarts", s.vehicle_restarts},
              {"messages", s.messages}};
  nlohmann::json rows = nlohmann::json::array();
  for (const RowAgronomy& r : a.rows) {
    rows.push_back({{"row", r.row},
                    {"crop_plants", r.crop},
                    {"stand_length_m", r.stand_length_m},
                    {"plants_per_m", r.plants_per_m},
                    {"plant_spacing_m", r.plant_spacing_m},
                    {"gaps", r.gaps},
                    {"missing_plants", r.missing},
                    {"longest_gap_plants", r.longest_gap},
                    {"longest_gap_at_m", r.longest_gap_at_m},
                    {"crop_radius", SizeJson(r.crop_size)},
                    {"weeds", r.weeds},
                    {"weeds_per_m2", r.weeds_per_m2}});
  }
  const auto opt = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(); };
  j["agronomy"] = {{"distance_m", a.distance_m},
                   {"duration_s", a.duration_s},
                   {"row_spacing_m", a.row_spacing_m},
                   {"row_spacing_source", a.row_spacing_source},
                   {"stand_y0_m", a.y0_m},
                   {"stand_y1_m", a.y1_m},
                   {"surveyed_area_m2", a.surveyed_area_m2},
                   {"crop_plants", a.crop},
                   {"plants_per_m", a.plants_per_m},
                   {"gaps", a.gaps},
                   {"missing_plants", a.missing},
                   {"longest_gap_plants", a.longest_gap},
                   {"crop_radius", SizeJson(a.crop_size)},
                   {"weeds", a.weeds},
                   {"weeds_per_m2", a.weeds_per_m2},
                   {"weeds_by_model", a.weeds_by_model},
                   {"weeds_per_m2_of_ground_seen", a.weeds_per_m2_seen},
                   {"unseen_canopy_area_m2", a.unseen_canopy_m2},
                   {"weed_records_far_views_of_crops", a.far_views_of_crops},
                   {"weed_records_crops_in_gaps", a.crops_recorded_as_weeds},
                   {"weed_radius", SizeJson(a.weed_size)},
                   {"area_treated_m2", opt(a.area_treated_m2)},
                   {"product_l", opt(a.product_l)},
                   {"broadcast_product_l", opt(a.broadcast_product_l)},
                   {"product_saved_fraction", opt(a.product_saved_fraction)},
                   {"rate_l_ha", a.rate_l_ha},
                   {"shots", a.shots},
                   {"faults", a.faults},
                   {"rows", rows}};
  j["truth"] = truth ? nlohmann::json{{"source", truth->source},
                                      {"crop_plants", truth->crop},
                                      {"missing_plants", truth->missing},
                                      {"gaps", truth->gaps},
                                      {"median_radius_m", truth->median_radius_m},
                                      {"weeds", truth->weeds},
                                      {"weeds_per_m2", truth->weeds_per_m2},
                                      {"median_weed_radius_m", truth->median_weed_radius_m}}
                     : nlohmann::json();
  j["problems"] = problems;
  return j.dump(2) + "\n";
}

}  // namespace plantscale::review
