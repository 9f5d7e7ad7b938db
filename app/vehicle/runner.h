#pragma once
// The vehicle process's loop: takes frames from a FrameSource (the
// simulator, or a camera for `plantscale run`), paces them in real time or
// as fast as possible, and passes each frame through a list of Stages that
// publish what they know. The engine runs in one of them (PipelineStage,
// stages.h: the vehicle pipeline of engine/pipeline); the others publish the
// heartbeat, thumbnails, odometry and the simulator's truth, or supervise
// the spray bar. Stages report fail-safe state and faults through RunStatus.

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "engine/pipeline/pipeline.h"
#include "engine/sim/simulator.h"
#include "telemetry/command_auth.h"
#include "telemetry/publisher.h"

namespace plantscale::vehicle {

using telemetry::Publisher;
using telemetry::ReceivedMessage;
using telemetry::Transport;

struct VehicleFrame {
  int64_t utime = 0;  // capture time on the message clock (epoch microseconds)
  int frame_index = 0;
  cv::Mat image;
  std::vector<pipeline::OdometrySample> odometry;  // since the previous frame, utime as above
  const sim::FrameTruth* truth = nullptr;     // simulator only: never feed it to the engine
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual bool Next(VehicleFrame& frame) = 0;  // false at the end
  virtual int dropped_frames() const = 0;      // lost so far by the source
  virtual std::string name() const = 0;        // "simulate", "run"
  // Faults of the source (camera, odometry input), reported in the heartbeat.
  virtual std::vector<std::string> faults(int64_t /*now_utime*/) const { return {}; }
};

// The simulator as a frame source; times are shifted to `epoch_utime`.
class SimFrameSource : public FrameSource {
 public:
  SimFrameSource(sim::Simulator& simulator, int64_t epoch_utime);
  bool Next(VehicleFrame& frame) override;
  int dropped_frames() const override { return simulator_.dropped_frames(); }
  std::string name() const override { return "simulate"; }

 private:
  sim::Simulator& simulator_;
  int64_t epoch_utime_;
  sim::SimFrame frame_;
  sim::FrameTruth truth_;
};

// What the operator asked for on PLANTSCALE_COMMAND (the vehicle is safe
// without it: a station that never speaks leaves spraying on).
struct OperatorCommands {
  bool paused = false;     // COMMAND_PAUSE until COMMAND_START
  bool spray_off = false;  // MODE_SPRAY_OFF until another mode
  int8_t mode = 0;         // plantscale_command_t::MODE_SPRAY_CROP/WEED; 0: as configured
  int64_t received = 0;    // commands applied
  int64_t refused = 0;     // undecodable, unknown or not authenticated commands
  bool held() const { return paused || spray_off; }
};

// What the stages know about the run; stages update it, HealthStage sends it.
struct RunStatus {
  std::string source;
  int64_t boot_utime = 0;
  int frames = 0;
  int dropped_frames = 0;
  double distance_m = 0.0;
  bool failsafe = true;  // nozzles closed until a treatment stage says otherwise
  std::vector<std::string> faults;
  OperatorCommands commands;
};

class Stage {
 public:
  virtual ~Stage() = default;
  virtual std::string name() const = 0;
  virtual void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) = 0;
  // The run has ended (after the last frame, before run_finished): send
  // what was held back for later.
  virtual void Finish(int64_t /*utime*/, Publisher& /*publisher*/) {}
};

// How the vehicle authenticates station commands (telemetry/command_auth.h).
// Fail closed: without a key every command is refused, unless
// accept_unsigned. A refused command leaves the state as it was, is a
// command_refused event and stays a fault line in the heartbeat
// ("command refused: forged (bad signature) from station@host") for
// fault_hold_us of message time.
struct CommandAuthOptions {
  std::optional<telemetry::CommandKey> key;
  // Demo and tests only: commands without a signature are obeyed (with a
  // key, a signature that is there must still be good; without one,
  // signatures go unchecked).
  bool accept_unsigned = false;
  int64_t window_us = telemetry::kCommandWindowUs;
  // The clock a command's utime is checked against; empty: the message
  // clock (now_utime()).
  std::function<int64_t()> clock;
  int64_t fault_hold_us = 5'000'000;
  // A flood of refused commands (any laptop on the multicast group can send
  // them) must not fill the log: at most this many command_refused events
  // per period of message time; the rest are counted and reported in one
  // summary event per period ("N more commands refused ...").
  int max_refusal_events = 4;
  int64_t refusal_period_us = 1'000'000;
};

struct RunnerOptions {
  bool real_time = true;  // false: as fast as possible (--fast)
  // What the run was made from (a JSON object's text: the simulator's preset
  // and seed, app/config/run_config.h), sent as a "run_config" event right after
  // "run_started" so that the log can be scored later; empty: none. (The
  // "= {}" keeps `RunnerOptions{false}` clear of -Wmissing-field-initializers.)
  std::string run_config = {};
};

struct RunSummary {
  int frames = 0;
  int dropped_frames = 0;
  double seconds = 0.0;  // message time from first to last frame
};

class VehicleRunner {
 public:
  VehicleRunner(Publisher& publisher, const RunnerOptions& options, int64_t boot_utime);
  void AddStage(std::unique_ptr<Stage> stage);
  // Acts on station commands (PLANTSCALE_COMMAND) received on `transport`,
  // polled before every frame, once `auth` lets them through; each applied
  // or refused command is an event.
  void ListenForCommands(Transport& transport, CommandAuthOptions auth = {});
  const RunStatus& status() const { return status_; }
  // Runs until the source ends or `stop` becomes true. Publishes run_started
  // (then run_config when given), frame_dropped and run_finished events.
  RunSummary Run(FrameSource& source, const std::atomic<bool>* stop = nullptr);
  // The message clock: utime of the frame being processed (for the log).
  int64_t now_utime() const { return now_utime_; }

 private:
  void Event(int8_t severity, const std::string& kind, const std::string& text);
  void Apply(const ReceivedMessage& message);
  // Empty when `command` may be obeyed, else why not.
  std::string Authenticate(const plantscale_command_t& command);
  void RefusalFaults();  // the recent refusals into status_.faults

  Publisher& publisher_;
  RunnerOptions options_;
  RunStatus status_;
  std::vector<std::unique_ptr<Stage>> stages_;
  int64_t now_utime_;
  Transport* commands_ = nullptr;
  CommandAuthOptions auth_;
  telemetry::CommandReplayState replay_;
  struct Refusal {
    int64_t utime;
    std::string line;
  };
  std::deque<Refusal> refusals_;  // newest last, one per line
  // The refusal events' rate limit (CommandAuthOptions::max_refusal_events).
  void ReportRefusal(const std::string& why);
  void ReportHeldRefusals(bool at_end = false);
  int64_t refusal_period_start_ = -1;
  int refusal_events_ = 0;       // sent this period
  int64_t refusals_held_ = 0;    // counted, not sent, this period
  std::string last_held_;
};

}  // namespace plantscale::vehicle
