#include "telemetry/log_stats.h"

#include <algorithm>

#include "telemetry/log.h"

namespace plantscale::telemetry {

LogTraffic MeasureLog(const std::filesystem::path& log) {
  LogReader reader(log);
  LogTraffic traffic;
  int64_t first = 0;
  int64_t last = 0;
  int64_t total_bytes = 0;
  while (std::optional<LogEvent> e = reader.Next()) {
    if (traffic.events == 0) first = e->utime;
    last = std::max(last, e->utime);
    ChannelTraffic& c = traffic.channels[e->channel];
    ++c.messages;
    c.bytes += static_cast<int64_t>(e->data.size());
    c.max_bytes = std::max(c.max_bytes, static_cast<int64_t>(e->data.size()));
    total_bytes += static_cast<int64_t>(e->data.size());
    ++traffic.events;
  }
  traffic.error = reader.error();
  // In doubles: corrupt utimes far apart overflow int64 (found by fuzzing).
  traffic.duration_s =
      traffic.events > 1 ? 1e-6 * (static_cast<double>(last) - static_cast<double>(first)) : 0.0;
  if (traffic.duration_s <= 0.0) return traffic;
  for (auto& [name, c] : traffic.channels) {
    c.rate_hz = static_cast<double>(c.messages) / traffic.duration_s;
    c.kbit_s = 8e-3 * static_cast<double>(c.bytes) / traffic.duration_s;
  }
  traffic.total_kbit_s = 8e-3 * static_cast<double>(total_bytes) / traffic.duration_s;
  return traffic;
}

}  // namespace plantscale::telemetry
