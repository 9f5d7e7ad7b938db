#pragma once
// Per-channel traffic of an LCM log: messages, rate and bandwidth
// (`plantscale telemetry-stats`). Rates use the log's span from its first
// to its last event.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

namespace plantscale::telemetry {

struct ChannelTraffic {
  int64_t messages = 0;
  int64_t bytes = 0;      // payload bytes
  int64_t max_bytes = 0;  // largest message
  double rate_hz = 0.0;
  double kbit_s = 0.0;  // payload kilobits (1000 bits) per second
};

struct LogTraffic {
  std::map<std::string, ChannelTraffic> channels;
  int64_t events = 0;
  double duration_s = 0.0;
  double total_kbit_s = 0.0;
  std::string error;  // LogReader::error(): the log was cut off or not a log
};

// Throws LogError when the file cannot be opened.
LogTraffic MeasureLog(const std::filesystem::path& log);

}  // namespace plantscale::telemetry
