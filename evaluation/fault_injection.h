#pragma once
// Fault injection on the simulator, end to end (issue 35; docs/faults.md).
// The vehicle process is the product's own wiring (app/vehicle/
// vehicle_process.h: runner, stages, pipeline, spray bar stage, records and
// heartbeat, the log written to a file) on the field preset, with LCM over
// memq:// and the spray bar over a socketpair to a SimulatedBar. Test-only
// parts sit around the real ones and break them on a schedule of message
// time:
//   camera stops      the frame source delivers frames without an image
//   corrupt frame     a frame cut short (half its rows)
//   NaN / spike / slip the odometry samples of the window changed
//   CAN write errors  the bar's socket swapped (dup2) for one whose send
//                     queue is full: write() fails with EAGAIN, as SocketCAN
//                     does with ENOBUFS; swapped back when it clears
//   bar silent        SimulatedBar::SetSilent: commands applied, no answer
//   station link down the LCM transport's publish throws TransportError
//   disk full         RLIMIT_FSIZE at the log's size: its writes fail (EFBIG)
// and everything the vehicle does is recorded: every scheduler tick with
// the bar's state after it, every frame's status, what the station receives,
// every message handed to LCM, and the log read back.

#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <plantscale_lcmtypes/plantscale_health_t.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "telemetry/codec.h"
#include "telemetry/log.h"

namespace plantscale::faults {

enum class FaultKind {
  kCameraStops,
  kCorruptFrame,
  kNanOdometry,
  kSpikeOdometry,       // one sample at 8 m/s, beyond the tracker's 3 m/s
  kSpikeWithinLimit,    // one sample at twice the speed, within 3 m/s
  kSlipBurst,           // both wheels read 15 % long
  kCanWriteErrors,
  kBarSilent,
  kStationLinkDown,
  kDiskFull,
};
const char* Describe(FaultKind kind);

struct Fault {
  FaultKind kind;
  double start_s = 4.0;  // message time from the first frame
  double end_s = 5.0;    // the fault clears (exclusive)
};

struct FaultRunOptions {
  double length_m = 7.0;  // of the field preset
  uint64_t seed = 1;
  Fault fault;
  std::string log;  // the log's file
};

struct TickRecord {
  int64_t utime = 0;           // the tick's (message time)
  int64_t frame_utime = 0;     // the frame whose processing sent it
  uint64_t open_mask = 0;      // the scheduler's
  uint32_t fail_reasons = 0;   // the scheduler's
  bool bar_failsafe = false;   // the spray bar's state after the tick's command
  uint64_t commanded_mask = 0; // what the spray bar last sent after it
};

struct FrameRecord {
  int64_t utime = 0;
  bool failsafe = false;
  std::vector<std::string> faults;  // the runner's status after every stage
  uint64_t valves = 0;              // the simulated bar's valves after its step
  double tracker_distance_m = 0.0;  // the tracker's forward distance
  double true_distance_m = 0.0;     // the simulator's
};

struct Published {
  std::string channel;
  telemetry::Bytes bytes;
};

struct FaultRunResult {
  int64_t start_utime = 0;  // first frame
  // When the fault arose: the bad sample's time, the bad frame's capture,
  // the frame at which a part was broken.
  int64_t onset_utime = -1;
  // When it cleared: the first good frame after bad ones, the end of the
  // last bad sample's period, the frame at which a broken part was mended.
  int64_t clear_utime = -1;
  int64_t end_utime = 0;    // last frame
  std::vector<TickRecord> ticks;
  std::vector<FrameRecord> frames;
  std::vector<plantscale_health_t> station_health;  // received over LCM
  std::vector<plantscale_event_t> station_events;
  std::vector<Published> published;  // every message handed to LCM, in order
  size_t published_at_injection = 0;  // how many before the fault was injected
  bool broken_part = false;  // CAN, bar, link or disk (else a bad frame or sample)
  std::vector<telemetry::LogEvent> log;
  std::string log_error;  // LogReader's; empty: read whole
  telemetry::LogStatus log_status;
  int64_t log_events_written = 0;
  int slip_bursts = 0;   // the tracker's slip guard
};

// Runs the field preset with `options.fault` injected.
FaultRunResult RunWithFault(const FaultRunOptions& options);

}  // namespace plantscale::faults
