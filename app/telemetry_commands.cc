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
#include "app/config_loader.h"
#include "app/vehicle/runner.h"
#include "app/vehicle/spray_bar_stage.h"
#include "app/vehicle/stages.h"
#include "app/tracking_eval.h"
#include "app/treatment_eval.h"
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
}

void AddCanOption(CLI::App* cmd, PublishArgs& a) {
  cmd->add_option("--can", a.can,
                  "SocketCAN interface of the spray bar (e.g. can0; telemetry/can/PROTOCOL.md), "
                  "not with --fast; simulate also takes 'simulated' (a simulated bar)");
}

SprayBarEndpoint OpenSprayBar(const PublishArgs& args, bool allow_simulated,
                              const telemetry::can::SprayBarOptions& options) {
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
tm::can::SprayBarOptions BarOptionsOfTreatment() {
  tm::can::SprayBarOptions o;
  o.num_nozzles = treatment::TreatmentOptions{}.scheduler.bar.nozzles;
  return o;
}

using SourceFactory =
    std::function<std::unique_ptr<vehicle::FrameSource>(tm::Transport& transport, int64_t boot)>;

// The vehicle process: LCM (and the log) around a runner with its stages;
// the simulator's truth stage only when `sim_truth`. With a calibrated
// camera the vehicle pipeline runs (segmentation, tracking, treatment and
// the bar); without one, segmentation alone for the thumbnails.
struct PipelineSetup {
  const geometry::CameraModel& camera;
  pipeline::PipelineOptions options;
  treatment::NozzleSink nozzle_sink = {};  // a spray bar: every tick's open mask
};

int RunVehicle(const PublishArgs& args, const SourceFactory& make_source, bool sim_truth,
               const std::string& title, const SprayBarEndpoint& endpoint,
               const std::optional<PipelineSetup>& tracker = {},
               const std::string& run_config = {}, VehicleHooks hooks = {}) {
  vehicle::CommandAuthOptions command_auth = VehicleCommandAuth(args.command_key);  // refuses a bad key file
  const int64_t boot = tm::WallUtime();
  tm::LcmTransport lcm(UrlOrDefault(args.lcm_url));
  std::unique_ptr<tm::LogWriter> log;
  std::unique_ptr<tm::LoggingTransport> logged;
  tm::Transport* transport = &lcm;
  const vehicle::VehicleRunner* clock = nullptr;
  if (!args.log.empty()) {
    log = std::make_unique<tm::LogWriter>(args.log);
    logged = std::make_unique<tm::LoggingTransport>(
        lcm, *log, [&clock] { return clock ? clock->now_utime() : tm::WallUtime(); });
    transport = logged.get();
  }
  tm::Publisher publisher(*transport, tm::PublisherOptions{});
  std::unique_ptr<vehicle::FrameSource> source = make_source(*transport, boot);
  vehicle::VehicleRunner runner(publisher, vehicle::RunnerOptions{!args.fast, run_config}, boot);
  clock = &runner;
  runner.ListenForCommands(*transport, std::move(command_auth));  // start, pause and mode from the station
  // The spray bar (--can): with the treatment stage (a calibrated camera)
  // its scheduler drives the bar through the bar's sink every tick; without
  // one the bar stage commands every nozzle closed each frame so the bar
  // stays supervised. The bar stage goes before HealthStage, which reports
  // its fail-safe state and faults; the simulated bar steps after the
  // treatment stage has commanded it.
  tm::can::SprayBar* bar = endpoint.bar.get();
  treatment::NozzleSink nozzle_sink = tracker ? tracker->nozzle_sink : treatment::NozzleSink{};
  if (hooks.nozzle_sink) {
    nozzle_sink = [hook = hooks.nozzle_sink, other = nozzle_sink](int64_t utime, uint64_t mask) {
      if (other) other(utime, mask);
      hook(utime, mask);
    };
  }
  if (bar != nullptr) {
    const bool scheduler_drives_bar = tracker.has_value();
    if (scheduler_drives_bar) {
      const treatment::NozzleSink to_bar = bar->Sink();
      const treatment::NozzleSink other = nozzle_sink;
      nozzle_sink = [to_bar, other](int64_t utime, uint64_t mask) {
        if (other) other(utime, mask);
        to_bar(utime, mask);
      };
    }
    runner.AddStage(std::make_unique<vehicle::SprayBarStage>(*bar, !scheduler_drives_bar));
  }
  runner.AddStage(std::make_unique<vehicle::OdometryStage>());
  const vehicle::BlobView* blobs = nullptr;
  if (tracker) {
    auto stage =
        std::make_unique<vehicle::PipelineStage>(tracker->camera, tracker->options, nozzle_sink);
    blobs = stage.get();
    runner.AddStage(std::move(stage));
  } else {
    auto stage = std::make_unique<vehicle::SegmentationStage>(
        treatment::SegmenterOptionsFor(treatment::TreatmentOptions{}.scheduler.mode));
    blobs = stage.get();
    runner.AddStage(std::move(stage));
  }
  // After every stage that reports faults or the fail-safe state this frame
  // (the runner starts each frame's fault list afresh from the source).
  runner.AddStage(std::make_unique<vehicle::HealthStage>());
  runner.AddStage(std::make_unique<vehicle::ThumbnailStage>(vehicle::ThumbnailOptions{}, blobs));
  if (endpoint.simulated) {
    runner.AddStage(std::make_unique<vehicle::SimulatedBarStage>(*endpoint.simulated));
  }
  if (sim_truth) runner.AddStage(std::make_unique<vehicle::SimTruthStage>());
  for (std::unique_ptr<vehicle::Stage>& stage : hooks.stages) runner.AddStage(std::move(stage));
  g_stop = false;
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  const vehicle::RunSummary s = runner.Run(*source, &g_stop);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  std::cout << title << ", " << s.frames << " frames (" << s.dropped_frames << " dropped) over "
            << std::fixed << std::setprecision(1) << s.seconds << " s on "
            << UrlOrDefault(args.lcm_url) << (g_stop ? " (interrupted)" : "") << '\n';
  PrintPublisherTraffic(publisher, s.seconds);
  if (log) std::cout << "  log               " << args.log << " (" << log->events() << " events)\n";
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
  std::string calibration;       // empty: segmentation alone
  std::string preset = "field";  // the crop and vehicle settings, with a calibration
};

int Run(const RunArgs& a, const GlobalOptions& global) {
  // With a calibration: the whole pipeline, with the crop and vehicle
  // settings of a simulator preset until crop profiles hold them.
  std::optional<sim::SimulatorOptions> settings;
  if (!a.calibration.empty()) {
    settings = LoadSimulatorPresetWithCalibration(a.preset, a.calibration, global.ConfigDir());
  }
  const SprayBarEndpoint bar =
      OpenSprayBar(a.publish, false, BarOptionsOfTreatment());  // before the camera
  std::string title = "plantscale run: camera " + a.camera.camera;
  std::optional<geometry::CameraModel> camera;
  std::optional<PipelineSetup> pipeline;
  if (settings) {
    camera.emplace(settings->camera);
    pipeline.emplace(PipelineSetup{*camera, ProductPipelineOptions(*settings)});
    title += ", calibration " + a.calibration + ", preset " + settings->preset;
  }
  return RunVehicle(
      a.publish,
      [&a](tm::Transport& t, int64_t boot) {
        return std::make_unique<CameraFrameSource>(a.camera, t, boot);
      },
      false, title, bar, pipeline);
}

}  // namespace

int SimulateAndPublish(const sim::SimulatorOptions& options, const PublishArgs& args,
                       const SimRunConfig& run, VehicleHooks hooks) {
  const SprayBarEndpoint bar =
      OpenSprayBar(args, true, BarOptionsOfTreatment());  // before anything else
  sim::Simulator simulator(options);
  return RunVehicle(
      args,
      [&simulator](tm::Transport&, int64_t boot) {
        return std::make_unique<vehicle::SimFrameSource>(simulator, boot);
      },
      true,
      "plantscale simulate --publish: preset " + options.preset + ", seed " +
          std::to_string(options.seed),
      bar, PipelineSetup{simulator.camera(), ProductPipelineOptions(options)}, RunConfigJson(run),
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
  CLI::Option* calibration =
      rc->add_option("--calibration", run.calibration,
                     "the camera's calibration: a YAML file as config/cameras/*.yaml (or a "
                     "camera name there); runs tracking, treatment and the bar");
  rc->add_option("--preset", run.preset,
                 "with --calibration: the crop and vehicle settings (row and plant spacing, "
                 "rows, track width, crop size, the crop's height for the virtual ground "
                 "plane, ...) of this simulator preset (config/presets) or YAML file, for "
                 "now, until crop profiles hold them; its camera is not used")
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
