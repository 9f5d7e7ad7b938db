#include "telemetry/log.h"

#include <gtest/gtest.h>
#include <lcm/eventlog.h>

#include <sys/resource.h>

#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <fstream>
#include <string>

#include "telemetry/log_stats.h"
#include "telemetry/testing.h"

namespace plantscale::telemetry {
namespace {

namespace fs = std::filesystem;

fs::path TempLog(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("plantscale_log_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

// Events 0..n-1 on two channels, 10 ms apart, payload i+1 bytes of value i.
void WriteLog(const fs::path& path, int n) {
  LogWriter w(path);
  for (int i = 0; i < n; ++i) {
    const std::string payload(static_cast<size_t>(i + 1), static_cast<char>(i));
    w.Write(i % 2 ? "PLANTSCALE_B" : "PLANTSCALE_A", payload.data(), payload.size(),
            1'000'000 + 10'000LL * i);
  }
}

TEST(Log, WrittenLogIsReadByLiblcmsOwnReader) {
  const fs::path path = TempLog("plain.lcmlog");
  WriteLog(path, 5);
  lcm_eventlog_t* log = lcm_eventlog_create(path.c_str(), "r");
  ASSERT_NE(log, nullptr);
  int n = 0;
  while (lcm_eventlog_event_t* e = lcm_eventlog_read_next_event(log)) {
    EXPECT_EQ(e->timestamp, 1'000'000 + 10'000LL * n);
    EXPECT_EQ(std::string(e->channel, static_cast<size_t>(e->channellen)),
              n % 2 ? "PLANTSCALE_B" : "PLANTSCALE_A");
    EXPECT_EQ(e->datalen, n + 1);
    EXPECT_EQ(static_cast<const char*>(e->data)[0], static_cast<char>(n));
    lcm_eventlog_free_event(e);
    ++n;
  }
  lcm_eventlog_destroy(log);
  EXPECT_EQ(n, 5);
}

TEST(Log, TruncatedLogKeepsWholeEventsAndNamesFileAndOffset) {
  const fs::path path = TempLog("cut.lcmlog");
  WriteLog(path, 4);
  const auto full = static_cast<int64_t>(fs::file_size(path));
  fs::resize_file(path, static_cast<uintmax_t>(full - 2));  // cut into the last event
  LogReader r(path);
  int n = 0;
  while (r.Next()) ++n;
  EXPECT_EQ(n, 3);
  // Each event: 28-byte header + 12-char channel + payload (1..4 bytes).
  const int64_t offset_of_fourth = 3 * (28 + 12) + 1 + 2 + 3;
  EXPECT_NE(r.error().find(path.string()), std::string::npos) << r.error();
  EXPECT_NE(r.error().find("byte offset " + std::to_string(offset_of_fourth)), std::string::npos)
      << r.error();
}

// Found by tests/fuzz/log_fuzz: liblcm allocated a corrupt header's data
// length (2 GB) before finding the bytes missing, and skipped garbage to the
// next magic. The reader stops at such an event and says where.
TEST(Log, CorruptEventHeaderOrGarbageEndsTheLogAtItsOffset) {
  const fs::path path = TempLog("huge.lcmlog");
  WriteLog(path, 2);
  const auto whole = static_cast<int64_t>(fs::file_size(path));
  {
    std::ofstream out(path, std::ios::binary | std::ios::app);
    const unsigned char header[28] = {0xED, 0xA1, 0xDA, 0x01, 0, 0, 0, 0, 0, 0, 0, 2, 0, 0,
                                      0,    0,    0,    0,    0, 0, 0, 0, 0, 3, 0x7F, 0xFF, 0xFF, 0xFF};
    out.write(reinterpret_cast<const char*>(header), sizeof header);
    out << "abc" << std::string(64, 'x');
  }
  LogReader r(path);
  int n = 0;
  while (r.Next()) ++n;
  EXPECT_EQ(n, 2);
  EXPECT_NE(r.error().find("byte offset " + std::to_string(whole)), std::string::npos) << r.error();

  // Garbage before the first event: liblcm would skip to the next magic.
  fs::resize_file(path, static_cast<uintmax_t>(whole));
  std::string events(static_cast<size_t>(whole), '\0');
  std::ifstream(path, std::ios::binary).read(events.data(), whole);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << "garbage" << events;
  LogReader g(path);
  EXPECT_FALSE(g.Next().has_value());
  EXPECT_NE(g.error().find("not an LCM log"), std::string::npos) << g.error();
}

// The event header check reads the file's size as it is now, not as it
// was when the reader was opened.
TEST(Log, EventsWrittenAfterTheReaderOpenedAreRead) {
  const fs::path path = TempLog("growing.lcmlog");
  LogWriter w(path);
  w.Write("A", "1", 1, 1);
  LogReader r(path);
  w.Write("A", "22", 2, 2);
  ASSERT_TRUE(r.Next().has_value());
  ASSERT_TRUE(r.Next().has_value());
  EXPECT_FALSE(r.Next().has_value());
  EXPECT_TRUE(r.error().empty()) << r.error();
}

TEST(Log, FileThatIsNotALogIsReportedNotCrashed) {
  const fs::path path = TempLog("not_a_log.txt");
  std::ofstream(path) << "this is a text file, not an LCM event log\n";
  LogReader r(path);
  EXPECT_FALSE(r.Next().has_value());
  EXPECT_NE(r.error().find("not an LCM log"), std::string::npos) << r.error();
  EXPECT_THROW(LogReader(TempLog("missing.lcmlog")), LogError);
  EXPECT_THROW(LogWriter(TempLog("no_such_dir") / "x.lcmlog"), LogError);
}

TEST(Log, LoggingTransportLogsWhatItPublishesAtItsClock) {
  const fs::path path = TempLog("logged.lcmlog");
  {
    testing::RecordingTransport inner;
    LogWriter w(path);
    int64_t now = 5'000'000;
    LoggingTransport t(inner, w, [&] { return now; });
    t.Publish("PLANTSCALE_X", "ab", 2);
    now += 500'000;
    t.Publish("PLANTSCALE_X", "cd", 2);
    EXPECT_EQ(inner.sent.size(), 2u);
  }
  LogReader r(path);
  const auto a = r.Next();
  const auto b = r.Next();
  ASSERT_TRUE(a && b);
  EXPECT_EQ(b->utime - a->utime, 500'000);
  EXPECT_EQ(std::string(b->data.begin(), b->data.end()), "cd");
}


// The disk fills (a file size limit, as a full disk to write(): the limit
// falls inside the next event): the write throws, what it wrote of the
// event is cut off, the log reads whole up to the event before it, and
// after Reopen the log goes on after it.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(uintmax_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit r = saved_;
    r.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &r);
  }
  ~FileSizeLimit() { ::setrlimit(RLIMIT_FSIZE, &saved_); }

 private:
  rlimit saved_{};
};

TEST(Log, AWriteThatFailsIsCutOffAndTheLogReadsWhole) {
  const fs::path path = TempLog("full.lcmlog");
  const std::string payload(1000, 'p');
  LogWriter w(path);
  for (int i = 0; i < 5; ++i) w.Write("A", payload.data(), payload.size(), i);
  const uintmax_t whole = fs::file_size(path);
  {
    const FileSizeLimit disk(whole + 300);  // 300 bytes of the next event fit
    EXPECT_THROW(w.Write("A", payload.data(), payload.size(), 5), LogError);
    EXPECT_FALSE(w.open());
    EXPECT_THROW(w.Write("A", payload.data(), payload.size(), 6), LogError);  // until Reopen
  }
  EXPECT_EQ(fs::file_size(path), whole);
  {
    LogReader r(path);
    int n = 0;
    while (r.Next()) ++n;
    EXPECT_EQ(n, 5);
    EXPECT_EQ(r.error(), "");
  }
  w.Reopen();
  w.Write("B", "after", 5, 7);
  LogReader r(path);
  std::vector<LogEvent> events;
  while (auto e = r.Next()) events.push_back(*e);
  EXPECT_EQ(r.error(), "");
  ASSERT_EQ(events.size(), 6u);
  EXPECT_EQ(events.back().channel, "B");
  EXPECT_EQ(events.back().utime, 7);
}

// A log that cannot be written never stops publishing: the messages are
// counted as not logged, and the log is tried again every retry period.
TEST(Log, LoggingTransportGoesOnPublishingWhenTheLogFails) {
  const fs::path path = TempLog("full_transport.lcmlog");
  testing::RecordingTransport inner;
  LogWriter w(path);
  int64_t now = 0;
  LoggingTransport t(inner, w, [&] { return now; }, 1'000'000);
  const std::string payload(500, 'q');
  t.Publish("A", payload.data(), payload.size());
  const uintmax_t whole = fs::file_size(path);
  {
    const FileSizeLimit disk(whole + 100);
    for (int i = 0; i < 20; ++i, now += 100'000) t.Publish("A", payload.data(), payload.size());
    EXPECT_FALSE(t.status().writing);
    EXPECT_EQ(t.status().failures, 1);
    EXPECT_EQ(t.status().failed_utime, 0);
    EXPECT_NE(t.status().error.find("File too large"), std::string::npos) << t.status().error;
  }
  EXPECT_EQ(inner.sent.size(), 21u);  // all published
  now += 50'000;                      // 2.05 s: a retry is due (last at 2.0 s)
  t.Publish("B", "x", 1);
  EXPECT_TRUE(t.status().writing);
  EXPECT_EQ(t.status().resumed, 1);
  EXPECT_EQ(t.status().not_logged, 20);
  LogReader r(path);
  std::vector<LogEvent> events;
  while (auto e = r.Next()) events.push_back(*e);
  EXPECT_EQ(r.error(), "");
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events.back().channel, "B");
}

TEST(LogStats, RatesAndBandwidthPerChannel) {
  const fs::path path = TempLog("stats.lcmlog");
  {
    LogWriter w(path);
    const std::string payload(1000, 'x');
    for (int i = 0; i <= 100; ++i) {  // 101 events over exactly 10 s
      w.Write(i % 4 ? "A" : "B", payload.data(), payload.size(), 100'000LL * i);
    }
  }
  const LogTraffic t = MeasureLog(path);
  EXPECT_TRUE(t.error.empty());
  EXPECT_DOUBLE_EQ(t.duration_s, 10.0);
  EXPECT_EQ(t.channels.at("B").messages, 26);
  EXPECT_NEAR(t.channels.at("B").rate_hz, 2.6, 1e-9);
  // 101 kB over 10 s = 80.8 kbit/s.
  EXPECT_NEAR(t.total_kbit_s, 80.8, 1e-9);
  EXPECT_NEAR(t.channels.at("A").kbit_s + t.channels.at("B").kbit_s, 80.8, 1e-9);
}

// Found by tests/fuzz/log_fuzz (UBSan): the span of corrupt utimes far
// apart overflowed int64.
TEST(LogStats, UtimesFarApartGiveAFiniteSpan) {
  const fs::path path = TempLog("far.lcmlog");
  {
    LogWriter w(path);
    w.Write("A", "x", 1, std::numeric_limits<int64_t>::min() + 1);
    w.Write("A", "x", 1, 1'000'000);
  }
  const LogTraffic t = MeasureLog(path);
  EXPECT_TRUE(std::isfinite(t.duration_s));
  EXPECT_GT(t.duration_s, 9e12);
}

TEST(Log, LcmLogplayerToolIsInstalled) {
  if (std::system("command -v lcm-logplayer > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "lcm-logplayer not on PATH (liblcm-bin not installed)";
  }
  // lcm-logplayer --help prints usage and exits 1; 127 would mean it cannot run.
  const int status = std::system("lcm-logplayer --help > /dev/null 2>&1");
  EXPECT_NE(WEXITSTATUS(status), 127);
}

}  // namespace
}  // namespace plantscale::telemetry
