#include "ui/report.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include "review/report_html.h"
#include "telemetry/log.h"
#include "ui/canvas.h"
#include "ui/palette.h"

namespace plantscale::ui {
namespace {

namespace tm = plantscale::telemetry;

std::string Fixed(double v, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << v;
  return out.str();
}

std::string CameraPicture(const std::filesystem::path& dir, const ReportOptions& o, const review::EventSnapshot& s,
                          int index) {
  Canvas canvas(o.camera_width_px, o.camera_height_px);
  CameraView view(o.camera);
  view.AddTo(canvas.AddRenderer(0, 0, 1, 1, palette::kBackground));
  view.Show(s.thumbnail ? &*s.thumbnail : nullptr, s.grid ? &*s.grid : nullptr);
  const std::string name = "camera_event_" + std::to_string(index) + ".png";
  WritePng(canvas.Render(), dir / name);
  return name;
}

// Where the plants in view are (the close-up's centre): the mean y of the
// latest frame's plants, else the vehicle.
std::optional<double> ViewY(const review::RunModel& model) {
  if (!model.plants_in_frame().empty()) {
    double y = 0.0;
    for (const tm::PlantObservation& p : model.plants_in_frame()) y += p.position_m.y();
    return y / static_cast<double>(model.plants_in_frame().size());
  }
  if (model.pose()) return model.pose()->y_m;
  return std::nullopt;
}

// Watches the replay for the close-ups: warning/error events and the
// largest offset error against truth (else the largest offset sd).
class CloseupPicker {
 public:
  CloseupPicker(const ReportOptions& o, double half_length_m) : o_(o), half_(half_length_m) {}

  void After(const review::RunModel& model) {
    while (events_seen_ < model.events().size()) {
      const plantscale_event_t& e = model.events()[events_seen_++];
      if (e.severity < plantscale_event_t::SEVERITY_WARNING ||
          static_cast<int>(events_.size()) >= o_.max_event_closeups) {
        continue;
      }
      if (const auto y = ViewY(model)) events_.push_back(TakeCloseup(model, *y, half_, "event: " + e.text));
    }
    CheckOffset(model);
  }

  std::vector<CloseupSnapshot> All() const {
    std::vector<CloseupSnapshot> all = events_;
    if (worst_) all.push_back(*worst_);
    std::stable_sort(all.begin(), all.end(),
                     [](const CloseupSnapshot& a, const CloseupSnapshot& b) { return a.distance_m < b.distance_m; });
    return all;
  }

 private:
  static void Remember(std::map<int64_t, double>& m, int64_t utime, double v) {
    m[utime] = v;
    if (m.size() > 64) m.erase(m.begin());
  }

  void Consider(const review::RunModel& model, double score, const std::string& what) {
    // A new close-up only when 10 % worse than the last: a bounded number of
    // snapshots (each a pass over the map) however the error grows.
    if (model.distance_m() < o_.settle_m || score < 1e-3 || score <= 1.1 * worst_score_) return;
    const auto y = ViewY(model);
    if (!y) return;
    worst_score_ = score;
    worst_ = TakeCloseup(model, *y, half_, what + " " + Fixed(1e3 * score, 1) + " mm");
  }

  void CheckOffset(const review::RunModel& model) {
    const bool est_new = model.trace().size() > trace_seen_, truth_new = model.truth_trace().size() > truth_seen_;
    trace_seen_ = model.trace().size();
    truth_seen_ = model.truth_trace().size();
    if (est_new) {
      const review::TraceSample& t = model.trace().back();
      Remember(est_, t.utime, t.offset_m);
      const auto it = truth_.find(t.utime);
      if (it != truth_.end()) {
        Consider(model, std::abs(t.offset_m - it->second), "largest offset error (tracker - truth)");
      } else if (model.truth_trace().empty() && t.mode == tm::FilterMode::kTracking) {
        Consider(model, t.offset_sigma_m, "largest offset sd");
      }
    }
    if (truth_new) {
      const review::TraceSample& t = model.truth_trace().back();
      Remember(truth_, t.utime, t.offset_m);
      const auto it = est_.find(t.utime);
      if (it != est_.end()) Consider(model, std::abs(it->second - t.offset_m), "largest offset error (tracker - truth)");
    }
  }

  const ReportOptions& o_;
  double half_;
  size_t events_seen_ = 0, trace_seen_ = 0, truth_seen_ = 0;
  std::map<int64_t, double> est_, truth_;
  std::vector<CloseupSnapshot> events_;
  std::optional<CloseupSnapshot> worst_;
  double worst_score_ = 0.0;
};

// Across the bed: the crop rows ± half a spacing and a margin, else the map.
std::pair<double, double> BedAcross(const review::RunModel& model, const review::AgronomySummary& a) {
  if (!a.rows.empty()) {
    return {(a.rows.front().row - 0.5) * a.row_spacing_m - 0.15, (a.rows.back().row + 0.5) * a.row_spacing_m + 0.15};
  }
  double lo = 1e300, hi = -1e300;
  for (const auto& [key, t] : model.tiles()) {
    lo = std::min(lo, t.origin_m.x());
    hi = std::max(hi, t.origin_m.x() + t.width * t.resolution_m);
  }
  if (lo < hi) return {lo, hi};
  return {-1.0, 1.0};
}

// Along the bed: the stand, else the map, else the path.
std::optional<std::pair<double, double>> BedAlong(const review::RunModel& model, const review::AgronomySummary& a) {
  if (a.crop > 0) return std::make_pair(a.y0_m, a.y1_m);
  double lo = 1e300, hi = -1e300;
  for (const auto& [key, t] : model.tiles()) {
    lo = std::min(lo, t.origin_m.y());
    hi = std::max(hi, t.origin_m.y() + t.height * t.resolution_m);
  }
  for (const auto& [x, y] : model.path()) lo = std::min(lo, y), hi = std::max(hi, y);
  if (lo < hi) return std::make_pair(lo, hi);
  return std::nullopt;
}

// The strips to draw: all of them when they fit, else the first, those with
// a close-up, the longest gap and the most weeds, then evenly spaced.
std::vector<int> PickStrips(int total, int max_strips, const std::vector<double>& wanted_y, double y0, double length,
                            const review::AgronomySummary& a, std::vector<std::string>& why) {
  std::vector<int> all;
  if (total <= max_strips) {
    for (int i = 0; i < total; ++i) all.push_back(i);
    return all;
  }
  std::set<int> picked{0};
  why.push_back("the start");
  const auto strip_of = [&](double y) { return std::clamp(static_cast<int>((y - y0) / length), 0, total - 1); };
  for (double y : wanted_y) {
    if (static_cast<int>(picked.size()) < max_strips) picked.insert(strip_of(y));
  }
  if (!wanted_y.empty()) why.push_back("the close-ups");
  for (const review::RowAgronomy& r : a.rows) {
    if (r.longest_gap == a.longest_gap && a.longest_gap > 0 && static_cast<int>(picked.size()) < max_strips) {
      picked.insert(strip_of(r.longest_gap_at_m));
      why.push_back("the longest gap");
      break;
    }
  }
  // Weeds per strip.
  std::vector<std::pair<int, int>> weeds;  // count, strip
  std::map<int, int> per;
  for (const review::HeatCell& c : a.cells) per[strip_of(a.y0_m + (c.index + 0.5) * a.cell_length_m)] += c.weeds;
  for (const auto& [s, n] : per) weeds.emplace_back(-n, s);
  std::sort(weeds.begin(), weeds.end());
  for (size_t i = 0; i < weeds.size() && i < 2 && static_cast<int>(picked.size()) < max_strips; ++i) {
    picked.insert(weeds[i].second);
  }
  if (!weeds.empty()) why.push_back("the most weeds");
  for (int k = 1; static_cast<int>(picked.size()) < max_strips && k < 4 * max_strips; ++k) {
    picked.insert(static_cast<int>(std::lround(static_cast<double>(k) * (total - 1) / (max_strips - 1))) % total);
  }
  why.push_back("evenly spaced");
  return {picked.begin(), picked.end()};
}

}  // namespace

OptionErrors ReportOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "strip_length_m", pictures.strip_length_m);
  RequireInRange(e, "strips_per_picture", pictures.strips_per_picture, 1, 50);
  RequireInRange(e, "max_strip_pictures", pictures.max_strip_pictures, 0, 100);
  RequirePositive(e, "closeup_length_m", pictures.closeup_length_m);
  RequirePositive(e, "ellipse_magnification", pictures.ellipse_magnification);
  RequireInRange(e, "ellipse_confidence", pictures.ellipse_confidence, 0.0, 1.0, false, false);
  RequireNonNegative(e, "max_event_closeups", max_event_closeups);
  for (const auto& [key, v] : {std::pair{"strip_width_px", pictures.strip_width_px},
                               {"closeup_width_px", pictures.closeup_width_px},
                               {"overview_width_px", pictures.overview_width_px},
                               {"trace_width_px", pictures.trace_width_px},
                               {"trace_height_px", pictures.trace_height_px},
                               {"camera_width_px", camera_width_px}}) {
    RequireInRange(e, key, v, 100, 8192);
  }
  const OptionErrors more = agronomy.Validate();
  e.insert(e.end(), more.begin(), more.end());
  return e;
}

namespace {

// Replays the log into `model`, `picker` choosing the close-ups on the way;
// the log's problems, the run's summary and agronomy into `result`. The
// run's configuration event, when the log has one.
std::optional<std::string> ReadRun(const std::filesystem::path& log, const ReportOptions& o, review::RunModel& model,
                                   CloseupPicker& picker, ReportResult& result) {
  tm::LogReader reader(log);
  tm::Subscriber subscriber;
  model.Follow(subscriber);
  int64_t clock = 0;
  while (const std::optional<tm::LogEvent> e = reader.Next()) {
    clock = e->utime;
    model.Feed(subscriber, e->channel, e->data.data(), e->data.size(), e->utime);
    picker.After(model);
  }
  std::optional<std::string> run_config;
  for (const plantscale_event_t& e : model.events()) {
    if (e.kind == "run_config" && !run_config) run_config = e.text;
  }
  if (!reader.error().empty()) result.problems.push_back("log: " + reader.error() + " (the report shows what came before)");
  if (reader.events_read() == 0) result.problems.push_back("log: no events in " + log.string());
  for (const std::string& p : model.Problems(clock)) result.problems.push_back(p);
  result.summary = model.Summary();
  result.agronomy = review::Agronomy(model, result.summary, o.agronomy);
  if (result.agronomy.crop == 0 && reader.events_read() > 0) {
    result.problems.push_back("no crop plant records in the log: no agronomic figures per row");
  }
  return run_config;
}

// The simulator's truth over the stand, when the log came from it.
void AddTruth(const review::RunModel& model, const std::string& run_config, const ReportOptions& o, ReportResult& result) {
  const review::AgronomySummary& a = result.agronomy;
  review::StandWindow stand{a.y0_m, a.y1_m, a.rows.front().row, a.rows.back().row, a.row_spacing_m, {}};
  for (const auto& [id, r] : model.plants()) {
    if (r.plant.kind == tm::PlantKind::kCrop) stand.crops_m.emplace_back(r.plant.position_m.x(), r.plant.position_m.y());
  }
  try {
    result.truth = o.truth(run_config, stand);
  } catch (const std::exception& e) {
    result.problems.push_back(std::string("simulator truth not rebuilt: ") + e.what());
  }
}

using SavePicture = std::function<std::string(const cv::Mat&, const std::string&)>;

// The bed as strips of strip_length_m, strips_per_picture to a picture, at
// most max_strip_pictures pictures (PickStrips chooses which strips).
void DrawBedStrips(const review::RunModel& model, const review::AgronomySummary& a, const std::vector<CloseupSnapshot>& closeups,
                   std::pair<double, double> across, const ReportOptions& o, const SavePicture& save,
                   review::ReportPictures& pictures) {
  const auto along = BedAlong(model, a);
  if (!along) return;
  const double L = o.pictures.strip_length_m;
  const double y0 = std::floor(along->first);
  const int total = std::max(1, static_cast<int>(std::ceil((along->second - y0) / L - 1e-9)));
  std::vector<double> wanted;
  for (const CloseupSnapshot& c : closeups) wanted.push_back(c.y_m);
  const std::vector<int> strips = PickStrips(total, o.pictures.max_strip_pictures * o.pictures.strips_per_picture,
                                             wanted, y0, L, a, pictures.strips_why);
  pictures.strips_total = total;
  const size_t per_picture = static_cast<size_t>(o.pictures.strips_per_picture);
  for (size_t i = 0; i < strips.size(); i += per_picture) {
    std::vector<double> starts;
    std::string caption;
    for (size_t k = i; k < strips.size() && k < i + per_picture; ++k) {
      starts.push_back(y0 + strips[k] * L);
      caption += (caption.empty() ? "" : ", ") + Fixed(starts.back(), 0) + "–" + Fixed(starts.back() + L, 0) + " m";
    }
    const std::string name = "bed_" + std::to_string(pictures.strips.size() + 1) + ".png";
    pictures.strips.emplace_back(save(DrawStrips(model, a, starts, across.first, across.second, o.pictures), name),
                                 caption);
    pictures.strips_shown += static_cast<int>(starts.size());
  }
}

// Every picture of the report into `out_dir`.
review::ReportPictures DrawPictures(const review::RunModel& model, const CloseupPicker& picker, const std::filesystem::path& out_dir,
                            const ReportOptions& o, ReportResult& result) {
  const review::AgronomySummary& a = result.agronomy;
  review::ReportPictures pictures;
  pictures.ellipse_confidence = o.pictures.ellipse_confidence;
  pictures.magnification = o.pictures.ellipse_magnification;
  const SavePicture save = [&](const cv::Mat& img, const std::string& name) {
    WritePng(img, out_dir / name);
    return name;
  };
  const auto [x_lo, x_hi] = BedAcross(model, a);
  if (a.cells_along > 0 && !a.rows.empty()) pictures.overview = save(DrawOverview(a, o.pictures), "overview.png");
  const std::vector<CloseupSnapshot> closeups = picker.All();
  DrawBedStrips(model, a, closeups, {x_lo, x_hi}, o, save, pictures);
  for (size_t i = 0; i < closeups.size(); ++i) {
    pictures.closeups.emplace_back(
        save(DrawCloseup(closeups[i], x_lo, x_hi, o.pictures), "closeup_" + std::to_string(i + 1) + ".png"),
        closeups[i].reason + ", at " + Fixed(closeups[i].distance_m, 1) + " m");
  }
  pictures.trace = save(DrawOffsetTrace(model, o.pictures), "offset_trace.png");
  if (a.crop_size.count + a.weed_size.count > 0) pictures.histogram = save(DrawSizeHistograms(a), "plant_size.png");
  if (model.event_snapshots().empty()) return pictures;
  if (!DisplayAvailable()) {
    result.problems.push_back("camera views at the events not drawn: no X display (plantscale report starts "
                              "xvfb-run itself when it is installed)");
    return pictures;
  }
  for (size_t i = 0; i < model.event_snapshots().size(); ++i) {
    pictures.cameras.push_back({CameraPicture(out_dir, o, model.event_snapshots()[i], static_cast<int>(i)),
                                model.event_snapshots()[i].event.text});
  }
  return pictures;
}

void WriteText(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
}

}  // namespace

ReportResult WriteReport(const std::filesystem::path& log, const std::filesystem::path& out_dir,
                         const ReportOptions& o) {
  ThrowIfInvalid("report options", o.Validate());
  std::filesystem::create_directories(out_dir);
  review::RunModel model;
  ReportResult result;
  CloseupPicker picker(o, 0.5 * o.pictures.closeup_length_m + 0.3);
  const std::optional<std::string> run_config = ReadRun(log, o, model, picker, result);
  const review::AgronomySummary& a = result.agronomy;
  if (o.truth && run_config && !a.rows.empty()) AddTruth(model, *run_config, o, result);
  const review::ReportPictures pictures = DrawPictures(model, picker, out_dir, o, result);
  const std::string name = log.filename().string();
  WriteText(out_dir / "summary.csv", review::AgronomyCsv(a));
  WriteText(out_dir / "summary.json", review::ReportJson(name, result.summary, a, result.truth, result.problems));
  result.index = out_dir / "index.html";
  WriteText(result.index, review::ReportHtml(name, result.summary, a, result.truth, result.problems, model.events(), pictures));
  result.pictures = pictures.AllFiles();
  return result;
}

}  // namespace plantscale::ui
