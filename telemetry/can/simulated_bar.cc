#include "telemetry/can/simulated_bar.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "engine/common/check.h"

namespace plantscale::telemetry::can {

OptionErrors SimulatedBarOptions::Validate() const {
  OptionErrors errors = Prefixed("ids", ids.Validate());
  RequireInRange(errors, "num_nozzles", num_nozzles, 1, kMaxNozzles);
  RequirePositive(errors, "heartbeat_period_s", heartbeat_period_s);
  return errors;
}

SimulatedBar::SimulatedBar(UniqueFd fd, const SimulatedBarOptions& options)
    : fd_(std::move(fd)), options_(options), reported_nozzles_(options.num_nozzles) {
  ThrowIfInvalid("simulated bar options", options_.Validate());
  faults_.assign(static_cast<size_t>(options_.num_nozzles), NozzleFault::kNone);
}

BarState SimulatedBar::state() const {
  if (bar_fault_) return BarState::kFault;
  return hold_until_utime_ < 0 ? BarState::kHoldExpired : BarState::kReady;
}

void SimulatedBar::InjectFault(int nozzle, NozzleFault fault) {
  PLANTSCALE_CHECK(nozzle >= 0 && nozzle < options_.num_nozzles, "no such nozzle");
  faults_[static_cast<size_t>(nozzle)] = fault;
  if (!silent_) SendFaults(nozzle / kSectionNozzles);  // on change, not only with the heartbeat
}

void SimulatedBar::SendFaults(int section) {
  NozzleFaults f;
  f.section = static_cast<uint8_t>(section);
  for (int j = 0; j < kSectionNozzles; ++j) {
    const size_t i = static_cast<size_t>(kSectionNozzles * section + j);
    if (i < faults_.size()) f.fault[static_cast<size_t>(j)] = faults_[i];
  }
  Send(Encode(options_.ids, f));
}

uint64_t SimulatedBar::HeldClosedMask() const {
  uint64_t m = 0;
  for (size_t i = 0; i < faults_.size(); ++i) {
    if (faults_[i] == NozzleFault::kOpenCircuit || faults_[i] == NozzleFault::kShortCircuit) {
      m |= uint64_t{1} << i;
    }
  }
  return m;
}

void SimulatedBar::Apply(int64_t utime, uint64_t mask) {
  if (mask == open_mask_) return;
  open_mask_ = mask;
  history_.push_back({utime, mask});
}

void SimulatedBar::Send(const can_frame& frame) { SendBytes(&frame, sizeof frame); }

void SimulatedBar::SendRaw(const can_frame& frame) { Send(frame); }

void SimulatedBar::SendBytes(const void* data, size_t size) {
  const ssize_t n = ::write(fd_.get(), data, size);
  PLANTSCALE_CHECK(n == static_cast<ssize_t>(size),
                   std::string("simulated bar write: ") + (n < 0 ? std::strerror(errno) : "short"));
}

void SimulatedBar::Step(int64_t utime) {
  for (;;) {
    can_frame frame;
    const ssize_t n = ::read(fd_.get(), &frame, sizeof frame);
    if (n <= 0) break;
    if (static_cast<size_t>(n) != sizeof frame) {
      errors_.push_back("read " + std::to_string(n) + " bytes");
      continue;
    }
    NozzleCommand c;
    try {
      const BarMessage m = Decode(options_.ids, frame);
      if (!std::holds_alternative<NozzleCommand>(m)) {
        errors_.push_back("not a command: " + Describe(frame));
        continue;
      }
      c = std::get<NozzleCommand>(m);
    } catch (const CanProtocolError& e) {
      errors_.push_back(e.what());
      continue;
    }
    commands_.push_back(c);
    NozzleAck ack;
    ack.seq = c.seq;
    ack.section = c.section;
    const int shift = kSectionNozzles * c.section;
    const int in_section = std::min(kSectionNozzles, options_.num_nozzles - shift);
    const uint64_t section_bits = uint64_t{0xFFFFFFFFu} << shift;
    const uint64_t rest = open_mask_ & ~section_bits;
    if (in_section <= 0 || (in_section < 32 && (c.open_mask >> in_section) != 0) || bar_fault_) {
      ack.status = AckStatus::kRejected;
      Apply(utime, rest);
    } else {
      Apply(utime, rest | ((uint64_t{c.open_mask} << shift) & ~HeldClosedMask()));
    }
    hold_until_utime_ = utime + static_cast<int64_t>(c.hold_ms) * 1000;
    ack.applied_mask = static_cast<uint32_t>(open_mask_ >> shift);
    if (!silent_) Send(Encode(options_.ids, ack));
  }
  if (hold_until_utime_ >= 0 && utime > hold_until_utime_) {
    hold_until_utime_ = -1;
    Apply(utime, 0);
  }
  if (bar_fault_) Apply(utime, 0);
  if (next_heartbeat_utime_ < 0 || utime >= next_heartbeat_utime_) {
    const int64_t period_us = std::llround(options_.heartbeat_period_s * 1e6);
    next_heartbeat_utime_ = (next_heartbeat_utime_ < 0 ? utime : next_heartbeat_utime_) + period_us;
    if (next_heartbeat_utime_ <= utime) next_heartbeat_utime_ = utime + period_us;
    if (!silent_) {
      BarHeartbeat hb;
      hb.counter = counter_;
      hb.state = state();
      hb.num_nozzles = static_cast<uint8_t>(reported_nozzles_);
      Send(Encode(options_.ids, hb));
      for (int section = 0; section < Sections(options_.num_nozzles); ++section) {
        SendFaults(section);
      }
    }
    ++counter_;
  }
}

std::vector<NozzleShot> ShotsFromValves(const std::vector<SimulatedBar::Valves>& history,
                                        int64_t end_utime) {
  std::vector<NozzleShot> shots;
  std::array<int64_t, kMaxNozzles> opened;
  opened.fill(-1);
  const auto close = [&](int nozzle, int64_t utime) {
    NozzleShot s;
    s.nozzle = nozzle;
    s.open_utime = opened[static_cast<size_t>(nozzle)];
    s.close_utime = utime;
    shots.push_back(s);
    opened[static_cast<size_t>(nozzle)] = -1;
  };
  for (const SimulatedBar::Valves& v : history) {
    for (int i = 0; i < kMaxNozzles; ++i) {
      const bool open = ((v.open_mask >> i) & 1u) != 0;
      const bool was_open = opened[static_cast<size_t>(i)] >= 0;
      if (open && !was_open) opened[static_cast<size_t>(i)] = v.utime;
      if (!open && was_open) close(i, v.utime);
    }
  }
  for (int i = 0; i < kMaxNozzles; ++i) {
    if (opened[static_cast<size_t>(i)] >= 0) close(i, end_utime);
  }
  return shots;
}

}  // namespace plantscale::telemetry::can
