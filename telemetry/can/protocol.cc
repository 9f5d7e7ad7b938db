#include "telemetry/can/protocol.h"

#include <cstdio>
#include <cstring>

#include "engine/common/check.h"

namespace plantscale::telemetry::can {
namespace {

constexpr int kKinds = 5;
constexpr uint8_t kDlc[kKinds] = {8, 8, 4, 8, 8};  // by MessageKind
const char* const kNames[kKinds] = {"nozzle command", "nozzle ack", "bar heartbeat",
                                    "nozzle faults (section 0)", "nozzle faults (section 1)"};

can_frame Frame(const ProtocolIds& ids, MessageKind kind) {
  can_frame f;
  std::memset(&f, 0, sizeof f);
  f.can_id = ids.Id(kind);
  f.can_dlc = kDlc[static_cast<int>(kind)];
  return f;
}

void PutU32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
uint32_t GetU32(const uint8_t* p) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(p[i]) << (8 * i);
  return v;
}

std::string Hex(uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%03X", v);
  return b;
}

[[noreturn]] void Fail(const can_frame& f, const std::string& reason) {
  throw CanProtocolError("CAN frame " + Describe(f) + ": " + reason);
}

void RequireZero(const can_frame& f, const char* what, int from, int to) {
  for (int i = from; i < to; ++i) {
    if (f.data[i] != 0)
      Fail(f, std::string(what) + ": reserved byte " + std::to_string(i) + " is not 0");
  }
}

}  // namespace

OptionErrors ProtocolIds::Validate() const {
  OptionErrors errors;
  if ((base_id & 0x7u) != 0 || base_id + 7 > CAN_SFF_MASK) {
    errors.push_back({"base_id", "must be a multiple of 8 with base_id + 7 <= 0x7FF (got " +
                                     Hex(base_id) + ")"});
  }
  return errors;
}

can_filter ProtocolIds::Filter() const {
  can_filter f;
  f.can_id = base_id;
  f.can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG | (CAN_SFF_MASK & ~0x7u);
  return f;
}

const char* NozzleFaultName(NozzleFault fault) {
  switch (fault) {
    case NozzleFault::kNone:
      return "ok";
    case NozzleFault::kOpenCircuit:
      return "valve coil open circuit";
    case NozzleFault::kShortCircuit:
      return "valve coil short circuit";
    case NozzleFault::kStuck:
      return "valve stuck (flow disagrees with command)";
  }
  return "unknown";
}

can_frame Encode(const ProtocolIds& ids, const NozzleCommand& m) {
  PLANTSCALE_CHECK(m.section < kMaxSections && m.flags <= 0x0F, "nozzle command section/flags");
  can_frame f = Frame(ids, MessageKind::kCommand);
  f.data[0] = m.seq;
  f.data[1] = static_cast<uint8_t>((m.flags & 0x0F) | (m.section << 4));
  PutU32(f.data + 2, m.open_mask);
  f.data[6] = static_cast<uint8_t>(m.hold_ms & 0xFF);
  f.data[7] = static_cast<uint8_t>(m.hold_ms >> 8);
  return f;
}

can_frame Encode(const ProtocolIds& ids, const NozzleAck& m) {
  PLANTSCALE_CHECK(m.section < kMaxSections, "nozzle ack section");
  can_frame f = Frame(ids, MessageKind::kAck);
  f.data[0] = m.seq;
  f.data[1] = static_cast<uint8_t>(m.status);
  PutU32(f.data + 2, m.applied_mask);
  f.data[6] = m.section;
  return f;
}

can_frame Encode(const ProtocolIds& ids, const BarHeartbeat& m) {
  can_frame f = Frame(ids, MessageKind::kHeartbeat);
  f.data[0] = m.counter;
  f.data[1] = static_cast<uint8_t>(m.state);
  f.data[2] = m.num_nozzles;
  f.data[3] = m.protocol_version;
  return f;
}

can_frame Encode(const ProtocolIds& ids, const NozzleFaults& m) {
  PLANTSCALE_CHECK(m.section < kMaxSections, "nozzle faults section");
  can_frame f = Frame(ids, m.section == 0 ? MessageKind::kFaults : MessageKind::kFaultsHigh);
  for (int i = 0; i < kSectionNozzles; ++i) {
    f.data[i / 4] |=
        static_cast<uint8_t>((static_cast<unsigned>(m.fault[i]) & 0x3u) << (2 * (i % 4)));
  }
  return f;
}

namespace {

// The message kind of a frame of the bar's block; throws for anything else.
MessageKind KindOf(const ProtocolIds& ids, const can_frame& f) {
  if ((f.can_id & CAN_ERR_FLAG) != 0) {
    Fail(f, "error frame from the CAN controller (class " + Hex(f.can_id & CAN_ERR_MASK) + ")");
  }
  if ((f.can_id & CAN_EFF_FLAG) != 0) Fail(f, "extended (29-bit) identifier; the bar uses 11-bit");
  if ((f.can_id & CAN_RTR_FLAG) != 0) Fail(f, "remote request frame; the bar protocol has none");
  const uint32_t id = f.can_id & CAN_SFF_MASK;
  if (id < ids.base_id || id > ids.base_id + 7) {
    Fail(f, "identifier not in the bar's block " + Hex(ids.base_id) + ".." + Hex(ids.base_id + 7));
  }
  if (id >= ids.base_id + kKinds) {
    Fail(f, "identifier reserved in the bar's block (defined: " + Hex(ids.base_id) + ".." +
                Hex(ids.base_id + kKinds - 1) + ")");
  }
  const int k = static_cast<int>(id - ids.base_id);
  if (f.can_dlc != kDlc[k]) {
    Fail(f, std::string(kNames[k]) + ": DLC " + std::to_string(f.can_dlc) + ", expected " +
                std::to_string(kDlc[k]));
  }
  return static_cast<MessageKind>(k);
}

NozzleCommand DecodeCommand(const can_frame& f) {
  NozzleCommand m;
  m.seq = f.data[0];
  m.flags = f.data[1] & 0x0F;
  m.section = f.data[1] >> 4;
  m.open_mask = GetU32(f.data + 2);
  m.hold_ms = static_cast<uint16_t>(f.data[6] | (f.data[7] << 8));
  if ((m.flags & ~NozzleCommand::kFlagFailsafe) != 0) Fail(f, "nozzle command: unknown flag bits");
  if (m.section >= kMaxSections) {
    Fail(f, "nozzle command: section " + std::to_string(m.section) + " beyond 0..1");
  }
  if (m.hold_ms == 0) Fail(f, "nozzle command: hold_ms is 0");
  if ((m.flags & NozzleCommand::kFlagFailsafe) != 0 && m.open_mask != 0) {
    Fail(f, "nozzle command: fail-safe flag with nozzles open");
  }
  return m;
}

NozzleAck DecodeAck(const can_frame& f) {
  NozzleAck m;
  m.seq = f.data[0];
  if (f.data[1] > static_cast<uint8_t>(AckStatus::kRejected)) {
    Fail(f, "nozzle ack: unknown status " + std::to_string(f.data[1]));
  }
  m.status = static_cast<AckStatus>(f.data[1]);
  m.applied_mask = GetU32(f.data + 2);
  m.section = f.data[6];
  if (m.section >= kMaxSections) {
    Fail(f, "nozzle ack: section " + std::to_string(m.section) + " beyond 0..1");
  }
  RequireZero(f, "nozzle ack", 7, 8);
  return m;
}

BarHeartbeat DecodeHeartbeat(const can_frame& f) {
  BarHeartbeat m;
  m.counter = f.data[0];
  if (f.data[1] > static_cast<uint8_t>(BarState::kFault)) {
    Fail(f, "bar heartbeat: unknown state " + std::to_string(f.data[1]));
  }
  m.state = static_cast<BarState>(f.data[1]);
  m.num_nozzles = f.data[2];
  if (m.num_nozzles < 1 || m.num_nozzles > kMaxNozzles) {
    Fail(f, "bar heartbeat: nozzle count " + std::to_string(m.num_nozzles) + " not in 1.." +
                std::to_string(kMaxNozzles));
  }
  m.protocol_version = f.data[3];
  return m;
}

NozzleFaults DecodeFaults(const can_frame& f, int section) {
  NozzleFaults m;
  m.section = static_cast<uint8_t>(section);
  for (int i = 0; i < kSectionNozzles; ++i) {
    m.fault[i] = static_cast<NozzleFault>((f.data[i / 4] >> (2 * (i % 4))) & 0x3u);
  }
  return m;
}

}  // namespace

BarMessage Decode(const ProtocolIds& ids, const can_frame& f) {
  switch (KindOf(ids, f)) {
    case MessageKind::kCommand: return DecodeCommand(f);
    case MessageKind::kAck: return DecodeAck(f);
    case MessageKind::kHeartbeat: return DecodeHeartbeat(f);
    case MessageKind::kFaults: return DecodeFaults(f, 0);
    case MessageKind::kFaultsHigh: return DecodeFaults(f, 1);
  }
  Fail(f, "unreachable");
}

std::string Describe(const can_frame& f) {
  std::string s = "id " + Hex(f.can_id & CAN_EFF_MASK);
  if ((f.can_id & CAN_EFF_FLAG) != 0) s += " (extended)";
  if ((f.can_id & CAN_RTR_FLAG) != 0) s += " (RTR)";
  if ((f.can_id & CAN_ERR_FLAG) != 0) s += " (error)";
  s += " dlc " + std::to_string(f.can_dlc) + " [";
  const int n = f.can_dlc <= CAN_MAX_DLEN ? f.can_dlc : CAN_MAX_DLEN;
  for (int i = 0; i < n; ++i) {
    char b[4];
    std::snprintf(b, sizeof b, "%02x", f.data[i]);
    s += (i ? " " : "") + std::string(b);
  }
  return s + "]";
}

}  // namespace plantscale::telemetry::can
