#include "app/vehicle/runner.h"

#include <chrono>
#include <sstream>
#include <plantscale_lcmtypes/plantscale_command_t.hpp>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <thread>
#include <utility>

#include "telemetry/channels.h"
#include "telemetry/codec.h"

namespace plantscale::vehicle {

namespace channels = telemetry::channels;

SimFrameSource::SimFrameSource(sim::Simulator& simulator, int64_t epoch_utime)
    : simulator_(simulator), epoch_utime_(epoch_utime) {}

bool SimFrameSource::Next(VehicleFrame& frame) {
  if (!simulator_.Next(frame_)) return false;
  truth_ = frame_.truth;
  frame.utime = epoch_utime_ + frame_.truth.utime;
  frame.frame_index = frame_.truth.index;
  frame.image = frame_.rendered.image;
  frame.odometry.clear();
  for (const sim::OdometrySample& s : frame_.odometry) {
    frame.odometry.push_back({epoch_utime_ + s.utime, s.left_m_s, s.right_m_s});
  }
  frame.truth = &truth_;
  return true;
}

VehicleRunner::VehicleRunner(Publisher& publisher, const RunnerOptions& options, int64_t boot_utime)
    : publisher_(publisher), options_(options), now_utime_(boot_utime) {
  status_.boot_utime = boot_utime;
}

void VehicleRunner::AddStage(std::unique_ptr<Stage> stage) { stages_.push_back(std::move(stage)); }

void VehicleRunner::Event(int8_t severity, const std::string& kind, const std::string& text) {
  plantscale_event_t e{};
  e.utime = now_utime_;
  e.severity = severity;
  e.kind = kind;
  e.text = text;
  publisher_.Publish(channels::kEvents, e);
}

void VehicleRunner::ListenForCommands(Transport& transport, CommandAuthOptions auth) {
  commands_ = &transport;
  auth_ = std::move(auth);
  transport.Subscribe(channels::kCommand, [this](const ReceivedMessage& m) { Apply(m); });
}

namespace {

// An origin as it may appear in a fault line: it is whatever the sender
// wrote, signed or not.
std::string Printable(const std::string& origin) {
  constexpr size_t kMax = 64;
  std::string out;
  for (const char c : origin.substr(0, kMax)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  return origin.size() > kMax ? out + "..." : out;
}

}  // namespace

std::string VehicleRunner::Authenticate(const plantscale_command_t& c) {
  const bool is_signed = c.mac_size != 0 || !c.mac.empty();
  if (!auth_.key) {
    if (auth_.accept_unsigned) return "";
    return is_signed ? "not verifiable (the vehicle has no command key, --command-key)"
                     : "unsigned (no signature; the vehicle has no command key, --command-key)";
  }
  if (!is_signed && auth_.accept_unsigned) return "";
  const int64_t now = auth_.clock ? auth_.clock() : now_utime_;
  return telemetry::Verify(c, *auth_.key, now, replay_, auth_.window_us).reason;
}

void VehicleRunner::RefusalFaults() {
  while (!refusals_.empty() && refusals_.front().utime < now_utime_ - auth_.fault_hold_us) {
    refusals_.pop_front();
  }
  for (const Refusal& r : refusals_) status_.faults.push_back(r.line);
}

void VehicleRunner::ReportRefusal(const std::string& why) {
  ReportHeldRefusals();
  if (refusal_period_start_ < 0) refusal_period_start_ = now_utime_;
  if (refusal_events_ < auth_.max_refusal_events) {
    ++refusal_events_;
    Event(plantscale_event_t::SEVERITY_WARNING, "command_refused", why);
  } else {
    ++refusals_held_;
    last_held_ = why;
  }
}

// Once the period is over (or the run), the refusals held back in one event.
void VehicleRunner::ReportHeldRefusals(bool at_end) {
  if (refusal_period_start_ < 0 || (!at_end && now_utime_ - refusal_period_start_ < auth_.refusal_period_us)) {
    return;
  }
  if (refusals_held_ > 0) {
    std::ostringstream text;
    text.precision(1);
    text << refusals_held_ << " more command" << (refusals_held_ == 1 ? "" : "s") << " refused in "
         << std::fixed << 1e-6 * static_cast<double>(now_utime_ - refusal_period_start_)
         << " s, not each reported (at most " << auth_.max_refusal_events << " per "
         << 1e-6 * static_cast<double>(auth_.refusal_period_us) << " s); the last: " << last_held_;
    Event(plantscale_event_t::SEVERITY_WARNING, "command_refused", text.str());
  }
  refusal_period_start_ = -1;
  refusal_events_ = 0;
  refusals_held_ = 0;
  last_held_.clear();
}

void VehicleRunner::Apply(const ReceivedMessage& m) {
  std::string error;
  const auto c = telemetry::Decode<plantscale_command_t>(m.channel, m.data, m.size, &error);
  OperatorCommands& k = status_.commands;
  const auto refuse = [&](const std::string& why) {
    ++k.refused;
    ReportRefusal(why);
    // A fault line while it is recent; the same line again renews it, and
    // a flood keeps the newest few.
    const std::string line = "command refused: " + why;
    std::erase_if(refusals_, [&](const Refusal& r) { return r.line == line; });
    refusals_.push_back({now_utime_, line});
    if (refusals_.size() > 4) refusals_.pop_front();
  };
  if (!c) return refuse(error);
  const std::string from = c->origin.empty() ? "the station" : Printable(c->origin);
  if (const std::string why = Authenticate(*c); !why.empty()) return refuse(why + " from " + from);
  const bool is_signed = c->mac_size != 0 || !c->mac.empty();
  const std::string trust = is_signed && auth_.key ? "" : " (unverified: --accept-unsigned-commands)";
  std::string did;
  if (c->command == plantscale_command_t::COMMAND_START) {
    k.paused = false;
    did = "started (spraying resumed)";
  } else if (c->command == plantscale_command_t::COMMAND_PAUSE) {
    k.paused = true;
    did = "paused (nozzles closed)";
  } else if (c->command == plantscale_command_t::COMMAND_SET_MODE) {
    if (c->mode == plantscale_command_t::MODE_SPRAY_OFF) {
      k.spray_off = true;
      did = "spraying switched off";
    } else if (c->mode == plantscale_command_t::MODE_SPRAY_CROP ||
               c->mode == plantscale_command_t::MODE_SPRAY_WEED) {
      k.spray_off = false;
      k.mode = c->mode;
      did = c->mode == plantscale_command_t::MODE_SPRAY_CROP ? "mode: spray the crop" : "mode: spray the weeds";
    } else {
      return refuse("command from " + from + ": unknown mode " + std::to_string(c->mode));
    }
  } else {
    return refuse("command from " + from + ": unknown command " + std::to_string(c->command));
  }
  ++k.received;
  Event(plantscale_event_t::SEVERITY_INFO, "command", did + " by " + from + trust);
}

RunSummary VehicleRunner::Run(FrameSource& source, const std::atomic<bool>* stop) {
  using Clock = std::chrono::steady_clock;
  status_.source = source.name();
  VehicleFrame frame;
  RunSummary summary;
  int64_t first_utime = -1;
  Clock::time_point wall_start;
  while ((!stop || !stop->load()) && source.Next(frame)) {
    if (first_utime < 0) {
      first_utime = frame.utime;
      wall_start = Clock::now();
      now_utime_ = frame.utime;
      Event(plantscale_event_t::SEVERITY_INFO, "run_started", "run started: " + source.name());
      if (!options_.run_config.empty()) {
        Event(plantscale_event_t::SEVERITY_INFO, "run_config", options_.run_config);
      }
    }
    if (options_.real_time) {
      std::this_thread::sleep_until(wall_start +
                                    std::chrono::microseconds(frame.utime - first_utime));
    }
    now_utime_ = frame.utime;
    const int dropped = source.dropped_frames();
    if (dropped > status_.dropped_frames) {
      Event(plantscale_event_t::SEVERITY_WARNING, "frame_dropped",
            std::to_string(dropped - status_.dropped_frames) +
                " camera frame(s) dropped before frame " + std::to_string(frame.frame_index));
    }
    status_.dropped_frames = dropped;
    status_.faults = source.faults(frame.utime);
    ++status_.frames;
    if (commands_ != nullptr) {
      while (commands_->Handle(0)) {
      }
      ReportHeldRefusals();
      RefusalFaults();
    }
    for (const std::unique_ptr<Stage>& stage : stages_) stage->Process(frame, status_, publisher_);
    summary.seconds = 1e-6 * static_cast<double>(frame.utime - first_utime);
  }
  ReportHeldRefusals(true);
  for (const std::unique_ptr<Stage>& stage : stages_) stage->Finish(now_utime_, publisher_);
  Event(plantscale_event_t::SEVERITY_INFO, "run_finished",
        "run finished after " + std::to_string(status_.frames) + " frames");
  summary.frames = status_.frames;
  summary.dropped_frames = status_.dropped_frames;
  return summary;
}

}  // namespace plantscale::vehicle
