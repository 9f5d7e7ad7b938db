#include "ui/report.h"

#include <fstream>
#include <iomanip>
#include <sstream>

#include "telemetry/log.h"
#include "ui/canvas.h"
#include "ui/map_view.h"
#include "ui/offset_trace.h"
#include "ui/palette.h"
#include "ui/report_html.h"

namespace plantscale::ui {
namespace {

namespace tm = plantscale::telemetry;

// Renders pieces of the run into PNG files in the output folder.
class Renderer {
 public:
  Renderer(const std::filesystem::path& dir, const ReportOptions& o) : dir_(dir), o_(o) {}

  std::string Map(const RunModel& model, const std::string& name, std::optional<FieldWindow> window,
                  int w, int h) {
    Canvas canvas(w, h);
    MapViewParams params;
    params.ellipses.confidence = o_.ellipse_confidence;
    MapView view(params);
    view.AddTo(canvas.AddRenderer(0, 0, 1, 1, palette::kBackground));
    view.Update(model);  // first pass builds the layers so that WholeRun sees the tiles
    view.SetWindow(window ? window : std::optional<FieldWindow>(view.WholeRun(model)));
    view.Update(model);
    return Save(canvas.Render(), name);
  }

  std::string Trace(const RunModel& model) {
    Canvas canvas(o_.trace_width_px, o_.trace_height_px);
    OffsetTrace trace;
    trace.AddTo(canvas.AddRenderer(0, 0, 1, 1, {1, 1, 1}));
    trace.Update(model);
    return Save(canvas.Render(), "offset_trace.png");
  }

  std::string Camera(const EventSnapshot& s, int index) {
    Canvas canvas(o_.camera_width_px, o_.camera_height_px);
    CameraView view(o_.camera);
    view.AddTo(canvas.AddRenderer(0, 0, 1, 1, palette::kBackground));
    view.Show(s.thumbnail ? &*s.thumbnail : nullptr, s.grid ? &*s.grid : nullptr);
    return Save(canvas.Render(), "camera_event_" + std::to_string(index) + ".png");
  }

 private:
  std::string Save(const cv::Mat& image, const std::string& name) {
    WritePng(image, dir_ / name);
    return name;
  }
  std::filesystem::path dir_;
  ReportOptions o_;
};

}  // namespace

OptionErrors ReportOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "closeup_every_m", closeup_every_m);
  RequirePositive(e, "closeup_length_m", closeup_length_m);
  RequireInRange(e, "ellipse_confidence", ellipse_confidence, 0.0, 1.0, false, false);
  for (const auto& [key, v] : {std::pair{"map_width_px", map_width_px}, {"map_height_px", map_height_px},
                               {"trace_width_px", trace_width_px}, {"camera_width_px", camera_width_px}}) {
    RequireInRange(e, key, v, 16, 8192);
  }
  return e;
}

ReportResult WriteReport(const std::filesystem::path& log, const std::filesystem::path& out_dir,
                         const ReportOptions& o) {
  ThrowIfInvalid("report options", o.Validate());
  RequireDisplay("plantscale report");
  std::filesystem::create_directories(out_dir);
  tm::LogReader reader(log);
  tm::Subscriber subscriber;
  RunModel model;
  model.Follow(subscriber);
  Renderer render(out_dir, o);
  ReportResult result;
  std::vector<std::string> closeups;
  double next_closeup_m = o.closeup_every_m;
  int64_t clock = 0;
  while (const std::optional<tm::LogEvent> e = reader.Next()) {
    clock = e->utime;
    subscriber.Feed(e->channel, e->data.data(), e->data.size(), e->utime);
    if (model.distance_m() >= next_closeup_m && model.pose()) {
      const double y = model.pose()->y_m;
      const std::string name = "closeup_" + std::to_string(static_cast<int>(next_closeup_m)) + "m.png";
      closeups.push_back(render.Map(model, name, FieldWindow{y - 0.5 * o.closeup_length_m, y + 0.5 * o.closeup_length_m, 0.0},
                                    o.closeup_width_px, o.closeup_height_px));
      next_closeup_m += o.closeup_every_m;
    }
  }
  if (!reader.error().empty()) result.problems.push_back("log: " + reader.error());
  if (reader.events_read() == 0) result.problems.push_back("log: no events in " + log.string());
  for (const std::string& p : model.Problems(clock)) result.problems.push_back(p);
  result.summary = model.Summary();
  ReportPictures pictures;
  pictures.map = render.Map(model, "map.png", std::nullopt, o.map_width_px, o.map_height_px);
  pictures.trace = render.Trace(model);
  pictures.closeups = closeups;
  pictures.ellipse_confidence = o.ellipse_confidence;
  for (size_t i = 0; i < model.event_snapshots().size(); ++i) {
    pictures.cameras.push_back({render.Camera(model.event_snapshots()[i], static_cast<int>(i)),
                                model.event_snapshots()[i].event.text});
  }
  result.index = out_dir / "index.html";
  std::ofstream html(result.index, std::ios::binary);
  html << ReportHtml(log.filename().string(), result.summary, result.problems, model.events(), pictures);
  if (!html) throw std::runtime_error(result.index.string() + ": cannot write");
  result.pictures = pictures.AllFiles();
  return result;
}

}  // namespace plantscale::ui
