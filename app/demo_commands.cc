#include "app/demo_commands.h"

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "app/processes.h"
#include "maps/archive.h"
#include "telemetry/command_auth.h"
#include "ui/display.h"

namespace plantscale::app {
namespace {

struct DemoArgs {
  std::string out = "out/demo";
  std::string preset = "field";
  double length_m = 40.0;
  bool real_time = false;
  std::string lcm_url = "udpm://239.255.76.67:7668?ttl=0";  // a port apart from LCM's default
  std::string origin = "52.0063,-0.4206";  // WGS84 of the field-frame origin for the map exports
  std::string to;  // the season archive; empty: OUT/archive.gpkg
};

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

void AddDemoCommands(CommandRegistry& registry) {
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
