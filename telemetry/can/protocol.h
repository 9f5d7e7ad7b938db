#pragma once
// The spray bar's CAN protocol (telemetry/can/PROTOCOL.md): classic CAN
// 2.0A frames in a block of eight identifiers starting at `base_id`. A bar
// has up to 64 nozzles in two sections of 32 (section s: nozzles 32s..32s+31).
//
//   base+0  NozzleCommand  vehicle -> bar  DLC 8  seq, flags | section << 4,
//                                                 open mask (u32 LE), hold ms (u16 LE)
//   base+1  NozzleAck      bar -> vehicle  DLC 8  seq, status, applied mask (u32 LE), section, 0
//   base+2  BarHeartbeat   bar -> vehicle  DLC 4  counter, state, nozzles, protocol version
//   base+3  NozzleFaults   bar -> vehicle  DLC 8  section 0: 2-bit fault code per nozzle
//   base+4  NozzleFaults   bar -> vehicle  DLC 8  section 1 (bars of more than 32 nozzles)
//   base+5 .. base+7       reserved
//
// Encode() builds a `struct can_frame` (linux/can.h); Decode() checks the
// identifier, flags, DLC and every field and throws CanProtocolError naming
// the identifier, the DLC or byte and the reason rather than passing a
// malformed frame on.

#include <linux/can.h>

#include <array>
#include <cstdint>
#include <string>
#include <variant>

#include "engine/common/options.h"

namespace plantscale::telemetry::can {

inline constexpr uint8_t kProtocolVersion = 1;
inline constexpr int kSectionNozzles = 32;  // one bit each in a u32 mask per frame
inline constexpr int kMaxSections = 2;
inline constexpr int kMaxNozzles = kSectionNozzles * kMaxSections;  // 64
inline constexpr uint32_t kDefaultBaseId = 0x210;

// Sections a bar of `nozzles` nozzles uses: 1 up to 32 nozzles, else 2.
inline int Sections(int nozzles) { return (nozzles + kSectionNozzles - 1) / kSectionNozzles; }

// A frame that does not follow the protocol (wrong identifier, DLC, flags or
// field value). what() names the identifier and the reason.
class CanProtocolError : public DataError {
 public:
  using DataError::DataError;
};

enum class MessageKind : uint8_t {
  kCommand = 0,
  kAck = 1,
  kHeartbeat = 2,
  kFaults = 3,      // section 0
  kFaultsHigh = 4,  // section 1
};

// The identifier block of one bar: base_id .. base_id + 7 (11-bit).
struct ProtocolIds {
  uint32_t base_id = kDefaultBaseId;  // a multiple of 8, base_id + 7 <= 0x7FF

  OptionErrors Validate() const;
  uint32_t Id(MessageKind kind) const { return base_id + static_cast<uint32_t>(kind); }
  // Kernel filter (CAN_RAW_FILTER) that passes exactly this block.
  can_filter Filter() const;
};

// Vehicle -> bar, one per section every tick. The bar applies `open_mask`
// to the section (bit i: nozzle 32·section + i open) and closes every
// nozzle on its own when no further command arrives within `hold_ms` (the
// bar-side dead-man).
struct NozzleCommand {
  static constexpr uint8_t kFlagFailsafe = 0x01;  // vehicle is fail-safe: mask is all closed
  uint8_t seq = 0;                                // +1 per command, modulo 256
  uint8_t flags = 0;
  uint32_t open_mask = 0;
  uint16_t hold_ms = 0;  // > 0
  uint8_t section = 0;   // 0 or 1
};

enum class AckStatus : uint8_t { kApplied = 0, kRejected = 1 };

// Bar -> vehicle, one per command, same seq and section. `applied_mask` is
// what the section's valves are driven to (faulty nozzles are held closed by
// the bar).
struct NozzleAck {
  uint8_t seq = 0;
  AckStatus status = AckStatus::kApplied;
  uint32_t applied_mask = 0;
  uint8_t section = 0;
};

enum class BarState : uint8_t {
  kReady = 0,        // valves follow commands
  kHoldExpired = 1,  // no command within hold_ms: the bar closed every nozzle
  kFault = 2,        // bar-level fault (supply, pressure): every nozzle closed
};

// Bar -> vehicle, periodic (PROTOCOL.md: every 50 ms). `counter` +1 per
// heartbeat modulo 256; a gap means frames were lost.
struct BarHeartbeat {
  uint8_t counter = 0;
  BarState state = BarState::kReady;
  uint8_t num_nozzles = 0;  // 1 .. kMaxNozzles (64)
  uint8_t protocol_version = kProtocolVersion;
};

// Per-nozzle fault codes, 2 bits each.
enum class NozzleFault : uint8_t {
  kNone = 0,
  kOpenCircuit = 1,   // valve coil open circuit: nozzle cannot open
  kShortCircuit = 2,  // valve coil short: driver switched off, nozzle closed
  kStuck = 3,         // flow disagrees with the command (valve stuck)
};
const char* NozzleFaultName(NozzleFault fault);

// Bar -> vehicle, per section, with every heartbeat and on any change: the
// section's whole fault state (a snapshot, so a lost frame costs nothing but
// latency). fault[i] is nozzle 32·section + i.
struct NozzleFaults {
  uint8_t section = 0;
  std::array<NozzleFault, kSectionNozzles> fault{};  // all kNone
};

using BarMessage = std::variant<NozzleCommand, NozzleAck, BarHeartbeat, NozzleFaults>;

can_frame Encode(const ProtocolIds& ids, const NozzleCommand& m);
can_frame Encode(const ProtocolIds& ids, const NozzleAck& m);
can_frame Encode(const ProtocolIds& ids, const BarHeartbeat& m);
can_frame Encode(const ProtocolIds& ids, const NozzleFaults& m);

// Throws CanProtocolError: extended/RTR/error frame, identifier outside the
// block or reserved, DLC not the message's, reserved bytes or bits not zero,
// unknown enum value, section beyond 1, nozzle count out of range, hold_ms
// zero, a failsafe command with nozzles open.
BarMessage Decode(const ProtocolIds& ids, const can_frame& frame);

// "id 0x211 dlc 8 [01 00 ff 00 00 00 00 00]" for error messages and logs.
std::string Describe(const can_frame& frame);

// Sequence numbers are modulo 256: how far `got` is ahead of `expected`
// (0 = in order, 1..127 = frames missing, 128..255 = old or repeated).
inline uint8_t SeqDistance(uint8_t expected, uint8_t got) {
  return static_cast<uint8_t>(got - expected);
}

}  // namespace plantscale::telemetry::can
