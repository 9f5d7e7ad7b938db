#pragma once
// The bar's end of the protocol (PROTOCOL.md), played in software on the
// other end of a CanFramePipe: applies and acknowledges every command,
// closes every nozzle itself when commands stop for longer than their
// hold_ms, sends a heartbeat and the fault state every heartbeat period, and
// records every change of the valves with its time. Tests (and simulations)
// can inject nozzle faults, a bar-level fault, silence, lost heartbeats and
// arbitrary raw frames.

#include <cstdint>
#include <string>
#include <vector>

#include "telemetry/can/protocol.h"
#include "telemetry/can/spray_bar.h"
#include "telemetry/types.h"

namespace plantscale::telemetry::can {

struct SimulatedBarOptions {
  int num_nozzles = 8;
  ProtocolIds ids;
  double heartbeat_period_s = 0.05;

  OptionErrors Validate() const;
};

class SimulatedBar {
 public:
  // One change of the valves: from `utime` on, nozzle i sprays when bit i is set.
  struct Valves {
    int64_t utime;
    uint64_t open_mask;
  };

  SimulatedBar(UniqueFd fd, const SimulatedBarOptions& options);

  // Reads and applies every command waiting (acknowledging each unless
  // silent), expires the hold, and sends a heartbeat plus the fault state
  // when the heartbeat period has passed (first one at the first Step).
  void Step(int64_t utime);

  // Faulty nozzles are held closed (a stuck valve is driven but reported).
  void InjectFault(int nozzle, NozzleFault fault);
  void SetBarFault(bool fault) { bar_fault_ = fault; }
  // A silent bar still reads and applies commands but sends nothing.
  void SetSilent(bool silent) { silent_ = silent; }
  // The next heartbeat's counter skips `n` values (as if n were lost).
  void SkipHeartbeats(int n) { counter_ = static_cast<uint8_t>(counter_ + n); }
  void SetReportedNozzles(int n) { reported_nozzles_ = n; }
  // Sends bytes as they are (malformed frames, short writes).
  void SendRaw(const can_frame& frame);
  void SendBytes(const void* data, size_t size);

  uint64_t open_mask() const { return open_mask_; }
  BarState state() const;
  const std::vector<NozzleCommand>& commands() const { return commands_; }
  const std::vector<Valves>& history() const { return history_; }
  // Frames from the vehicle that did not decode as commands, with the reason.
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  void Apply(int64_t utime, uint64_t mask);
  void Send(const can_frame& frame);
  void SendFaults(int section);
  uint64_t HeldClosedMask() const;

  UniqueFd fd_;
  SimulatedBarOptions options_;
  std::vector<NozzleFault> faults_;
  bool bar_fault_ = false;
  bool silent_ = false;
  int reported_nozzles_;
  uint8_t counter_ = 0;
  int64_t next_heartbeat_utime_ = -1;
  int64_t hold_until_utime_ = -1;  // -1: no command yet
  uint64_t open_mask_ = 0;
  std::vector<NozzleCommand> commands_;
  std::vector<Valves> history_;
  std::vector<std::string> errors_;
};

// Every shot in `history`: one NozzleShot per nozzle and opening, from the
// change that opened it to the one that closed it (`end_utime` for shots
// still open). position_m is left at zero and plant_id at -1 for the caller,
// who knows the pose and the nozzle's footprint, to fill in.
std::vector<NozzleShot> ShotsFromValves(const std::vector<SimulatedBar::Valves>& history,
                                        int64_t end_utime);

}  // namespace plantscale::telemetry::can
