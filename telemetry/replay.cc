#include "telemetry/replay.h"

#include <chrono>
#include <regex>
#include <thread>

#include "telemetry/log.h"

namespace plantscale::telemetry {

OptionErrors ReplayOptions::Validate() const {
  OptionErrors errors;
  RequirePositive(errors, "speed", speed);
  RequireNonNegative(errors, "start_s", start_s);
  try {
    std::regex check(channels);
  } catch (const std::regex_error& e) {
    errors.push_back(
        {"channels", "not a regular expression: '" + channels + "' (" + e.what() + ")"});
  }
  return errors;
}

ReplaySummary Replay(const std::filesystem::path& log, Transport& transport,
                     const ReplayOptions& options) {
  ThrowIfInvalid("replay options", options.Validate());
  using Clock = std::chrono::steady_clock;
  const std::regex channels(options.channels);
  LogReader reader(log);
  ReplaySummary summary;
  int64_t first_utime = -1;  // first event of the log
  int64_t start_utime = -1;  // first published event
  Clock::time_point wall_start;
  while (std::optional<LogEvent> e = reader.Next()) {
    if (first_utime < 0) first_utime = e->utime;
    if (e->utime - first_utime < static_cast<int64_t>(options.start_s * 1e6)) continue;
    if (!std::regex_match(e->channel, channels)) continue;
    if (start_utime < 0) {
      start_utime = e->utime;
      wall_start = Clock::now();
    }
    const double log_s = 1e-6 * static_cast<double>(e->utime - start_utime);
    std::this_thread::sleep_until(wall_start +
                                  std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(log_s / options.speed)));
    transport.Publish(e->channel, e->data.data(), e->data.size());
    ++summary.published;
    summary.log_seconds = log_s;
  }
  summary.events_read = reader.events_read();
  if (start_utime >= 0) {
    summary.wall_seconds = std::chrono::duration<double>(Clock::now() - wall_start).count();
  }
  summary.error = reader.error();
  return summary;
}

}  // namespace plantscale::telemetry
