#include "telemetry/log.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <system_error>

namespace plantscale::telemetry {

LogWriter::LogWriter(const std::filesystem::path& path)
    : path_(path), file_(std::make_unique<lcm::LogFile>(path.string(), "w")) {
  if (!file_->good()) throw LogError(path.string() + ": cannot create the LCM log");
}

LogWriter::~LogWriter() = default;

void LogWriter::Write(const std::string& channel, const void* data, size_t size, int64_t utime) {
  lcm::LogEvent event;
  event.eventnum = events_;
  event.timestamp = utime;
  event.channel = channel;
  event.datalen = static_cast<int32_t>(size);
  event.data = const_cast<void*>(data);  // lcm::LogEvent is not const-correct; only read
  if (!file_) throw LogError(path_.string() + ": not open (an earlier write failed)");
  errno = 0;
  if (file_->writeEvent(&event) != 0 || std::fflush(file_->getFilePtr()) != 0) {
    const std::string why = errno != 0 ? std::strerror(errno) : "short write";
    const std::string cut = CutBack() ? "the log ends with the last whole event, at byte "
                                      : "could not cut the log back to its whole events, at byte ";
    throw LogError(path_.string() + ": write failed after " + std::to_string(events_) +
                   " events (" + why + "); " + cut + std::to_string(whole_bytes_));
  }
  ++events_;
  whole_bytes_ = std::ftell(file_->getFilePtr());
}

// What the failed write left in the file (part of an event) and in the
// stream's buffer goes: closing flushes the buffer (it fails again, or
// writes more of the event), then the file is cut back to its whole events.
bool LogWriter::CutBack() {
  file_.reset();
  return ::truncate(path_.c_str(), static_cast<off_t>(whole_bytes_)) == 0;
}

void LogWriter::Reopen() {
  if (file_) return;
  auto file = std::make_unique<lcm::LogFile>(path_.string(), "a");
  if (!file->good()) throw LogError(path_.string() + ": cannot open the LCM log again to append");
  file_ = std::move(file);
}

LogReader::LogReader(const std::filesystem::path& path)
    : path_(path), file_(std::make_unique<lcm::LogFile>(path.string(), "r")) {
  std::error_code ec;
  size_ = static_cast<int64_t>(std::filesystem::file_size(path, ec));
  if (!file_->good() || ec || std::filesystem::is_directory(path)) {
    throw LogError(path.string() + ": cannot open the LCM log");
  }
}

LogReader::~LogReader() = default;

namespace {

// Whether the event header at `offset` (magic, eventnum, timestamp, channel
// and data lengths, big-endian) starts a whole event of the file (`size`:
// its size, updated).
// liblcm would skip bytes up to the next magic, and allocates the declared
// data length (up to 2 GB when corrupt) before it finds the bytes missing;
// the reader stops at such an event instead (found by tests/fuzz/log_fuzz).
bool WholeEventAt(std::FILE* f, int64_t offset, int64_t& size) {
  // A log still being written has grown since it was opened.
  struct stat st {};
  if (::fstat(::fileno(f), &st) == 0) size = std::max<int64_t>(size, st.st_size);
  std::clearerr(f);  // an end of file met before: the log may have grown since
  uint8_t h[28];
  const size_t got = std::fread(h, 1, sizeof h, f);
  std::fseek(f, static_cast<long>(offset), SEEK_SET);
  if (got != sizeof h) return false;
  const auto u32 = [&h](int at) {
    return (uint32_t{h[at]} << 24) | (uint32_t{h[at + 1]} << 16) | (uint32_t{h[at + 2]} << 8) |
           uint32_t{h[at + 3]};
  };
  constexpr uint32_t kMagic = 0xEDA1DA01;
  const auto channel = static_cast<int32_t>(u32(20));
  const auto data = static_cast<int32_t>(u32(24));
  return u32(0) == kMagic && channel > 0 && channel < 1000 && data >= 0 &&
         offset + int64_t{sizeof h} + channel + data <= size;
}

}  // namespace

std::optional<LogEvent> LogReader::Next() {
  if (done_) return std::nullopt;
  const int64_t offset = std::ftell(file_->getFilePtr());
  const lcm::LogEvent* e =
      WholeEventAt(file_->getFilePtr(), offset, size_) ? file_->readNextEvent() : nullptr;
  if (!e) {
    done_ = true;
    if (offset < size_) {
      error_ = path_.string() + ": " +
               (events_read_ == 0 ? std::string("not an LCM log, or its first event is cut off")
                                  : std::string("event cut off or corrupt")) +
               " at byte offset " + std::to_string(offset) + " of " + std::to_string(size_) + " (" +
               std::to_string(events_read_) + " whole events read before it)";
    }
    return std::nullopt;
  }
  ++events_read_;
  const auto* bytes = static_cast<const uint8_t*>(e->data);
  return LogEvent{e->eventnum, e->timestamp, e->channel,
                  std::vector<uint8_t>(bytes, bytes + e->datalen)};
}

void LoggingTransport::Publish(const std::string& channel, const void* data, size_t size) {
  Log(channel, data, size);
  inner_.Publish(channel, data, size);
}

void LoggingTransport::Log(const std::string& channel, const void* data, size_t size) {
  const int64_t now = clock_();
  if (!status_.writing) {
    if (now < next_retry_utime_) {
      ++status_.not_logged;
      return;
    }
    try {
      log_.Reopen();
    } catch (const LogError& e) {
      status_.error = e.what();
    }
  }
  try {
    log_.Write(channel, data, size, now);
    if (!status_.writing) ++status_.resumed;
    status_.writing = true;
  } catch (const LogError& e) {
    if (status_.writing) ++status_.failures, status_.failed_utime = now;
    status_.writing = false;
    status_.error = e.what();
    ++status_.not_logged;
    next_retry_utime_ = now + retry_us_;
  }
}

}  // namespace plantscale::telemetry
