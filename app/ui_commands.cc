#include "app/ui_commands.h"

#include <chrono>
#include <iomanip>
#include <iostream>

#include "ui/canvas.h"
#include "ui/report.h"
#include "ui/station.h"

namespace plantscale::app {
namespace {

struct StationArgs {
  ui::StationOptions options;
  std::string log;
};

struct ReportArgs {
  std::string log;
  std::string out;
  double closeup_every_m = 10.0;
  double confidence = 0.95;
};

// Without DISPLAY VTK would abort the process; say so and how to fix it
// rather than re-executing under xvfb-run behind the user's back.
int NoDisplay(const ui::DisplayError& e) {
  std::cerr << "plantscale: error: " << e.what() << '\n';
  return 2;
}

int Station(StationArgs& a) {
  a.options.log = a.log;
  try {
    const ui::StationResult r = ui::RunStation(a.options);
    std::cout << "station: " << r.frames << " frames in " << std::fixed << std::setprecision(1)
              << r.seconds << " s (" << r.frames_per_second << " fps)\n";
    for (const std::string& p : r.problems) std::cout << "station: problem: " << p << '\n';
  } catch (const ui::DisplayError& e) {
    return NoDisplay(e);
  }
  return 0;
}

int Report(const ReportArgs& a) {
  ui::ReportOptions options;
  options.closeup_every_m = a.closeup_every_m;
  options.ellipse_confidence = a.confidence;
  const auto start = std::chrono::steady_clock::now();
  try {
    const ui::ReportResult r = ui::WriteReport(a.log, a.out, options);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "report: " << r.index.string() << " (" << r.pictures.size() << " pictures, "
              << std::fixed << std::setprecision(2) << r.summary.distance_m << " m, " << s << " s)\n";
    for (const std::string& p : r.problems) std::cout << "report: problem: " << p << '\n';
  } catch (const ui::DisplayError& e) {
    return NoDisplay(e);
  }
  return 0;
}

}  // namespace

void AddUiCommands(CommandRegistry& registry) {
  StationArgs& s = registry.Keep(StationArgs{});
  CLI::App* station = registry.Add("station", "operator station window (live LCM or a log)",
                                   [&s] { return Station(s); });
  station->add_option("--lcm-url", s.options.lcm_url, "LCM URL to subscribe to (default LCM's)");
  station->add_option("--log", s.log, "replay this LCM log with a timeline instead of live")
      ->check(CLI::ExistingFile);
  station->add_option("--speed", s.options.speed, "log replay speed (default 1)");
  station->add_option("--confidence", s.options.ellipse_confidence, "ellipse confidence (default 0.95)");
  station->add_option("--seconds", s.options.max_seconds, "close after this many seconds (0: never)");
  station->add_option("--close-when-quiet", s.options.close_when_quiet_s,
                      "close this many seconds after the last message (0: never)");
  station->add_flag("--offscreen", s.options.offscreen, "render without showing a window (needs --seconds)");

  ReportArgs& r = registry.Keep(ReportArgs{});
  CLI::App* report = registry.Add("report", "render a run report (index.html and PNGs) from a log",
                                  [&r] { return Report(r); });
  report->add_option("LOG", r.log, "LCM log of the run")->required()->check(CLI::ExistingFile);
  report->add_option("--out", r.out, "output folder")->required();
  report->add_option("--closeup-every-m", r.closeup_every_m, "ellipse close-up spacing (default 10 m)");
  report->add_option("--confidence", r.confidence, "ellipse confidence (default 0.95)");
}

}  // namespace plantscale::app
