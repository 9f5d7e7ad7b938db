#pragma once
// The vehicle's end of the spray bar (PROTOCOL.md): sends nozzle commands,
// reads the bar's acknowledgements, heartbeats and per-nozzle faults, and
// keeps the nozzles closed (fail-safe) whenever it cannot trust the bar.
//
// SprayBar works on any file descriptor that carries whole `struct
// can_frame`s: a SocketCAN raw socket in the product (OpenSocketCan), one
// end of a socketpair in tests (the other end played by SimulatedBar). The
// encoder, decoder and the bar logic are the same on both.
//
// Time is the caller's message clock (`utime`, microseconds): the watchdog
// compares it with the utime of the Poll that read the last heartbeat.
// Single-threaded: call Poll/Command from the runner's thread.

#include <cstdint>
#include <deque>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "telemetry/can/protocol.h"

namespace plantscale::telemetry::can {

// The CAN endpoint could not be opened, read or written (no SocketCAN in the
// kernel, no such interface, not a CAN interface). what() names the
// interface, the call and the errno text.
class CanError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Owns a file descriptor; closes it on destruction.
class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) : fd_(fd) {}
  UniqueFd(UniqueFd&& other) noexcept : fd_(other.Release()) {}
  UniqueFd& operator=(UniqueFd&& other) noexcept;
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  ~UniqueFd();
  int get() const { return fd_; }
  int Release();

 private:
  int fd_ = -1;
};

// A connected pair of SOCK_SEQPACKET sockets: each write of a can_frame is
// read as one frame on the other end (tests, simulations). Throws CanError.
std::pair<UniqueFd, UniqueFd> CanFramePipe();

// socket(PF_CAN, SOCK_RAW, CAN_RAW) bound to `interface` (SIOCGIFINDEX),
// non-blocking, with a kernel filter passing only `ids`' block and bus-off /
// controller error frames. Throws CanError naming the interface and why:
// empty or too long a name, no such network interface, no SocketCAN in the
// kernel (EAFNOSUPPORT), not a CAN interface.
UniqueFd OpenSocketCan(const std::string& interface, const ProtocolIds& ids);

// The CAN link to the bar: how many nozzles it drives and its timing. Where
// the nozzles stand is the vehicle's bar geometry
// (treatment::SprayBarOptions, the vehicle profile's `nozzles`), whose count
// the process copies here (app/telemetry_commands.cc); 8 is the `spraybar`
// command's bench bar.
struct BarLinkOptions {
  int num_nozzles = 8;  // 1 .. kMaxNozzles (64); more than 32: two command frames per tick
  ProtocolIds ids;
  double heartbeat_timeout_s = 0.25;  // bar silent longer: fail-safe (bar sends every 50 ms)
  double ack_timeout_s = 0.1;         // a command unacknowledged longer: fail-safe
  double hold_s = 0.2;                // sent to the bar: it closes on its own after this
  int recover_heartbeats = 3;  // good heartbeats after any trouble (and at start) before opening

  OptionErrors Validate() const;
};

struct SprayBarStatus {
  bool failsafe = true;                    // nozzles commanded closed
  std::vector<std::string> reasons;        // why fail-safe, one line each (empty when not)
  std::vector<NozzleFault> nozzle_faults;  // per nozzle, as last reported by the bar
  uint64_t requested_mask = 0;             // what the caller asked for last
  uint64_t commanded_mask = 0;  // what was last sent (requested minus faulty, 0 in fail-safe)
  uint64_t applied_mask = 0;    // what the bar last acknowledged driving
  bool heard = false;           // any heartbeat so far
  BarState bar_state = BarState::kHoldExpired;
  int64_t last_heartbeat_utime = 0;
  // Counters since construction.
  int64_t commands_sent = 0;
  int64_t acks = 0;
  int64_t heartbeats = 0;
  int64_t frames_rejected = 0;  // malformed frames and bad reads
  int64_t sequence_gaps = 0;    // heartbeat or ack sequence gaps
  std::string last_error;       // latest protocol or I/O error, with the frame
};

class SprayBar {
 public:
  // `endpoint` names the fd in messages ("can0", "socketpair").
  SprayBar(UniqueFd fd, const BarLinkOptions& options, std::string endpoint);
  // The product path: OpenSocketCan(interface) then the constructor above.
  static SprayBar Open(const std::string& interface, const BarLinkOptions& options);

  SprayBar(SprayBar&&) = default;

  // Reads every frame waiting (never blocks), runs the watchdog at `utime`,
  // and when the bar has just become untrusted sends an all-closed command
  // at once.
  void Poll(int64_t utime);
  // Commands `open_mask` (bit i: nozzle i). Sent as all-closed with the
  // fail-safe flag while fail-safe; nozzles with a reported fault are held
  // closed. Bits at or beyond num_nozzles are a programming error.
  void Command(int64_t utime, uint64_t open_mask);

  // The nozzle sink of the treatment scheduler: Poll then Command every tick.
  // It refers to this SprayBar: do not move the bar after taking its sink.
  std::function<void(int64_t utime, uint64_t open_mask)> Sink();

  const SprayBarStatus& status() const { return status_; }
  const std::string& endpoint() const { return endpoint_; }
  const BarLinkOptions& options() const { return options_; }
  // For the heartbeat (PLANTSCALE_HEALTH faults): fail-safe reasons and
  // faulty nozzles, one line each, prefixed "spray bar <endpoint>: ".
  std::vector<std::string> HealthFaults() const;

 private:
  struct Outstanding {
    uint8_t seq;
    uint8_t section;
    uint32_t mask;
    int64_t sent_utime;
  };
  void ReadAll(int64_t utime);
  void Handle(int64_t utime, const BarMessage& message);
  void OnAck(const NozzleAck& ack);
  void OnHeartbeat(int64_t utime, const BarHeartbeat& heartbeat);
  void OnFaults(const NozzleFaults& faults);
  void Trouble(const std::string& text);
  void Evaluate(int64_t utime);
  void Send(int64_t utime, uint64_t mask);  // one command per section
  void SendSection(int64_t utime, int section, uint32_t mask);
  uint64_t FaultyMask() const;

  UniqueFd fd_;
  BarLinkOptions options_;
  std::string endpoint_;
  SprayBarStatus status_;
  std::deque<Outstanding> outstanding_;
  uint8_t next_seq_ = 0;
  bool expect_counter_ = false;
  uint8_t expected_counter_ = 0;
  std::string trouble_;  // latched until recover_heartbeats good heartbeats
  int good_heartbeats_ = 0;
  int64_t start_utime_ = -1;
  bool peer_closed_ = false;
};

}  // namespace plantscale::telemetry::can
