#include "evaluation/fault_injection.h"

#include <linux/can.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <stdexcept>

#include "app/config/config_loader.h"
#include "app/config/profiles.h"
#include "app/vehicle/vehicle_process.h"
#include "engine/sim/simulator.h"
#include "evaluation/treatment_eval.h"
#include "telemetry/can/simulated_bar.h"
#include "telemetry/can/spray_bar.h"
#include "telemetry/channels.h"
#include "telemetry/transport.h"

namespace plantscale::faults {
namespace {

namespace can = telemetry::can;
namespace channels = telemetry::channels;
using telemetry::ReceivedMessage;
using telemetry::Transport;
using vehicle::VehicleFrame;

// LCM with a link that can go down: publish throws as LcmTransport does when
// lcm_publish fails. Records every message it is handed.
class FaultyTransport : public Transport {
 public:
  explicit FaultyTransport(Transport& inner, std::vector<Published>& published)
      : inner_(inner), published_(published) {}
  void Publish(const std::string& channel, const void* data, size_t size) override {
    const auto* b = static_cast<const uint8_t*>(data);
    published_.push_back({channel, telemetry::Bytes(b, b + size)});
    if (link_down) {
      throw telemetry::TransportError("LCM URL 'memq://': publish on " + channel + " failed (" +
                                      std::to_string(size) + " bytes)");
    }
    inner_.Publish(channel, data, size);
  }
  void Subscribe(const std::string& regex, Handler handler) override {
    inner_.Subscribe(regex, std::move(handler));
  }
  bool Handle(int timeout_ms) override { return inner_.Handle(timeout_ms); }
  bool link_down = false;

 private:
  Transport& inner_;
  std::vector<Published>& published_;
};

// The bar's socket as the vehicle sees it, swapped under the SprayBar.
class CanSocketSwap {
 public:
  explicit CanSocketSwap(int fd) : fd_(fd), saved_(::dup(fd)) {
    if (saved_.get() < 0) throw std::runtime_error("dup of the bar's socket failed");
  }
  // A socket whose send queue is full and that never receives.
  void Break() {
    auto [full, peer] = can::CanFramePipe();
    can_frame frame{};
    frame.can_id = 0x7FF;
    for (int i = 0; i < 1'000'000 && ::write(full.get(), &frame, sizeof frame) > 0; ++i) {
    }
    full_ = std::move(full);
    peer_ = std::move(peer);
    if (::dup2(full_.get(), fd_) < 0) throw std::runtime_error("dup2 onto the bar's socket failed");
  }
  void Restore() {
    if (::dup2(saved_.get(), fd_) < 0) throw std::runtime_error("dup2 back failed");
  }

 private:
  int fd_;
  can::UniqueFd saved_, full_, peer_;
};

// The disk fills: the process may write no file beyond the log's size
// (plus a part of an event, cut back by the log).
class FileSizeLimit {
 public:
  FileSizeLimit() {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, SIG_IGN);  // as the vehicle process does
  }
  ~FileSizeLimit() { Lift(); }
  void Impose(const std::string& path) {
    rlimit r = saved_;
    r.rlim_cur = std::filesystem::file_size(path) + 100;  // room for part of an event
    ::setrlimit(RLIMIT_FSIZE, &r);
  }
  void Lift() { ::setrlimit(RLIMIT_FSIZE, &saved_); }

 private:
  rlimit saved_{};
};

bool IsFrameFault(FaultKind k) { return k == FaultKind::kCameraStops || k == FaultKind::kCorruptFrame; }
bool IsOdometryFault(FaultKind k) {
  return k == FaultKind::kNanOdometry || k == FaultKind::kSpikeOdometry ||
         k == FaultKind::kSpikeWithinLimit || k == FaultKind::kSlipBurst;
}

// The schedule's clock and the parts it breaks.
struct Injector {
  Fault fault;
  FaultyTransport* transport = nullptr;
  CanSocketSwap* can = nullptr;
  can::SimulatedBar* bar = nullptr;
  FileSizeLimit* disk = nullptr;
  std::string log;
  FaultRunResult* result = nullptr;
  int64_t start = -1;
  bool active = false;
  int hits = 0;  // frames or samples changed

  bool In(int64_t utime) const {
    const double t = 1e-6 * static_cast<double>(utime - start);
    return t >= fault.start_s && t < fault.end_s;
  }
  void Onset(int64_t utime) {
    if (result->onset_utime < 0) result->onset_utime = utime;
  }
  void Switch(bool on) {
    switch (fault.kind) {
      case FaultKind::kCanWriteErrors: on ? can->Break() : can->Restore(); break;
      case FaultKind::kBarSilent: bar->SetSilent(on); break;
      case FaultKind::kStationLinkDown: transport->link_down = on; break;
      case FaultKind::kDiskFull: on ? disk->Impose(log) : disk->Lift(); break;
      default: break;
    }
  }
  void Frame(VehicleFrame& frame) {
    if (start < 0) start = frame.utime;
    const bool in = In(frame.utime);
    if (in != active) {
      if (in) result->published_at_injection = result->published.size();
      const bool switched = !IsFrameFault(fault.kind) && !IsOdometryFault(fault.kind);
      result->broken_part = switched;
      if (in && switched) Onset(frame.utime);
      if (!in && switched && result->clear_utime < 0) result->clear_utime = frame.utime;
      Switch(in);
      active = in;
    }
    const bool hit = in && IsFrameFault(fault.kind) &&
                     (fault.kind != FaultKind::kCorruptFrame || hits == 0);  // one corrupt frame
    if (hit) {
      ++hits;
      Onset(frame.utime);
      if (fault.kind == FaultKind::kCameraStops) frame.image = cv::Mat();
      if (fault.kind == FaultKind::kCorruptFrame) {
        frame.image = frame.image.rowRange(0, frame.image.rows / 2).clone();
      }
    } else if (hits > 0 && result->clear_utime < 0) {
      result->clear_utime = frame.utime;  // the first good frame after the bad ones
    }
    for (pipeline::OdometrySample& s : frame.odometry) Odometry(s);
  }
  // A bad sample's ticks run until the next sample (50 Hz).
  static constexpr int64_t kSamplePeriodUs = 20'000;
  void Odometry(pipeline::OdometrySample& s) {
    if (!IsOdometryFault(fault.kind) || !In(s.utime)) return;
    if ((fault.kind == FaultKind::kSpikeOdometry || fault.kind == FaultKind::kSpikeWithinLimit) &&
        hits > 0) {
      return;  // one sample
    }
    ++hits;
    Onset(s.utime);
    result->clear_utime = std::max(result->clear_utime, s.utime + kSamplePeriodUs);
    switch (fault.kind) {
      case FaultKind::kNanOdometry: s.left_m_s = std::numeric_limits<double>::quiet_NaN(); break;
      case FaultKind::kSpikeOdometry: s.left_m_s = s.right_m_s = 8.0; break;
      case FaultKind::kSpikeWithinLimit: s.left_m_s *= 2.0, s.right_m_s *= 2.0; break;
      case FaultKind::kSlipBurst: s.left_m_s *= 1.15, s.right_m_s *= 1.15; break;
      default: break;
    }
  }
};

class FaultyFrameSource : public vehicle::FrameSource {
 public:
  FaultyFrameSource(vehicle::FrameSource& inner, Injector& injector)
      : inner_(inner), injector_(injector) {}
  bool Next(VehicleFrame& frame) override {
    if (!inner_.Next(frame)) return false;
    injector_.Frame(frame);
    return true;
  }
  int dropped_frames() const override { return inner_.dropped_frames(); }
  std::string name() const override { return inner_.name(); }

 private:
  vehicle::FrameSource& inner_;
  Injector& injector_;
};

// Last stage: what the vehicle did this frame.
class Observer : public vehicle::Stage {
 public:
  Observer(const vehicle::VehicleProcess& process, const can::SprayBar& bar,
           const can::SimulatedBar& simulated, FaultRunResult& result)
      : process_(process), bar_(bar), simulated_(simulated), result_(result) {}
  std::string name() const override { return "fault_observer"; }
  void Process(const VehicleFrame& frame, vehicle::RunStatus& status, vehicle::Publisher&) override {
    const vehicle::PipelineStage& stage = *process_.pipeline_stage();
    for (const treatment::TickResult& t : stage.ticks()) {
      TickRecord r;
      r.utime = t.utime;
      r.open_mask = t.open_mask;
      r.fail_reasons = t.fail_reasons;
      r.frame_utime = frame.utime;
      result_.ticks.push_back(r);
    }
    // The bar after the frame's last tick (earlier ones: from the sink).
    if (!result_.ticks.empty()) {
      result_.ticks.back().bar_failsafe = bar_.status().failsafe;
      result_.ticks.back().commanded_mask = bar_.status().commanded_mask;
    }
    FrameRecord f;
    f.utime = frame.utime;
    f.failsafe = status.failsafe;
    f.faults = status.faults;
    f.valves = simulated_.open_mask();
    f.tracker_distance_m = stage.pipeline().tracker().forward_distance_m();
    f.true_distance_m = frame.truth ? frame.truth->distance_m : 0.0;
    result_.frames.push_back(std::move(f));
    result_.end_utime = frame.utime;
    if (result_.start_utime == 0) result_.start_utime = frame.utime;
  }

 private:
  const vehicle::VehicleProcess& process_;
  const can::SprayBar& bar_;
  const can::SimulatedBar& simulated_;
  FaultRunResult& result_;
};

}  // namespace

const char* Describe(FaultKind kind) {
  switch (kind) {
    case FaultKind::kCameraStops: return "camera frames stop (1 s)";
    case FaultKind::kCorruptFrame: return "corrupt frame (one, cut to half its rows)";
    case FaultKind::kNanOdometry: return "NaN odometry (0.3 s of samples)";
    case FaultKind::kSpikeOdometry: return "odometry spike (one sample at 8 m/s)";
    case FaultKind::kSpikeWithinLimit: return "odometry spike within limits (one sample at 2x)";
    case FaultKind::kSlipBurst: return "wheel slip burst (both wheels +15 %, 0.6 s)";
    case FaultKind::kCanWriteErrors: return "CAN write errors (send queue full, 0.5 s)";
    case FaultKind::kBarSilent: return "spray bar stops answering (1 s)";
    case FaultKind::kStationLinkDown: return "station vanishes (LCM publish fails, 1 s)";
    case FaultKind::kDiskFull: return "disk full while logging (2 s)";
  }
  return "?";
}

FaultRunResult RunWithFault(const FaultRunOptions& options) {
  FaultRunResult result;
  sim::SimulatorOptions so = app::LoadSimulatorPreset("field", app::DefaultConfigDir());
  // The engine as a grower configures it: the preset's crop and vehicle profiles.
  const app::Profiles profiles = app::LoadProfiles("", "", "field", app::DefaultConfigDir());
  const geometry::CameraModel engine_camera(app::EngineCamera(profiles));
  so.length_m = options.length_m;
  so.seed = options.seed;
  sim::Simulator simulator(so);

  // The spray bar over a socketpair, as `simulate --publish --can simulated`.
  can::BarLinkOptions bar_options;
  bar_options.num_nozzles = treatment::TreatmentOptions{}.scheduler.bar.nozzles;
  auto [vehicle_end, bar_end] = can::CanFramePipe();
  CanSocketSwap can_swap(vehicle_end.get());
  vehicle::SprayBarEndpoint endpoint;
  endpoint.bar = std::make_unique<can::SprayBar>(std::move(vehicle_end), bar_options, "socketpair");
  can::SimulatedBarOptions sim_bar;
  sim_bar.num_nozzles = bar_options.num_nozzles;
  endpoint.simulated = std::make_unique<can::SimulatedBar>(std::move(bar_end), sim_bar);

  // LCM over memq:// with the station listening, the link breakable.
  telemetry::LcmTransport lcm("memq://");
  lcm.Subscribe(channels::kHealth, [&](const ReceivedMessage& m) {
    if (auto h = telemetry::Decode<plantscale_health_t>(m.channel, m.data, m.size)) {
      result.station_health.push_back(*h);
    }
  });
  lcm.Subscribe(channels::kEvents, [&](const ReceivedMessage& m) {
    if (auto e = telemetry::Decode<plantscale_event_t>(m.channel, m.data, m.size)) {
      result.station_events.push_back(*e);
    }
  });
  FaultyTransport link(lcm, result.published);
  FileSizeLimit disk;

  Injector injector;
  injector.fault = options.fault;
  injector.transport = &link;
  injector.can = &can_swap;
  injector.bar = endpoint.simulated.get();
  injector.disk = &disk;
  injector.log = options.log;
  injector.result = &result;

  const int64_t boot = 1'700'000'000'000'000;
  vehicle::VehicleProcessOptions po;
  po.real_time = false;
  po.log = options.log;
  po.sim_truth = true;
  {
    vehicle::VehicleProcess process(link, po, boot);
    // Every tick: the bar's state as the tick finds it, which is the state
    // after the previous tick's command (within a tick: the bar stage polls
    // between frames).
    std::vector<std::pair<bool, uint64_t>> bar_before;
    const can::SprayBar& bar = *endpoint.bar;
    treatment::NozzleSink observe = [&](int64_t, uint64_t) {
      bar_before.emplace_back(bar.status().failsafe, bar.status().commanded_mask);
    };
    vehicle::SimFrameSource sim_source(simulator, boot);
    FaultyFrameSource source(sim_source, injector);
    process.AddStages(endpoint, vehicle::PipelineSetup{engine_camera, app::ProductPipelineOptions(profiles), observe});
    process.runner().AddStage(std::make_unique<Observer>(process, bar, *endpoint.simulated, result));
    process.Run(source);
    result.log_status = process.logging()->status();
    result.log_events_written = process.log()->events();
    result.slip_bursts = process.pipeline_stage()->pipeline().tracker().slip_guard().bursts();
    if (bar_before.size() != result.ticks.size()) {
      throw std::logic_error("the sink saw " + std::to_string(bar_before.size()) +
                             " ticks, the pipeline stage " + std::to_string(result.ticks.size()));
    }
    // A frame's last tick keeps the Observer's record: the next frame's bar
    // stage polls before the next tick.
    for (size_t i = 0; i + 1 < result.ticks.size(); ++i) {
      if (result.ticks[i + 1].frame_utime != result.ticks[i].frame_utime) continue;
      result.ticks[i].bar_failsafe = bar_before[i + 1].first;
      result.ticks[i].commanded_mask = bar_before[i + 1].second;
    }
  }
  disk.Lift();
  while (lcm.Handle(0)) {
  }
  telemetry::LogReader reader(options.log);
  while (auto e = reader.Next()) result.log.push_back(std::move(*e));
  result.log_error = reader.error();
  return result;
}

}  // namespace plantscale::faults
