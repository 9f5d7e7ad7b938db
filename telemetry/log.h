#pragma once
// LCM logs in LCM's own event-log format (liblcm's lcm_eventlog through
// lcm::LogFile), so lcm-logger, lcm-logplayer and lcm-spy read them
// unchanged. The vehicle writes its own log (LoggingTransport) so that
// logging works with any URL, memq:// included; each event is flushed, so a
// crash keeps everything written before it. A write that fails (disk full,
// file size limit) is cut back off the file: the log stays whole up to the
// last event written (docs/faults.md).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "telemetry/transport.h"

namespace lcm {
class LogFile;
}

namespace plantscale::telemetry {

// A log that cannot be opened, written, or read to its end. what() names
// the file and, for reading, the byte offset of the first bad event.
class LogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LogEvent {
  int64_t eventnum = 0;
  int64_t utime = 0;  // when it was logged (publish time), microseconds
  std::string channel;
  std::vector<uint8_t> data;
};

class LogWriter {
 public:
  // Throws LogError naming the file when it cannot be created.
  explicit LogWriter(const std::filesystem::path& path);
  ~LogWriter();
  // Writes and flushes one event; throws LogError on a write failure, after
  // closing the file and cutting off what was written of the event (the log
  // then ends with the last whole event; Write throws until Reopen).
  void Write(const std::string& channel, const void* data, size_t size, int64_t utime);
  // After a write failure: opens the log again to append; throws LogError
  // when it cannot.
  void Reopen();
  bool open() const { return file_ != nullptr; }
  int64_t events() const { return events_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  bool CutBack();  // closes the file and truncates it to whole_bytes_ (false: could not)

  std::filesystem::path path_;
  std::unique_ptr<lcm::LogFile> file_;
  int64_t events_ = 0;
  int64_t whole_bytes_ = 0;  // the file's size after the last whole event
};

class LogReader {
 public:
  // Throws LogError naming the file when it cannot be opened.
  explicit LogReader(const std::filesystem::path& path);
  ~LogReader();
  // The next whole event, or nullopt at the end of the log or at the first
  // event that is cut off or not an LCM event (then error() says where).
  std::optional<LogEvent> Next();
  // Empty when the whole file was read; else "FILE: ... at byte offset N".
  const std::string& error() const { return error_; }
  int64_t events_read() const { return events_read_; }

 private:
  std::filesystem::path path_;
  std::unique_ptr<lcm::LogFile> file_;
  int64_t size_ = 0;
  int64_t events_read_ = 0;
  std::string error_;
  bool done_ = false;
};

// The log's state as LoggingTransport sees it (for the vehicle's heartbeat).
struct LogStatus {
  bool writing = true;         // false while writes fail
  std::string error;           // the latest write failure (LogError::what)
  int64_t failed_utime = -1;   // when writing stopped (the clock's time), -1: never
  int64_t not_logged = 0;      // messages published but not logged, over the run
  int64_t failures = 0;        // times writing stopped
  int64_t resumed = 0;         // times it started again
};

// Publishes through `inner` and writes every published message to `log` with
// the time `clock` gives: wall-clock by default (LCM logger semantics); the
// vehicle runner passes its message clock so that a --fast simulated run
// logs simulated time and replays at the real pace.
//
// The log is written first, so a message the network refuses is still
// logged. A log write that fails never stops publishing: the log stays
// whole up to its last event, the messages published meanwhile are counted
// as not logged, and the log is opened again every `retry_us` of the clock
// until a write succeeds (status() says which).
class LoggingTransport : public Transport {
 public:
  using Clock = std::function<int64_t()>;
  LoggingTransport(Transport& inner, LogWriter& log, Clock clock = WallUtime,
                   int64_t retry_us = 1'000'000)
      : inner_(inner), log_(log), clock_(std::move(clock)), retry_us_(retry_us) {}
  // Throws what `inner` throws (after logging).
  void Publish(const std::string& channel, const void* data, size_t size) override;
  const LogStatus& status() const { return status_; }
  void Subscribe(const std::string& channel_regex, Handler handler) override {
    inner_.Subscribe(channel_regex, std::move(handler));
  }
  bool Handle(int timeout_ms) override { return inner_.Handle(timeout_ms); }

 private:
  void Log(const std::string& channel, const void* data, size_t size);

  Transport& inner_;
  LogWriter& log_;
  Clock clock_;
  int64_t retry_us_;
  int64_t next_retry_utime_ = 0;
  LogStatus status_;
};

}  // namespace plantscale::telemetry
