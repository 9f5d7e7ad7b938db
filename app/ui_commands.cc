#include "app/ui_commands.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <vector>

#include "app/processes.h"
#include "app/report_truth.h"
#include "maps/map_errors.h"
#include "maps/plants_layer.h"
#include "review/log_timeline.h"
#include "telemetry/command_auth.h"
#include "telemetry/gateway/client.h"
#include "ui/display.h"
#include "ui/report.h"
#include "ui/station.h"
#include "ui/station_sources.h"

namespace plantscale::app {
namespace {

struct StationArgs {
  ui::StationOptions options;
  std::string log;
  std::string review;
  std::string connect, token_file, ca;
  std::vector<std::string> press;
};

struct ReportArgs {
  std::string log;
  std::string out;
  double confidence = 0.95;
  double rate_l_ha = 200.0;
  double strip_length_m = 10.0;
  int max_strip_pictures = 4;
  double magnification = 20.0;
  bool json = false;
  std::string config_dir;
};

int NoDisplay(const ui::DisplayError& e) {
  std::cerr << "plantscale: error: " << e.what() << '\n';
  return 2;
}

// A row of an exported plants layer as the station's plant record.
review::PlantRecord PlantRecordOf(const maps::PlantsLayerRow& row) {
  review::PlantRecord r;
  telemetry::PlantObservation& p = r.plant;
  p.id = row.plant_id;
  p.kind = row.kind == "crop"   ? telemetry::PlantKind::kCrop
           : row.kind == "weed" ? telemetry::PlantKind::kWeed
                                : telemetry::PlantKind::kUnknown;
  p.position_m = {row.field_x_m, row.field_y_m};
  p.size_m2 = 3.14159265358979 * row.radius_m * row.radius_m;  // the leaf-tip disc
  p.sprayed = row.treated;
  r.why_text = row.why.empty() ? "no reason recorded" : row.why;
  return r;
}

bool IsGeoPackage(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  char head[16] = {};
  in.read(head, sizeof head);
  return file.extension() == ".gpkg" || std::string(head, 15) == "SQLite format 3";
}

// The run --review opens: an exported GeoPackage's plants, or a log read to
// its end. Throws ReviewInputError naming the file when there is nothing to
// review (no file, an empty log or one of another program, a GeoPackage
// without its plants layer); a log cut mid-event opens with what was read.
struct ReviewInputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void LoadReview(const std::filesystem::path& file, ui::StationOptions& o) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) throw ReviewInputError(file.string() + ": no such file");
  o.review_name = file.filename().string();
  if (IsGeoPackage(file)) {
    auto model = std::make_shared<review::RunModel>();
    try {
      for (const maps::PlantsLayerRow& row : maps::ReadPlantsLayer(file)) model->InsertPlant(PlantRecordOf(row));
    } catch (const maps::MapIoError& e) {
      throw ReviewInputError(e.what());
    }
    o.review_model = model;
    return;
  }
  const review::ReviewRun run = review::LoadReviewRun(file);
  if (run.empty) {
    throw ReviewInputError(file.string() + ": no events to review" + (run.error.empty() ? " (empty log)" : ": " + run.error));
  }
  if (run.model->plantscale_messages() == 0) {
    throw ReviewInputError(file.string() + ": no plantscale messages in " + std::to_string(run.model->messages()) +
                           " events (a log of another program?)");
  }
  o.review_model = run.model, o.review_error = run.error;
}

void PrintTour(const std::vector<double>& ms, double cpu_ms) {
  if (ms.empty()) return;
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  double sum = 0.0;
  for (const double m : ms) sum += m;
  const double mean = sum / static_cast<double>(ms.size());
  std::cout << "station: tour " << ms.size() << " frames: mean " << std::fixed << std::setprecision(1) << mean
            << " ms (" << 1e3 / mean << " fps), median " << sorted[sorted.size() / 2] << " ms, 95th percentile "
            << sorted[sorted.size() * 95 / 100] << " ms, worst " << sorted.back() << " ms; process CPU "
            << cpu_ms / static_cast<double>(ms.size()) << " ms a frame\n";
}

double PeakResidentMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

// Live: how far behind the vehicle the station was (each grid message's
// reception minus its stamp, on this host's clock and the vehicle's), the
// thumbnails received and, over the gateway, the bytes. One line:
// "station: lag: grid 250 messages, p50 182 ms, p95 240 ms, max 410 ms;
// 41 thumbnails; link 812345 bytes, 40213 bytes/s".
void PrintLag(const ui::StationResult& r) {
  std::cout << "station: lag: grid " << r.grid_lag_ms.size() << " messages";
  if (!r.grid_lag_ms.empty()) {
    std::vector<float> sorted = r.grid_lag_ms;
    std::sort(sorted.begin(), sorted.end());
    const auto at = [&](double q) {
      return sorted[std::min(sorted.size() - 1, static_cast<size_t>(q * static_cast<double>(sorted.size())))];
    };
    std::cout << std::fixed << std::setprecision(0) << ", p50 " << at(0.5) << " ms, p95 " << at(0.95)
              << " ms, max " << sorted.back() << " ms";
  }
  std::cout << "; " << r.thumbnails << " thumbnails";
  if (r.link_bytes >= 0) {
    std::cout << "; link " << r.link_bytes << " bytes, " << std::fixed << std::setprecision(0)
              << (r.seconds > 0 ? static_cast<double>(r.link_bytes) / r.seconds : 0.0) << " bytes/s";
  }
  std::cout << '\n';
}

// A bad --connect, --token-file, --ca or --press: one line naming it.
struct StationInputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// --press KEY@SECONDS, sorted by time.
std::vector<std::pair<double, std::string>> ParsePresses(const std::vector<std::string>& presses) {
  std::vector<std::pair<double, std::string>> out;
  for (const std::string& p : presses) {
    const size_t at = p.rfind('@');
    size_t used = 0;
    double s = -1.0;
    try {
      if (at != std::string::npos && at > 0) s = std::stod(p.substr(at + 1), &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (at == std::string::npos || at == 0 || used == 0 || at + 1 + used != p.size() || !(s >= 0.0)) {
      throw StationInputError("--press '" + p + "': expected KEY@SECONDS, e.g. C@3 (the key C 3 s after the start)");
    }
    out.emplace_back(s, p.substr(0, at));
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

// --connect, --token-file and --ca into the gateway client's options.
void ConnectOptions(const StationArgs& a, ui::StationOptions& o) {
  namespace gw = telemetry::gateway;
  if (a.connect.empty()) {
    if (!a.token_file.empty()) throw StationInputError("--token-file: only with --connect");
    if (!a.ca.empty()) throw StationInputError("--ca: only with --connect");
    return;
  }
  if (a.token_file.empty()) {
    throw StationInputError("--token-file: required with --connect (the token `plantscale users add` printed, in a file of mode 0600)");
  }
  gw::GatewayClientOptions g;
  g.url = gw::ParseGatewayUrl(a.connect);
  g.token = gw::ReadTokenFile(a.token_file);
  if (!a.ca.empty()) {
    if (!g.url.tls) throw StationInputError("--ca: only with wss://");
    if (!std::ifstream(a.ca).good()) throw StationInputError("--ca " + a.ca + ": cannot be read");
    g.ca_file = a.ca;
  }
  o.gateway = g;
}

int Station(StationArgs& a) {
  a.options.log = a.log;
  try {
    ConnectOptions(a, a.options);
    a.options.press = ParsePresses(a.press);
  } catch (const StationInputError& e) {
    std::cerr << "plantscale: error: station: " << e.what() << '\n';
    return 2;
  } catch (const telemetry::gateway::GatewayClientError& e) {
    std::cerr << "plantscale: error: station: " << e.what() << '\n';
    return 2;
  }
  if (!a.options.screenshot.empty() || a.options.tour_frames > 0) RerunUnderXvfb();
  try {
    if (!a.review.empty()) LoadReview(a.review, a.options);
    const ui::StationResult r = ui::RunStation(a.options);
    std::cout << "station: " << r.frames << " frames in " << std::fixed << std::setprecision(1)
              << r.seconds << " s (" << r.frames_per_second << " fps), peak resident " << PeakResidentMb()
              << " MB\n";
    PrintTour(r.tour_frame_ms, r.tour_cpu_ms);
    std::cout << "station: link: " << r.link << '\n';
    for (const std::string& l : r.link_changes) std::cout << "station: gateway: " << l << '\n';
    for (const std::string& c : r.command_replies) std::cout << "station: command: " << c << '\n';
    std::cout << "station: model: " << r.messages << " messages, " << r.grid_states << " grid states, " << r.map_tiles
              << " map tiles (" << r.tile_revisions << " revisions), " << r.plants << " plants, " << r.events.size()
              << " events\n";
    for (const std::string& e : r.events) {
      if (e.rfind("command", 0) == 0 || e.rfind("gateway", 0) == 0) std::cout << "station: event: " << e << '\n';
    }
    for (const std::string& p : r.problems) std::cout << "station: problem: " << p << '\n';
    if (a.review.empty() && a.log.empty()) PrintLag(r);
  } catch (const ui::DisplayError& e) {
    return NoDisplay(e);
  } catch (const telemetry::CommandAuthError& e) {
    std::cerr << "plantscale: error: station: --command-key: " << e.what() << '\n';
    return 2;
  } catch (const ReviewInputError& e) {
    std::cerr << "plantscale: error: station --review: " << e.what() << '\n';
    return 2;
  } catch (const telemetry::gateway::GatewayClientError& e) {
    std::cerr << "plantscale: error: station: " << e.what() << '\n';
    return 2;
  } catch (const telemetry::LogError& e) {
    std::cerr << "plantscale: error: station: " << e.what() << '\n';
    return 2;
  }
  return 0;
}

int Report(const ReportArgs& a) {
  RerunUnderXvfb();  // for the camera views at events (VTK); the rest needs no display
  ui::ReportOptions options;
  options.pictures.ellipse_confidence = a.confidence;
  options.pictures.strip_length_m = a.strip_length_m;
  options.pictures.max_strip_pictures = a.max_strip_pictures;
  options.pictures.ellipse_magnification = a.magnification;
  options.agronomy.rate_l_ha = a.rate_l_ha;
  const std::string config_dir = a.config_dir;
  options.truth = [config_dir](const std::string& run_config, const review::StandWindow& stand) {
    return SimulatorTruth(run_config, stand, config_dir);
  };
  const auto start = std::chrono::steady_clock::now();
  const ui::ReportResult r = ui::WriteReport(a.log, a.out, options);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (a.json) {
    std::ifstream in(std::filesystem::path(a.out) / "summary.json", std::ios::binary);
    std::cout << in.rdbuf();
    return 0;
  }
  std::cout << "report: " << r.index.string() << " (" << r.pictures.size() << " pictures, " << std::fixed
            << std::setprecision(2) << r.summary.distance_m << " m, " << s << " s)\n";
  const review::AgronomySummary& g = r.agronomy;
  std::cout << "report: crop " << g.crop << " (" << std::setprecision(2) << g.plants_per_m << "/m), gaps "
            << g.gaps << " (" << g.missing << " missing, longest " << g.longest_gap << "), radius median "
            << std::setprecision(1) << 100 * g.crop_size.median_m << " cm, weeds " << std::setprecision(2)
            << g.weeds_per_m2 << "/m2\n";
  for (const std::string& p : r.problems) std::cout << "report: problem: " << p << '\n';
  return 0;
}

}  // namespace

void AddUiCommands(CommandRegistry& registry) {
  StationArgs& s = registry.Keep(StationArgs{});
  CLI::App* station = registry.Add("station", "operator station window (live LCM, over the gateway, or a log)",
                                   [&s] { return Station(s); });
  station->add_option("--lcm-url", s.options.lcm_url, "LCM URL to subscribe to (default LCM's)");
  station->add_option("--log", s.log, "replay this LCM log with a timeline instead of live")
      ->check(CLI::ExistingFile);
  station->add_option("--review", s.review,
                      "open a finished run whole (an LCM log, or a GeoPackage from plantscale export): "
                      "overview, zoom and pan, pick, measure")
      ->excludes("--log");
  station->add_option("--magnification", s.options.ellipse_magnification,
                      "covariance ellipses drawn this many times their size (key x cycles 1/5/20/50)")
      ->capture_default_str();
  station->add_option("--tour", s.options.tour_frames,
                      "draw this many frames touring the bed (6 m, 40 m, 300 m and whole views, panning), "
                      "print their frame times, and close")
      ->check(CLI::NonNegativeNumber);
  station->footer(ui::StationKeysHelp());
  station->add_option("--speed", s.options.speed, "log replay speed")->capture_default_str();
  station->add_option("--confidence", s.options.ellipse_confidence, "ellipse confidence")
      ->capture_default_str();
  station->add_option("--seconds", s.options.max_seconds, "close after this many seconds (0: never)");
  station->add_option("--close-when-quiet", s.options.close_when_quiet_s,
                      "close this many seconds after the last message (0: never)");
  station->add_flag("--offscreen", s.options.offscreen, "render without showing a window (needs --seconds)");
  station->add_option("--screenshot", s.options.screenshot, "write the window as it closed to this PNG");
  station->add_option("--command-key", s.options.command_key,
                      "sign vehicle commands with this key file (plantscale keygen, mode 0600); without it "
                      "they go unsigned and a vehicle refuses them unless --accept-unsigned-commands");
  station->add_option("--connect", s.connect,
                      "live over the gateway instead of LCM: wss://HOST:PORT (docs/remote.md); reconnects by "
                      "itself")
      ->excludes("--lcm-url")
      ->excludes("--log")
      ->excludes("--review");
  station->add_option("--token-file", s.token_file,
                      "with --connect: the file (mode 0600) holding the token `plantscale users add` printed");
  station->add_option("--ca", s.ca,
                      "with --connect: trust the gateway's certificate (or its CA) in this PEM file (default: the "
                      "system's trusted roots)");
  station->add_option("--press", s.press,
                      "press KEY SECONDS after the start, as KEY@SECONDS (repeatable; e.g. C@3 sends spray the "
                      "crop): a scripted session");

  ReportArgs& r = registry.Keep(ReportArgs{});
  CLI::App* report = registry.Add("report", "render a run report (index.html and PNGs) from a log",
                                  [&r, &registry] {
                                    r.config_dir = registry.global().config_dir;  // the truth's preset
                                    return Report(r);
                                  });
  report->add_option("LOG", r.log, "LCM log of the run")->required()->check(CLI::ExistingFile);
  report->add_option("--out", r.out, "output folder")->required();
  report->add_option("--confidence", r.confidence, "ellipse confidence")->capture_default_str();
  report->add_option("--rate-l-ha", r.rate_l_ha, "product rate on the treated area, L/ha (product used)")
      ->capture_default_str();
  report->add_option("--strip-length-m", r.strip_length_m, "bed strip length")->capture_default_str();
  report->add_option("--max-strip-pictures", r.max_strip_pictures,
                     "bed pictures (5 strips each) at most; a longer run shows the strips that matter")
      ->capture_default_str();
  report->add_option("--magnification", r.magnification, "covariance ellipses drawn this many times their size")
      ->capture_default_str();
  report->add_flag("--json", r.json, "print summary.json (run, agronomy per row, truth, problems) instead of text");
}

}  // namespace plantscale::app
