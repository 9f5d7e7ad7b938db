#include "telemetry/can/spray_bar.h"

#include <fcntl.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "engine/common/check.h"

namespace plantscale::telemetry::can {
namespace {

std::string Errno(int e) { return std::strerror(e); }

std::string Seconds(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f s", s);
  return b;
}

std::string Mask(uint32_t m) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%08X", m);
  return b;
}

}  // namespace

UniqueFd& UniqueFd::operator=(UniqueFd&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.Release();
  }
  return *this;
}

UniqueFd::~UniqueFd() {
  if (fd_ >= 0) ::close(fd_);
}

int UniqueFd::Release() {
  const int fd = fd_;
  fd_ = -1;
  return fd;
}

std::pair<UniqueFd, UniqueFd> CanFramePipe() {
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds) != 0) {
    throw CanError("socketpair(AF_UNIX, SOCK_SEQPACKET) for CAN frames: " + Errno(errno));
  }
  return {UniqueFd(fds[0]), UniqueFd(fds[1])};
}

UniqueFd OpenSocketCan(const std::string& interface, const ProtocolIds& ids) {
  ThrowIfInvalid("CAN protocol ids", ids.Validate());
  const std::string what = "cannot open CAN interface '" + interface + "': ";
  if (interface.empty()) throw CanError(what + "empty interface name");
  if (interface.size() >= IFNAMSIZ) {
    throw CanError(what + "name longer than " + std::to_string(IFNAMSIZ - 1) +
                   " characters (IFNAMSIZ)");
  }
  // Whether the interface exists does not depend on CAN support: say both.
  const bool exists = ::if_nametoindex(interface.c_str()) != 0;
  const std::string missing = "no such network interface (" + Errno(ENODEV) +
                              "; `ip link` lists them, a virtual bus is `ip link add dev " +
                              interface + " type vcan`)";
  UniqueFd fd(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (fd.get() < 0) {
    const int e = errno;
    std::string hint;
    if (e == EAFNOSUPPORT) hint = " (this kernel has no SocketCAN: modules can and can_raw)";
    throw CanError(what + "socket(PF_CAN, SOCK_RAW, CAN_RAW): " + Errno(e) + hint +
                   (exists ? "" : "; and " + missing));
  }
  if (!exists) throw CanError(what + missing);
  ifreq ifr;
  std::memset(&ifr, 0, sizeof ifr);
  std::memcpy(ifr.ifr_name, interface.c_str(), interface.size());
  if (::ioctl(fd.get(), SIOCGIFINDEX, &ifr) != 0) {
    throw CanError(what + "ioctl(SIOCGIFINDEX): " + Errno(errno));
  }
  const can_filter filter = ids.Filter();
  if (::setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_FILTER, &filter, sizeof filter) != 0) {
    throw CanError(what + "setsockopt(CAN_RAW_FILTER): " + Errno(errno));
  }
  const can_err_mask_t errors = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_TX_TIMEOUT;
  if (::setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors) != 0) {
    throw CanError(what + "setsockopt(CAN_RAW_ERR_FILTER): " + Errno(errno));
  }
  sockaddr_can addr;
  std::memset(&addr, 0, sizeof addr);
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(fd.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    const int e = errno;
    throw CanError(what + "bind: " + Errno(e) +
                   (e == ENODEV ? " (not a CAN interface, or it is down)" : ""));
  }
  return fd;
}

OptionErrors BarLinkOptions::Validate() const {
  OptionErrors errors = Prefixed("ids", ids.Validate());
  RequireInRange(errors, "num_nozzles", num_nozzles, 1, kMaxNozzles);
  RequirePositive(errors, "heartbeat_timeout_s", heartbeat_timeout_s);
  RequirePositive(errors, "ack_timeout_s", ack_timeout_s);
  RequireInRange(errors, "hold_s", hold_s, 0.001, 65.535);
  RequireInRange(errors, "recover_heartbeats", recover_heartbeats, 1, 1000);
  return errors;
}

SprayBar::SprayBar(UniqueFd fd, const BarLinkOptions& options, std::string endpoint)
    : fd_(std::move(fd)), options_(options), endpoint_(std::move(endpoint)) {
  ThrowIfInvalid("spray bar options", options_.Validate());
  PLANTSCALE_CHECK(fd_.get() >= 0, "spray bar needs an open file descriptor");
  const int flags = ::fcntl(fd_.get(), F_GETFL);
  if (flags < 0 || ::fcntl(fd_.get(), F_SETFL, flags | O_NONBLOCK) != 0) {
    throw CanError("spray bar " + endpoint_ + ": fcntl(O_NONBLOCK): " + Errno(errno));
  }
  status_.nozzle_faults.assign(static_cast<size_t>(options_.num_nozzles), NozzleFault::kNone);
  status_.reasons = {"waiting for the bar's first heartbeat"};
  trouble_ = status_.reasons.front();
}

SprayBar SprayBar::Open(const std::string& interface, const BarLinkOptions& options) {
  ThrowIfInvalid("spray bar options", options.Validate());
  return SprayBar(OpenSocketCan(interface, options.ids), options, interface);
}

void SprayBar::Trouble(const std::string& text) {
  trouble_ = text;
  good_heartbeats_ = 0;
  status_.last_error = text;
}

void SprayBar::ReadAll(int64_t utime) {
  // Bounded: a babbling bus cannot keep the caller here.
  constexpr int kMaxFramesPerPoll = 1024;
  for (int frames = 0; frames < kMaxFramesPerPoll && !peer_closed_; ++frames) {
    can_frame frame;
    const ssize_t n = ::read(fd_.get(), &frame, sizeof frame);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return;
      if (errno == EINTR) continue;
      ++status_.frames_rejected;
      Trouble("read failed: " + Errno(errno));
      return;
    }
    if (n == 0) {
      peer_closed_ = true;
      Trouble("the bar's endpoint closed the connection");
      return;
    }
    if (static_cast<size_t>(n) != sizeof frame) {
      ++status_.frames_rejected;
      Trouble("read " + std::to_string(n) + " bytes, a CAN frame is " +
              std::to_string(sizeof frame));
      continue;
    }
    try {
      Handle(utime, Decode(options_.ids, frame));
    } catch (const CanProtocolError& e) {
      ++status_.frames_rejected;
      Trouble(e.what());
    }
  }
}

void SprayBar::Handle(int64_t utime, const BarMessage& message) {
  if (std::holds_alternative<NozzleCommand>(message)) {
    throw CanProtocolError(
        "CAN frame " + Describe(Encode(options_.ids, std::get<NozzleCommand>(message))) +
        ": nozzle command received from the bar side (another master on the bus?)");
  }
  if (const auto* ack = std::get_if<NozzleAck>(&message)) OnAck(*ack);
  if (const auto* hb = std::get_if<BarHeartbeat>(&message)) OnHeartbeat(utime, *hb);
  if (const auto* faults = std::get_if<NozzleFaults>(&message)) OnFaults(*faults);
}

void SprayBar::OnAck(const NozzleAck& ack) {
  ++status_.acks;
  const std::string seq = "seq " + std::to_string(ack.seq);
  size_t index = 0;
  while (index < outstanding_.size() && outstanding_[index].seq != ack.seq) ++index;
  if (index == outstanding_.size()) {
    Trouble("acknowledgement for " + seq + ", which is not an outstanding command");
    return;
  }
  if (index > 0) {
    ++status_.sequence_gaps;
    Trouble("acknowledgement sequence gap: expected seq " +
            std::to_string(outstanding_.front().seq) + ", got " + std::to_string(ack.seq) + " (" +
            std::to_string(index) + " command(s) never acknowledged)");
  }
  const Outstanding command = outstanding_[index];
  outstanding_.erase(outstanding_.begin(), outstanding_.begin() + static_cast<long>(index) + 1);
  const int shift = kSectionNozzles * command.section;
  const std::string where = seq + " (section " + std::to_string(command.section) + ")";
  if (ack.section != command.section) {
    Trouble("acknowledgement of command " + where + " names section " +
            std::to_string(ack.section));
    return;
  }
  status_.applied_mask = (status_.applied_mask & ~(uint64_t{0xFFFFFFFFu} << shift)) |
                         (uint64_t{ack.applied_mask} << shift);
  if (ack.status == AckStatus::kRejected) {
    Trouble("bar rejected command " + where + " (mask " + Mask(command.mask) + ")");
    return;
  }
  const auto faulty = static_cast<uint32_t>(FaultyMask() >> shift);
  const uint32_t extra = ack.applied_mask & ~command.mask;
  const uint32_t missing = command.mask & ~ack.applied_mask & ~faulty;
  if (extra != 0 || missing != 0) {
    Trouble("bar applied " + Mask(ack.applied_mask) + " for command " + where + ", commanded " +
            Mask(command.mask));
  }
}

void SprayBar::OnHeartbeat(int64_t utime, const BarHeartbeat& hb) {
  ++status_.heartbeats;
  status_.heard = true;
  status_.last_heartbeat_utime = utime;
  status_.bar_state = hb.state;
  bool good = true;
  if (expect_counter_ && hb.counter != expected_counter_) {
    ++status_.sequence_gaps;
    const int lost = SeqDistance(expected_counter_, hb.counter);
    Trouble("heartbeat sequence gap: expected counter " + std::to_string(expected_counter_) +
            ", got " + std::to_string(hb.counter) +
            (lost < 128 ? " (" + std::to_string(lost) + " lost)" : " (old or repeated)"));
    good = false;
  }
  expect_counter_ = true;
  expected_counter_ = static_cast<uint8_t>(hb.counter + 1);
  if (hb.protocol_version != kProtocolVersion) {
    Trouble("bar speaks protocol version " + std::to_string(hb.protocol_version) + ", expected " +
            std::to_string(kProtocolVersion));
    good = false;
  }
  if (hb.num_nozzles != options_.num_nozzles) {
    Trouble("bar has " + std::to_string(hb.num_nozzles) + " nozzles, configured for " +
            std::to_string(options_.num_nozzles));
    good = false;
  }
  if (hb.state == BarState::kFault) {
    Trouble("bar reports a bar-level fault (heartbeat state 2: supply or pressure)");
    good = false;
  }
  if (good && !trouble_.empty() && ++good_heartbeats_ >= options_.recover_heartbeats) {
    trouble_.clear();
  }
}

void SprayBar::OnFaults(const NozzleFaults& faults) {
  for (int j = 0; j < kSectionNozzles; ++j) {
    const int i = kSectionNozzles * faults.section + j;
    const NozzleFault fault = faults.fault[static_cast<size_t>(j)];
    if (i < options_.num_nozzles) {
      status_.nozzle_faults[static_cast<size_t>(i)] = fault;
    } else if (fault != NozzleFault::kNone) {
      Trouble("fault reported for nozzle " + std::to_string(i) + ", beyond the bar's " +
              std::to_string(options_.num_nozzles) + " nozzles");
    }
  }
}

uint64_t SprayBar::FaultyMask() const {
  uint64_t m = 0;
  for (size_t i = 0; i < status_.nozzle_faults.size(); ++i) {
    if (status_.nozzle_faults[i] != NozzleFault::kNone) m |= uint64_t{1} << i;
  }
  return m;
}

void SprayBar::Evaluate(int64_t utime) {
  if (start_utime_ < 0) start_utime_ = utime;
  std::vector<std::string> active;
  const double timeout_s = options_.heartbeat_timeout_s;
  if (!status_.heard) {
    const double waited_s = 1e-6 * static_cast<double>(utime - start_utime_);
    if (waited_s > timeout_s) {
      active.push_back("no heartbeat from the bar in " + Seconds(waited_s) +
                       " since start (timeout " + Seconds(timeout_s) + ")");
    } else {
      active.push_back("waiting for the bar's first heartbeat");
    }
  } else {
    const double silent_s = 1e-6 * static_cast<double>(utime - status_.last_heartbeat_utime);
    if (silent_s > timeout_s) {
      active.push_back("no heartbeat from the bar for " + Seconds(silent_s) + " (timeout " +
                       Seconds(timeout_s) + ")");
    }
  }
  if (!outstanding_.empty()) {
    const double waited_s = 1e-6 * static_cast<double>(utime - outstanding_.front().sent_utime);
    if (waited_s > options_.ack_timeout_s) {
      active.push_back("command seq " + std::to_string(outstanding_.front().seq) +
                       " not acknowledged in " + Seconds(waited_s) + " (timeout " +
                       Seconds(options_.ack_timeout_s) + ")");
      // Given up as lost (the reason stays latched): later acknowledgements
      // of newer commands are then in sequence again.
      outstanding_.clear();
    }
  }
  // Lasting conditions latch too: after they clear the bar must prove
  // itself with recover_heartbeats good heartbeats.
  if (!active.empty()) {
    trouble_ = active.front();
    good_heartbeats_ = 0;
  }
  if (!trouble_.empty() && (active.empty() || trouble_ != active.front())) {
    active.push_back("recovering from: " + trouble_ + " (" + std::to_string(good_heartbeats_) +
                     " of " + std::to_string(options_.recover_heartbeats) + " good heartbeats)");
  }
  status_.reasons = std::move(active);
  status_.failsafe = !status_.reasons.empty();
}

void SprayBar::Send(int64_t utime, uint64_t mask) {
  for (int section = 0; section < Sections(options_.num_nozzles); ++section) {
    SendSection(utime, section, static_cast<uint32_t>(mask >> (kSectionNozzles * section)));
  }
}

void SprayBar::SendSection(int64_t utime, int section, uint32_t mask) {
  NozzleCommand c;
  c.seq = next_seq_;
  c.flags = status_.failsafe ? NozzleCommand::kFlagFailsafe : 0;
  c.section = static_cast<uint8_t>(section);
  c.open_mask = mask;
  c.hold_ms = static_cast<uint16_t>(std::lround(options_.hold_s * 1e3));
  const can_frame frame = Encode(options_.ids, c);
  const ssize_t n = ::write(fd_.get(), &frame, sizeof frame);
  if (n != static_cast<ssize_t>(sizeof frame)) {
    Trouble("write of command seq " + std::to_string(c.seq) + " failed: " +
            (n < 0 ? Errno(errno) : "short write of " + std::to_string(n) + " bytes"));
    Evaluate(utime);
    return;
  }
  ++next_seq_;
  ++status_.commands_sent;
  const int shift = kSectionNozzles * section;
  status_.commanded_mask =
      (status_.commanded_mask & ~(uint64_t{0xFFFFFFFFu} << shift)) | (uint64_t{mask} << shift);
  outstanding_.push_back({c.seq, c.section, mask, utime});
  constexpr size_t kMaxOutstanding = 64;  // well inside the 256 sequence space
  while (outstanding_.size() > kMaxOutstanding) outstanding_.pop_front();
}

void SprayBar::Poll(int64_t utime) {
  ReadAll(utime);
  Evaluate(utime);
  if (status_.failsafe && status_.commanded_mask != 0) Send(utime, 0);
}

void SprayBar::Command(int64_t utime, uint64_t open_mask) {
  PLANTSCALE_CHECK(
      options_.num_nozzles >= 64 || (open_mask >> options_.num_nozzles) == 0,
      "nozzle mask has bits beyond the bar's " + std::to_string(options_.num_nozzles) + " nozzles");
  Evaluate(utime);
  status_.requested_mask = open_mask;
  Send(utime, status_.failsafe ? 0 : status_.requested_mask & ~FaultyMask());
}

std::function<void(int64_t, uint64_t)> SprayBar::Sink() {
  return [this](int64_t utime, uint64_t open_mask) {
    Poll(utime);
    Command(utime, open_mask);
  };
}

std::vector<std::string> SprayBar::HealthFaults() const {
  std::vector<std::string> lines;
  const std::string prefix = "spray bar " + endpoint_ + ": ";
  for (const std::string& r : status_.reasons) lines.push_back(prefix + "fail-safe: " + r);
  for (size_t i = 0; i < status_.nozzle_faults.size(); ++i) {
    if (status_.nozzle_faults[i] != NozzleFault::kNone) {
      lines.push_back(prefix + "nozzle " + std::to_string(i) + ": " +
                      NozzleFaultName(status_.nozzle_faults[i]));
    }
  }
  return lines;
}

}  // namespace plantscale::telemetry::can
