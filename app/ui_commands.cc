#include "app/ui_commands.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

extern char** environ;

#include "app/config/config_loader.h"
#include "app/config/run_config.h"
#include "engine/sim/simulator.h"
#include "maps/archive.h"
#include "maps/map_errors.h"
#include "maps/plants_layer.h"
#include "telemetry/command_auth.h"
#include "telemetry/gateway/client.h"
#include "ui/canvas.h"
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

bool OnPath(const std::string& program) {
  return std::system(("command -v " + program + " >/dev/null 2>&1").c_str()) == 0;
}

// Without DISPLAY, runs this very command again under its own virtual X
// server (`xvfb-run -a`, as demo does) when xvfb-run is installed; returns
// only when that is not possible (then the caller goes on without one).
void RerunUnderXvfb() {
  if (ui::DisplayAvailable() || std::getenv("PLANTSCALE_XVFB") != nullptr || !OnPath("xvfb-run")) return;
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  const std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::string> args{"xvfb-run", "-a", "-s", "-screen 0 1280x1024x24 -noreset"};
  args.push_back(std::filesystem::read_symlink("/proc/self/exe").string());
  size_t at = raw.find('\0');  // skip argv[0]: the path of this executable instead
  while (at != std::string::npos && at + 1 < raw.size()) {
    const size_t end = raw.find('\0', at + 1);
    args.push_back(raw.substr(at + 1, end - at - 1));
    at = end;
  }
  std::vector<char*> argv;
  for (std::string& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);
  setenv("PLANTSCALE_XVFB", "1", 1);
  std::cout.flush();
  execvp(argv[0], argv.data());
}

// The shift (rows, metres along) that takes the report's bed frame (y from
// where the tracker started) to the simulated field's: the one under which
// most crop records have a true crop within 6 cm. The pattern of missing
// plants and the spacing drift make it unique.
std::pair<int, double> RegisterOnField(const ui::StandWindow& stand, const sim::Field& field) {
  std::map<int, std::vector<double>> rows;  // true crop y by row
  for (const sim::Plant& p : field.plants()) {
    if (p.cls == sim::PlantClass::kCrop) rows[p.row].push_back(p.position_m.y());
  }
  for (auto& [n, ys] : rows) std::sort(ys.begin(), ys.end());
  std::vector<std::pair<int, double>> records;  // row, y; at most 400 spread over the run
  const size_t step = std::max<size_t>(1, stand.crops_m.size() / 400);
  for (size_t i = 0; i < stand.crops_m.size(); i += step) {
    records.emplace_back(static_cast<int>(std::lround(stand.crops_m[i].first / stand.row_spacing_m)),
                         stand.crops_m[i].second);
  }
  const auto matches = [&](int dr, double dy) {
    int n = 0;
    for (const auto& [row, y] : records) {
      const auto it = rows.find(row + dr);
      if (it == rows.end()) continue;
      const auto at = std::lower_bound(it->second.begin(), it->second.end(), y + dy - 0.06);
      n += at != it->second.end() && *at <= y + dy + 0.06;
    }
    return n;
  };
  std::pair<int, double> best{0, 0.0};
  int best_n = -1;
  for (int dr = -1; dr <= 1; ++dr) {
    for (int k = -1000; k <= 1000; ++k) {  // ±10 m in 1 cm steps
      const int n = matches(dr, 0.01 * k);
      if (n > best_n) best_n = n, best = {dr, 0.01 * k};
    }
  }
  return best;
}

// Simulator truth over the report's stand, from the log's run_config event:
// the simulated field rebuilt (app/config/run_config.h), registered on the crop
// records, and its plants counted in the same rows and along the same stand.
std::optional<ui::AgronomyTruth> SimTruth(const std::string& run_config, const ui::StandWindow& stand,
                                          const std::string& config_dir_option) {
  const SimRunConfig run = ParseRunConfig(run_config, "run_config event");
  std::filesystem::path dir = config_dir_option;
  std::error_code ec;
  if (dir.empty()) dir = !run.config_dir.empty() && std::filesystem::is_directory(run.config_dir, ec)
                             ? std::filesystem::path(run.config_dir) : DefaultConfigDir();
  const sim::Simulator simulator(SimulatorOptionsOf(run, dir));
  const sim::Field& field = simulator.field();
  const auto [dr, dy] = RegisterOnField(stand, field);
  const double spacing = field.options().plant_spacing_m;
  const double y0 = stand.y0_m + dy - 0.25 * spacing, y1 = stand.y1_m + dy + 0.25 * spacing;
  const int first_row = stand.first_row + dr, last_row = stand.last_row + dr;
  ui::AgronomyTruth t;
  std::ostringstream source;
  source << "simulator: preset " << run.preset << ", seed " << run.seed << ", " << run.length_m
         << " m; the bed frame registered on the field at " << std::showpos << dr << " rows, " << std::fixed
         << std::setprecision(2) << dy << " m";
  t.source = source.str();
  std::set<std::pair<int, int>> present;  // row, line
  std::vector<double> radii, weed_radii;
  const double x_lo = (first_row - 0.5) * stand.row_spacing_m, x_hi = (last_row + 0.5) * stand.row_spacing_m;
  for (const sim::Plant& p : field.plants()) {
    const double x = p.position_m.x(), y = p.position_m.y();
    if (p.cls == sim::PlantClass::kCrop) {
      if (p.row < first_row || p.row > last_row || y < y0 || y > y1) continue;
      ++t.crop;
      radii.push_back(p.radius_m);
      present.insert({p.row, p.line});
    } else if (x >= x_lo && x <= x_hi && y >= stand.y0_m + dy && y <= stand.y1_m + dy) {
      ++t.weeds;
      // The outline r(θ) = R (1 − d + d |cos(kθ/2)|) (sim/plant_shape.cc)
      // encloses π R² ((1 − d)² + (4/π)(1 − d) d + d²/2).
      const double d = p.lobes > 0 ? p.lobe_depth : 0.0;
      weed_radii.push_back(p.radius_m * std::sqrt((1 - d) * (1 - d) + 4 / std::numbers::pi * (1 - d) * d + d * d / 2));
    }
  }
  const std::vector<double>& lines = field.line_y_m();
  for (int row = first_row; row <= last_row; ++row) {
    bool in_gap = false;
    for (size_t line = 0; line < lines.size(); ++line) {
      if (lines[line] < y0 || lines[line] > y1) continue;
      const bool missing = !present.count({row, static_cast<int>(line)});
      t.missing += missing;
      t.gaps += missing && !in_gap;
      in_gap = missing;
    }
  }
  const auto median = [](std::vector<double>& v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  };
  t.median_radius_m = median(radii);
  t.median_weed_radius_m = median(weed_radii);
  const double area = (x_hi - x_lo) * (stand.y1_m - stand.y0_m);
  t.weeds_per_m2 = area > 0.0 ? t.weeds / area : 0.0;
  return t;
}

// A row of an exported plants layer as the station's plant record.
ui::PlantRecord PlantRecordOf(const maps::PlantsLayerRow& row) {
  ui::PlantRecord r;
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
    auto model = std::make_shared<ui::RunModel>();
    try {
      for (const maps::PlantsLayerRow& row : maps::ReadPlantsLayer(file)) model->InsertPlant(PlantRecordOf(row));
    } catch (const maps::MapIoError& e) {
      throw ReviewInputError(e.what());
    }
    o.review_model = model;
    return;
  }
  const ui::ReviewRun run = ui::LoadReviewRun(file);
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
  options.truth = [config_dir](const std::string& run_config, const ui::StandWindow& stand) {
    return SimTruth(run_config, stand, config_dir);
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
  const ui::AgronomySummary& g = r.agronomy;
  std::cout << "report: crop " << g.crop << " (" << std::setprecision(2) << g.plants_per_m << "/m), gaps "
            << g.gaps << " (" << g.missing << " missing, longest " << g.longest_gap << "), radius median "
            << std::setprecision(1) << 100 * g.crop_size.median_m << " cm, weeds " << std::setprecision(2)
            << g.weeds_per_m2 << "/m2\n";
  for (const std::string& p : r.problems) std::cout << "report: problem: " << p << '\n';
  return 0;
}

struct DemoArgs {
  std::string out = "out/demo";
  std::string preset = "field";
  double length_m = 40.0;
  bool real_time = false;
  std::string lcm_url = "udpm://239.255.76.67:7668?ttl=0";  // a port apart from LCM's default
  std::string origin = "52.0063,-0.4206";  // WGS84 of the field-frame origin for the map exports
  std::string to;  // the season archive; empty: OUT/archive.gpkg
};

// Starts `args` (args[0] looked up on PATH); returns the child's pid, or -1.
pid_t Spawn(const std::vector<std::string>& args, const std::filesystem::path& output) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = -1;
  const int error = posix_spawnp(&pid, argv[0], &files, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  return error == 0 ? pid : -1;
}

int Wait(pid_t pid) {
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// The run into the demo's own season archive (a GeoPackage under the demo's
// folder by default, PostGIS when `to` names a server), as field "demo".
int ArchiveDemoRun(const DemoArgs& a, const std::string& self, const std::filesystem::path& log,
                   const std::filesystem::path& out) {
  const std::string to = a.to.empty() ? (out / "archive.gpkg").string() : a.to;
  const int status = Wait(Spawn({self, "export", log.string(), "--to", to, "--field", "demo", "--bed", "1",
                                 "--origin", a.origin, "--heading", "0", "--quiet"},
                                out / "archive.txt"));
  std::cout << "demo: archive         "
            << (status == 0 ? maps::Redacted(to) + "  (field 'demo'; plantscale archive query --to " +
                                  maps::Redacted(to) + " --field demo)"
                            : "not written, see " + (out / "archive.txt").string())
            << '\n';
  return status;
}

// Without a display the whole demo runs again under one `xvfb-run -a` (one
// virtual X server for the station and the report: separate xvfb-run -a
// calls race for display numbers). Returns only when that is not possible.
void ReexecUnderXvfb(const std::string& self, const DemoArgs& a) {
  if (ui::DisplayAvailable() || !OnPath("xvfb-run")) return;
  // -noreset: the server must not reset between the station and the report.
  std::vector<std::string> args{"xvfb-run", "-a", "-s", "-screen 0 1280x1024x24 -noreset", self, "demo-system", "--out", a.out, "--preset", a.preset,
                                "--length-m", std::to_string(a.length_m), "--lcm-url", a.lcm_url,
                                "--origin", a.origin};
  if (a.real_time) args.push_back("--real-time");
  std::vector<char*> argv;
  for (std::string& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);
  setenv("PLANTSCALE_DEMO_XVFB", "1", 1);  // tells the re-run its display is virtual
  execvp(argv[0], argv.data());
}

// The whole system on the simulator: the vehicle process publishing over
// LCM and logging, the station subscribing (a window with DISPLAY, else
// off-screen under xvfb-run), then the report of the log.
int DemoSystem(const DemoArgs& a) {
  namespace fs = std::filesystem;
  if (a.lcm_url.rfind("memq://", 0) == 0) {
    std::cerr << "plantscale: error: demo: --lcm-url " << a.lcm_url
              << " cannot work: memq:// stays inside one process, and the demo runs the vehicle and the station"
                 " as separate processes; use a udpm:// URL\n";
    return 2;
  }
  const fs::path out = a.out, log = out / "run.lcmlog";
  fs::create_directories(out);
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  ReexecUnderXvfb(self, a);
  const bool can_render = ui::DisplayAvailable();
  // A key for this demo only: the station signs its commands with it and
  // the vehicle obeys only those (removed when the demo ends).
  const fs::path key = out / "command.key";
  fs::remove(key);  // left by an interrupted demo
  telemetry::WriteNewCommandKey(key);
  struct RemoveKey {
    fs::path file;
    ~RemoveKey() {
      std::error_code ignored;
      fs::remove(file, ignored);
    }
  } remove_key{key};
  // The station shows a window when there is a real display, else renders off-screen.
  const bool virtual_display = std::getenv("PLANTSCALE_DEMO_XVFB") != nullptr;
  std::vector<std::string> station{"station",  "--lcm-url", a.lcm_url, "--close-when-quiet", "3", "--seconds", "900",
                                   "--screenshot", (out / "station.png").string(), "--command-key", key.string()};
  if (virtual_display) station.push_back("--offscreen");
  station.insert(station.begin(), self);
  const pid_t station_pid = can_render ? Spawn(station, out / "station.txt") : -1;
  std::this_thread::sleep_for(std::chrono::seconds(can_render ? 2 : 0));  // let it subscribe
  std::vector<std::string> vehicle{self, "simulate", "--preset", a.preset, "--length-m", std::to_string(a.length_m),
                                   "--publish", "--lcm-url", a.lcm_url, "--log", log.string(),
                                   "--command-key", key.string()};
  if (!a.real_time) vehicle.push_back("--fast");
  std::cout << "demo: vehicle publishing on " << a.lcm_url << (a.real_time ? "" : " (as fast as it can)") << "...\n";
  const int vehicle_status = Wait(Spawn(vehicle, out / "vehicle.txt"));
  const int station_status = Wait(station_pid);
  if (vehicle_status != 0) {
    std::cerr << "plantscale: error: demo: the vehicle process exited " << vehicle_status << "; see "
              << (out / "vehicle.txt").string() << '\n';
    return 1;
  }
  const int report_status =
      can_render ? Wait(Spawn({self, "report", log.string(), "--out", (out / "report").string()}, out / "report.txt"))
                 : -1;
  std::cout << "demo: vehicle log     " << log.string() << "  (vehicle output " << (out / "vehicle.txt").string()
            << ")\n";
  std::cout << "demo: station         " << (station_pid < 0 ? "not run (no display and no xvfb-run)"
                                            : "exit " + std::to_string(station_status) + ", output " +
                                                  (out / "station.txt").string())
            << '\n';
  std::cout << "demo: report          " << (report_status == 0 ? (out / "report" / "index.html").string()
                                                              : "failed, see " + (out / "report.txt").string())
            << '\n';
  // The maps of the run from its log, anchored at a demonstration field
  // (Silsoe, Bedfordshire, where the thesis's trials were run).
  const int maps_status = Wait(Spawn({self, "export", log.string(), "--out", (out / "maps").string(), "--origin",
                                      a.origin, "--heading", "0", "--quiet"},
                                     out / "maps.txt"));
  std::cout << "demo: maps            "
            << (maps_status == 0 ? (out / "maps").string() + "/  (GeoTIFF, GeoPackage, GeoJSON, CSV, PNG, ISOXML)"
                                 : "not written, see " + (out / "maps.txt").string())
            << '\n';
  const int archive_status = ArchiveDemoRun(a, self, log, out);
  return report_status == 0 && station_status == 0 && maps_status == 0 && archive_status == 0 ? 0 : 1;
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


  // `demo` (what ./plantscale.sh demo runs) and `demo-system` are the same command.
  for (const char* name : {"demo", "demo-system"}) {
    DemoArgs& d = registry.Keep(DemoArgs{});
    CLI::App* demo = registry.Add(name,
                                  "the whole system on the simulator: vehicle over LCM, station, log, report",
                                  [&d] { return DemoSystem(d); });
    demo->add_option("--out", d.out, "output folder")->capture_default_str();
    demo->add_option("--preset", d.preset, "simulator preset")->capture_default_str();
    demo->add_option("--length-m", d.length_m, "distance to drive, metres")->capture_default_str();
    demo->add_flag("--real-time", d.real_time, "drive in real time (default: as fast as possible)");
    demo->add_option("--lcm-url", d.lcm_url, "LCM URL")->capture_default_str();
    demo->add_option("--origin", d.origin, "WGS84 LAT,LON of the field origin for the maps")->capture_default_str();
    demo->add_option("--to", d.to, "season archive of the run: postgresql://… or FILE.gpkg (default OUT/archive.gpkg)");
  }
}

}  // namespace plantscale::app
