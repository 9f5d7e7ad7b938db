#include "telemetry/publisher.h"

#include <algorithm>
#include <cmath>

#include "telemetry/channels.h"

namespace plantscale::telemetry {

std::map<std::string, ChannelLimit> PublisherOptions::DefaultChannelLimits() {
  using namespace channels;
  // Map tiles are sent once, when the bar has passed them: one dropped is a
  // hole in the map for good, so they are never dropped by the budget.
  return {{kGrid, {12.5, false}},     {kPlants, {12.5, false}},      {kMapTiles, {0.0, true}},
          {kNozzles, {12.5, true}},   {kHealth, {2.0, true}},        {kThumbnail, {2.0, false}},
          {kEvents, {0.0, true}},     {kOdometry, {12.5, false}},    {kPose, {12.5, false}},
          {kSimTruth, {12.5, false}}, {kSimTruthPose, {12.5, false}}};
}

OptionErrors PublisherOptions::Validate() const {
  OptionErrors errors;
  RequirePositive(errors, "budget_kbit_s", budget_kbit_s);
  RequirePositive(errors, "burst_s", burst_s);
  RequireInRange(errors, "rate_tolerance", rate_tolerance, 0.0, 0.5);
  for (const auto& [name, limit] : channels) {
    RequireNonNegative(errors, "channels." + name + ".max_rate_hz", limit.max_rate_hz);
  }
  RequireNonNegative(errors, "unlisted.max_rate_hz", unlisted.max_rate_hz);
  return errors;
}

Publisher::Publisher(Transport& transport, const PublisherOptions& options)
    : transport_(transport), options_(options) {
  ThrowIfInvalid("telemetry publisher options", options_.Validate());
  budget_bytes_ = options_.budget_kbit_s * 125.0 * options_.burst_s;
}

const ChannelLimit& Publisher::LimitFor(const std::string& channel) const {
  const auto it = options_.channels.find(channel);
  return it == options_.channels.end() ? options_.unlisted : it->second;
}

// Slots every 1/rate seconds of message time: a message takes the current
// slot if it is due (up to rate_tolerance of an interval early); the next
// slot is one interval later, and never less than half an interval after a
// late message, so a stream that paused does not burst to catch up.
bool Publisher::RateAllows(const std::string& channel, int64_t utime) {
  const ChannelLimit& limit = LimitFor(channel);
  if (limit.max_rate_hz <= 0.0) return true;
  const auto interval = static_cast<int64_t>(std::llround(1e6 / limit.max_rate_hz));
  const auto tolerance = static_cast<int64_t>(std::llround(options_.rate_tolerance * interval));
  auto [it, first] = next_slot_utime_.try_emplace(channel, utime);
  if (!first && utime + tolerance < it->second) {
    ++counters_[channel].dropped_rate;
    return false;
  }
  it->second = std::max(it->second + interval, utime + interval - tolerance);
  if (first) it->second = utime + interval;
  return true;
}

bool Publisher::Due(const std::string& channel, int64_t utime) const {
  const ChannelLimit& limit = LimitFor(channel);
  const auto it = next_slot_utime_.find(channel);
  if (limit.max_rate_hz <= 0.0 || it == next_slot_utime_.end()) return true;
  const double tolerance_us = options_.rate_tolerance * 1e6 / limit.max_rate_hz;
  return static_cast<double>(utime) + tolerance_us >= static_cast<double>(it->second);
}

// Token bucket over message time: budget_kbit_s fills it, burst_s caps it.
bool Publisher::BudgetAllows(const ChannelLimit& limit, size_t bytes, int64_t utime) {
  const double rate_bytes_s = options_.budget_kbit_s * 125.0;
  if (budget_utime_ >= 0 && utime > budget_utime_) {
    budget_bytes_ += rate_bytes_s * 1e-6 * static_cast<double>(utime - budget_utime_);
    budget_bytes_ = std::min(budget_bytes_, rate_bytes_s * options_.burst_s);
  }
  budget_utime_ = std::max(budget_utime_, utime);
  const double needed = static_cast<double>(bytes);
  if (budget_bytes_ < needed && !limit.essential) return false;
  budget_bytes_ -= needed;
  return true;
}

bool Publisher::PublishBytes(const std::string& channel, const Bytes& bytes, int64_t utime) {
  ChannelCounters& c = counters_[channel];
  if (!BudgetAllows(LimitFor(channel), bytes.size(), utime)) {
    ++c.dropped_budget;
    return false;
  }
  return Send(channel, bytes, utime);
}

bool Publisher::Send(const std::string& channel, const Bytes& bytes, int64_t utime) {
  ChannelCounters& c = counters_[channel];
  try {
    transport_.Publish(channel, bytes.data(), bytes.size());
  } catch (const TransportError& e) {
    ++c.failed;
    ++failures_.count;
    failures_.last_utime = utime;
    failures_.last_error = e.what();
    return false;
  }
  ++c.sent;
  c.bytes += static_cast<int64_t>(bytes.size());
  return true;
}

int64_t Publisher::total_dropped() const {
  int64_t n = 0;
  for (const auto& [name, c] : counters_) n += c.dropped_rate + c.dropped_budget;
  return n;
}

}  // namespace plantscale::telemetry
