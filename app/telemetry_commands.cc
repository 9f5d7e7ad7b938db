#include "app/telemetry_commands.h"

#include <atomic>
#include <csignal>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "app/camera_source.h"
#include "app/config/config_loader.h"
#include "app/vehicle/runner.h"
#include "app/vehicle/spray_bar_stage.h"
#include "app/vehicle/stages.h"
#include "evaluation/tracking_eval.h"
#include "evaluation/treatment_eval.h"
#include "telemetry/can/spray_bar.h"
#include "telemetry/log.h"
#include "telemetry/log_stats.h"
#include "telemetry/replay.h"

namespace plantscale::app {
namespace {

namespace tm = plantscale::telemetry;

std::atomic<bool> g_stop{false};
extern "C" void OnSignal(int) { g_stop = true; }

std::string UrlOrDefault(const std::string& url) {
  return url.empty() ? tm::LcmTransportOptions{}.url : url;
}

void PrintPublisherTraffic(const tm::Publisher& publisher, double seconds) {
  std::cout << "  channel                     sent  dropped(rate,budget)  bytes/msg  kbit/s\n";
  double total = 0.0;
  for (const auto& [name, c] : publisher.counters()) {
    const double kbit_s = seconds > 0 ? 8e-3 * static_cast<double>(c.bytes) / seconds : 0.0;
    total += kbit_s;
    std::cout << "  " << std::left << std::setw(26) << name << std::right << std::setw(6) << c.sent
              << std::setw(10) << c.dropped_rate << "," << std::setw(6) << c.dropped_budget
              << std::setw(15) << (c.sent ? c.bytes / c.sent : 0) << std::fixed
              << std::setprecision(1) << std::setw(8) << kbit_s << '\n';
  }
  std::cout << "  total " << std::fixed << std::setprecision(1) << total << " kbit/s over "
            << seconds << " s of run\n";
}

}  // namespace

void AddPublishOptions(CLI::App* cmd, PublishArgs& a) {
  cmd->add_flag("--publish", a.publish,
                "publish telemetry over LCM instead of writing files (vehicle runner)");
  cmd->add_flag("--fast", a.fast, "with --publish: as fast as possible, not in real time");
  cmd->add_option("--lcm-url", a.lcm_url,
                  "with --publish: LCM URL (default udpm://239.255.76.67:7667?ttl=0)");
  cmd->add_option("--log", a.log, "with --publish: also write an LCM log of what is published");
  AddCanOption(cmd, a);
  AddVehicleCommandKeyOptions(cmd, a.command_key);
  AddVehicleGatewayOptions(cmd, a.gateway);
}

void AddCanOption(CLI::App* cmd, PublishArgs& a) {
  cmd->add_option("--can", a.can,
                  "SocketCAN interface of the spray bar (e.g. can0; telemetry/can/PROTOCOL.md), "
                  "not with --fast; simulate also takes 'simulated' (a simulated bar)");
}

SprayBarEndpoint OpenSprayBar(const PublishArgs& args, bool allow_simulated,
                              const telemetry::can::BarLinkOptions& options) {
  namespace can = telemetry::can;
  SprayBarEndpoint e;
  if (args.can.empty()) return e;
  if (args.can == kSimulatedBar) {
    if (!allow_simulated) {
      throw ConfigError("command line", "--can", "'simulated' only with simulate --publish");
    }
    auto [vehicle_end, bar_end] = can::CanFramePipe();
    e.bar = std::make_unique<can::SprayBar>(std::move(vehicle_end), options, kSimulatedBar);
    can::SimulatedBarOptions sim;
    sim.num_nozzles = options.num_nozzles;
    sim.ids = options.ids;
    e.simulated = std::make_unique<can::SimulatedBar>(std::move(bar_end), sim);
    return e;
  }
  if (args.fast) {
    throw ConfigError("command line", "--can",
                      "not with --fast: the spray bar's heartbeat watchdog needs real time");
  }
  e.bar = std::make_unique<can::SprayBar>(can::SprayBar::Open(args.can, options));
  return e;
}

namespace {

// The CAN bar has as many nozzles as the treatment scheduler's bar.
tm::can::BarLinkOptions BarOptionsOfTreatment(int nozzles) {
  tm::can::BarLinkOptions o;
  o.num_nozzles = nozzles;
  return o;
}

using SourceFactory =
    std::function<std::unique_ptr<vehicle::FrameSource>(tm::Transport& transport, int64_t boot)>;
using vehicle::PipelineSetup;

// The vehicle process (app/vehicle/vehicle_process.h) on LCM; the
// simulator's truth stage only when `sim_truth`.
int RunVehicle(const PublishArgs& args, const SourceFactory& make_source, bool sim_truth,
               const std::string& title, const SprayBarEndpoint& endpoint,
               const std::optional<PipelineSetup>& tracker = {},
               const std::string& run_config = {}, VehicleHooks hooks = {}) {
  vehicle::CommandAuthOptions command_auth = VehicleCommandAuth(args.command_key);  // refuses a bad key file
  // The gateway in this process (one process on a small vehicle computer):
  // an LCM instance of its own on the same URL, served on its own thread.
  // Started before the vehicle, so that a bad certificate or users file is
  // refused before a log is opened.
  std::optional<BackgroundGateway> gateway;
  if (!args.gateway.listen.empty()) {
    gateway.emplace(args.gateway, UrlOrDefault(args.lcm_url));
    std::cout << "gateway: " << gateway->address() << " (connect with "
              << gateway->address() << "?token=TOKEN)" << std::endl;
  } else if (!args.gateway.cert.empty() || !args.gateway.key.empty() || !args.gateway.users.empty()) {
    throw ConfigError("command line", "--cert/--key/--users", "only with --gateway HOST:PORT");
  }
  const int64_t boot = tm::WallUtime();
  tm::LcmTransport lcm(UrlOrDefault(args.lcm_url));
  vehicle::VehicleProcessOptions options;
  options.real_time = !args.fast;
  options.log = args.log;
  options.run_config = run_config;
  options.sim_truth = sim_truth;
  vehicle::VehicleProcess process(lcm, options, boot);
  std::unique_ptr<vehicle::FrameSource> source = make_source(process.transport(), boot);
  process.ListenForCommands(std::move(command_auth));  // start, pause and mode from the station
  process.AddStages(endpoint, tracker, std::move(hooks));
  g_stop = false;
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  // A file size limit (ulimit -f) is a full disk to the log: its write
  // fails and the vehicle goes on (docs/faults.md), not killed by SIGXFSZ.
  std::signal(SIGXFSZ, SIG_IGN);
  const vehicle::RunSummary s = process.Run(*source, &g_stop);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  if (gateway) std::cout << "gateway: stopped; " << GatewayStatsText(gateway->Stop()) << '\n';
  std::cout << title << ", " << s.frames << " frames (" << s.dropped_frames << " dropped) over "
            << std::fixed << std::setprecision(1) << s.seconds << " s on "
            << UrlOrDefault(args.lcm_url) << (g_stop ? " (interrupted)" : "") << '\n';
  PrintPublisherTraffic(process.publisher(), s.seconds);
  if (const tm::LogWriter* log = process.log()) {
    std::cout << "  log               " << args.log << " (" << log->events() << " events)\n";
    const tm::LogStatus& ls = process.logging()->status();
    if (ls.failures > 0) {
      std::cout << "    " << ls.not_logged << " messages not logged after " << ls.failures
                << " write failure(s), last: " << ls.error << '\n';
    }
  }
  tm::can::SprayBar* bar = endpoint.bar.get();
  if (bar != nullptr) {
    const tm::can::SprayBarStatus& b = bar->status();
    std::cout << "  spray bar         " << bar->endpoint() << ": " << b.commands_sent
              << " commands, " << b.acks << " acks, " << b.heartbeats << " heartbeats, "
              << b.frames_rejected << " frames rejected, " << b.sequence_gaps << " sequence gaps"
              << (b.failsafe ? ", fail-safe" : "") << '\n';
    for (const std::string& line : bar->HealthFaults()) std::cout << "    " << line << '\n';
  }
  if (endpoint.simulated) {
    std::cout << "  simulated bar     " << endpoint.simulated->commands().size()
              << " commands received, " << endpoint.simulated->history().size()
              << " valve changes, " << endpoint.simulated->errors().size() << " bad frames\n";
  }
  return 0;
}

struct RunArgs {
  PublishArgs publish;
  CameraSourceOptions camera;
  std::string calibration;       // the vehicle's camera instead of its own calibration
  std::string preset = "field";  // the crop and vehicle profiles of this preset, by name
  std::string crop;              // crop profile (config/crops or a file)
  std::string segmenter_model;   // --segmenter-model (overrides the crop profile's)
  std::string vehicle;           // vehicle profile (config/vehicles or a file)
};

int Run(const RunArgs& a, const GlobalOptions& global) {
  // With a vehicle profile or a calibration: the whole pipeline, configured
  // from the crop and vehicle profiles (--crop, --vehicle; else those named
  // for --preset's nominal crop and vehicle) and, when given, the
  // calibration in place of the vehicle's own.
  std::optional<Profiles> profiles;
  if (!a.segmenter_model.empty() && a.calibration.empty() && a.vehicle.empty() && a.crop.empty()) {
    throw ConfigError("command line", "--segmenter-model",
                      "only with the whole pipeline (--crop, --vehicle or --calibration)");
  }
  if (!a.calibration.empty() || !a.vehicle.empty() || !a.crop.empty()) {
    const std::filesystem::path dir = global.ConfigDir();
    if (a.crop.empty() || a.vehicle.empty()) {
      ResolveConfigFile(a.preset, dir / "presets", "preset");  // names an unknown preset
    }
    profiles = LoadProfiles(a.crop, a.vehicle, std::filesystem::path(a.preset).stem().string(), dir);
    ProfileArgs model;
    model.segmenter_model = a.segmenter_model;
    ApplySegmenterModelArg(model, dir, *profiles);
    if (!a.calibration.empty()) {
      const std::string file = ResolveConfigFile(a.calibration, dir / "cameras", "camera").string();
      const geometry::CameraOptions calibration = LoadCamera(a.calibration, dir);
      if (!a.vehicle.empty()) RequireSameCamera(profiles->vehicle, calibration, file);
      profiles->vehicle.camera = calibration;
      profiles->vehicle.calibration_file = file;
    }
    PrintProfileWarnings(*profiles, std::cerr);
  }
  const SprayBarEndpoint bar = OpenSprayBar(
      a.publish, false,
      BarOptionsOfTreatment(profiles ? profiles->vehicle.bar.nozzles
                                     : treatment::SprayBarOptions{}.nozzles));  // before the camera
  std::string title = "plantscale run: camera " + a.camera.camera;
  std::optional<geometry::CameraModel> camera;
  std::optional<PipelineSetup> pipeline;
  if (profiles) {
    camera.emplace(EngineCamera(*profiles));
    pipeline.emplace(PipelineSetup{*camera, ProductPipelineOptions(*profiles)});
    if (!a.calibration.empty()) title += ", calibration " + a.calibration;
    title += ", crop " + profiles->crop.name + ", vehicle " + profiles->vehicle.name;
    if (a.crop.empty() || a.vehicle.empty()) {
      title += ", preset " + std::filesystem::path(a.preset).stem().string();
    }
  }
  return RunVehicle(
      a.publish,
      [&a](tm::Transport& t, int64_t boot) {
        return std::make_unique<CameraFrameSource>(a.camera, t, boot);
      },
      false, title, bar, pipeline);
}

}  // namespace

int SimulateAndPublish(const sim::SimulatorOptions& options, const Profiles& profiles,
                       const PublishArgs& args, const SimRunConfig& run, VehicleHooks hooks) {
  RequireImageSize(profiles.vehicle, options.camera.image_width_px, options.camera.image_height_px);
  const SprayBarEndpoint bar = OpenSprayBar(
      args, true, BarOptionsOfTreatment(profiles.vehicle.bar.nozzles));  // before anything else
  sim::Simulator simulator(options);
  const geometry::CameraModel engine_camera(EngineCamera(profiles));  // not the simulator's
  return RunVehicle(
      args,
      [&simulator](tm::Transport&, int64_t boot) {
        return std::make_unique<vehicle::SimFrameSource>(simulator, boot);
      },
      true,
      "plantscale simulate --publish: preset " + options.preset + ", seed " +
          std::to_string(options.seed) + ", crop " + profiles.crop.name + ", vehicle " +
          profiles.vehicle.name,
      bar, PipelineSetup{engine_camera, ProductPipelineOptions(profiles)}, RunConfigJson(run),
      std::move(hooks));
}

namespace {

struct ReplayArgs {
  std::string log;
  tm::ReplayOptions options;
  std::string lcm_url;
};

int ReportLogError(const std::string& error) {
  if (error.empty()) return 0;
  std::cerr << "plantscale: error: " << error << '\n';
  return 2;
}

int RunReplay(const ReplayArgs& a) {
  tm::LcmTransport lcm(UrlOrDefault(a.lcm_url));
  const tm::ReplaySummary s = tm::Replay(a.log, lcm, a.options);
  std::cout << "plantscale replay: " << s.published << " of " << s.events_read
            << " events republished, " << std::fixed << std::setprecision(2) << s.log_seconds
            << " s of log in " << s.wall_seconds << " s\n";
  return ReportLogError(s.error);
}

nlohmann::json TrafficJson(const tm::LogTraffic& t) {
  nlohmann::json channels = nlohmann::json::object();
  for (const auto& [name, c] : t.channels) {
    channels[name] = {{"messages", c.messages},
                      {"rate_hz", c.rate_hz},
                      {"kbit_s", c.kbit_s},
                      {"bytes_per_message", c.messages ? c.bytes / c.messages : 0},
                      {"max_bytes", c.max_bytes}};
  }
  nlohmann::json j = {{"channels", channels},
                      {"total_kbit_s", t.total_kbit_s},
                      {"events", t.events},
                      {"duration_s", t.duration_s}};
  if (!t.error.empty()) j["error"] = t.error;
  return j;
}

int TelemetryStats(const std::string& log, bool json) {
  const tm::LogTraffic t = tm::MeasureLog(log);
  if (json) {
    std::cout << TrafficJson(t).dump(2) << '\n';
    return ReportLogError(t.error);
  }
  std::cout << std::left << std::setw(28) << "channel" << std::right << std::setw(9) << "messages"
            << std::setw(9) << "rate_hz" << std::setw(10) << "bytes/msg" << std::setw(9)
            << "kbit_s\n";
  for (const auto& [name, c] : t.channels) {
    std::cout << std::left << std::setw(28) << name << std::right << std::setw(9) << c.messages
              << std::fixed << std::setprecision(2) << std::setw(9) << c.rate_hz << std::setw(10)
              << (c.messages ? c.bytes / c.messages : 0) << std::setw(9) << c.kbit_s << '\n';
  }
  std::cout << "total " << t.total_kbit_s << " kbit/s over " << t.duration_s << " s, " << t.events
            << " events\n";
  return ReportLogError(t.error);
}

}  // namespace

void AddTelemetryCommands(CommandRegistry& registry) {
  RunArgs& run = registry.Keep(RunArgs{});
  const GlobalOptions& global = registry.global();
  CLI::App* rc = registry.Add(
      "run",
      "the vehicle process on a real camera (V4L2 device or image folder) and LCM odometry: "
      "with --calibration the whole pipeline (tracking, treatment and the spray bar), "
      "without it segmentation alone",
      [&run, &global] { return Run(run, global); });
  rc->add_option("--camera", run.camera.camera, "/dev/videoN, N, or a folder of images")
      ->required();
  rc->add_option("--crop", run.crop,
                 "crop profile (config/crops name or YAML file, docs/profiles.md); runs tracking, "
                 "treatment and the bar (default: --preset's nominal crop)");
  rc->add_option("--vehicle", run.vehicle,
                 "vehicle profile (config/vehicles name or YAML file: track width, calibration, "
                 "valve latency, nozzles, suspension); runs tracking, treatment and the bar "
                 "(default: --preset's vehicle)");
  rc->add_option("--segmenter-model", run.segmenter_model,
                 "the grower's learned crop/weed model (config/models name or .onnx file) instead "
                 "of the crop profile's; \"none\": the grid's rule alone");
  CLI::Option* calibration =
      rc->add_option("--calibration", run.calibration,
                     "the camera's calibration: a YAML file as config/cameras/*.yaml (or a "
                     "camera name there) in place of the vehicle profile's; runs tracking, "
                     "treatment and the bar");
  rc->add_option("--preset", run.preset,
                 "with --calibration: the crop and vehicle profiles named for this simulator "
                 "preset's nominal crop and vehicle (field: cauliflower-6-week, silsoe), when "
                 "--crop or --vehicle is not given; none of its parameters is used")
      ->capture_default_str()
      ->needs(calibration);
  rc->add_option("--frame-rate", run.camera.folder_frame_rate_hz,
                 "frame rate of a folder of images without --frame-times, Hz")
      ->capture_default_str();
  rc->add_option("--frame-times", run.camera.frame_times,
                 "folder: CSV of the images' capture times, one row per image in name order, "
                 "columns utime (us from the start) and frame (index), as simulate --out's "
                 "truth/frames.csv (needs its --every 1)");
  rc->add_option("--odometry", run.camera.odometry,
                 "folder: CSV of wheel odometry instead of LCM input, columns utime (us, the "
                 "frame times' clock), left_m_s, right_m_s (measured ground speeds), as "
                 "simulate --out's truth/odometry.csv");
  rc->add_flag("--fast", run.publish.fast, "folder of images: as fast as possible");
  rc->add_option("--lcm-url", run.publish.lcm_url,
                 "LCM URL (default udpm://239.255.76.67:7667?ttl=0)");
  rc->add_option("--log", run.publish.log, "also write an LCM log of what is published");
  AddCanOption(rc, run.publish);
  AddVehicleCommandKeyOptions(rc, run.publish.command_key);
  AddVehicleGatewayOptions(rc, run.publish.gateway);

  ReplayArgs& replay = registry.Keep(ReplayArgs{});
  CLI::App* r = registry.Add("replay", "republish an LCM log with its original timing",
                             [&replay] { return RunReplay(replay); });
  r->add_option("LOG", replay.log, "LCM log file")->required();
  r->add_option("--speed", replay.options.speed, "playback speed factor")->capture_default_str();
  r->add_option("--start", replay.options.start_s, "skip this many seconds of the log")
      ->capture_default_str();
  r->add_option("--channels", replay.options.channels, "regex of channels to republish")
      ->capture_default_str();
  r->add_option("--lcm-url", replay.lcm_url, "LCM URL (default udpm://239.255.76.67:7667?ttl=0)");

  std::string& stats_log = registry.Keep(std::string{});
  bool& stats_json = registry.Keep(false);
  CLI::App* s =
      registry.Add("telemetry-stats", "per-channel messages, rate and bandwidth of an LCM log",
                   [&stats_log, &stats_json] { return TelemetryStats(stats_log, stats_json); });
  s->add_option("LOG", stats_log, "LCM log file")->required();
  s->add_flag("--json", stats_json,
              "JSON: channels.<name>.{messages, rate_hz, kbit_s}, total_kbit_s");
}

}  // namespace plantscale::app
