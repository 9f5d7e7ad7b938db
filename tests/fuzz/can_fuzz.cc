// Fuzz target: the spray bar's CAN protocol (telemetry/can/protocol.h) and
// the vehicle side that consumes it (telemetry/can/spray_bar.h). Input:
//   bytes 0-1  the bar's identifier block (base id, a multiple of 8)
//   byte 2     the bar's nozzle count (1..64)
//   then records, each an op byte and its operands:
//     op % 4 == 0  a 16-byte struct can_frame from the bar
//     op % 4 == 1  a short datagram: 1 length byte, then that many bytes (< 16)
//     op % 4 == 2  the vehicle commands an 8-byte nozzle mask
//     op % 4 == 3  1 byte: the clock advances that many ms, then Poll
// Every frame is first decoded on its own: Decode may refuse it only with
// CanProtocolError, and what it accepts must encode to a frame that decodes
// to the same message. Then the frames reach a SprayBar through a socket
// pair, whose Poll and Command must never throw.
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <variant>

#include "telemetry/can/protocol.h"
#include "telemetry/can/spray_bar.h"
#include "tests/fuzz/fuzz_util.h"

namespace can = plantscale::telemetry::can;

namespace {

can_frame Reencode(const can::ProtocolIds& ids, const can::BarMessage& m) {
  return std::visit([&](const auto& message) { return can::Encode(ids, message); }, m);
}

void CheckDecode(const can::ProtocolIds& ids, const can_frame& frame) {
  (void)can::Describe(frame);
  can::BarMessage m;
  try {
    m = can::Decode(ids, frame);
  } catch (const can::CanProtocolError&) {
    return;  // the documented refusal
  }
  const can_frame again = Reencode(ids, m);
  const can_frame third = Reencode(ids, can::Decode(ids, again));
  if (std::memcmp(&again, &third, sizeof again) != 0) {
    plantscale::fuzz::Fail("Decode(Encode(m)) != m");
  }
  // Identifier bits above the 11 of a standard frame are not looked at.
  if (again.can_id != (frame.can_id & CAN_SFF_MASK) || again.can_dlc != frame.can_dlc ||
      std::memcmp(again.data, frame.data, frame.can_dlc) != 0) {
    plantscale::fuzz::Fail("an accepted frame does not encode back to its bytes");
  }
}

void Drain(int fd) {
  can_frame f;
  while (::read(fd, &f, sizeof f) > 0) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  can::ProtocolIds ids;
  ids.base_id = static_cast<uint32_t>(((data[0] | (data[1] << 8)) % 256) * 8);
  can::BarLinkOptions options;
  options.ids = ids;
  options.num_nozzles = 1 + data[2] % can::kMaxNozzles;
  auto [vehicle_fd, bar_fd] = can::CanFramePipe();
  const int bar = bar_fd.get();
  can::SprayBar vehicle(std::move(vehicle_fd), options, "fuzz");
  int64_t utime = 1'000'000;
  size_t i = 3;
  while (i < size) {
    const uint8_t op = data[i++];
    switch (op % 4) {
      case 0: {
        if (size - i < sizeof(can_frame)) return 0;
        can_frame frame;
        std::memcpy(&frame, data + i, sizeof frame);
        i += sizeof frame;
        CheckDecode(ids, frame);
        if (::write(bar, &frame, sizeof frame) < 0) {
          vehicle.Poll(utime);
          (void)!::write(bar, &frame, sizeof frame);
        }
        break;
      }
      case 1: {
        if (i >= size) return 0;
        const size_t n = data[i++] % sizeof(can_frame);
        if (size - i < n) return 0;
        (void)!::write(bar, data + i, n);
        i += n;
        break;
      }
      case 2: {
        if (size - i < 8) return 0;
        uint64_t mask = 0;
        std::memcpy(&mask, data + i, 8);
        i += 8;
        if (options.num_nozzles < 64) mask &= (uint64_t{1} << options.num_nozzles) - 1;
        vehicle.Command(utime, mask);
        break;
      }
      default: {
        if (i >= size) return 0;
        utime += 1000 * static_cast<int64_t>(data[i++]);
        vehicle.Poll(utime);
        break;
      }
    }
    Drain(bar);
  }
  vehicle.Poll(utime);
  (void)vehicle.HealthFaults();
  return 0;
}
