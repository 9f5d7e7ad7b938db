#include "telemetry/replay.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>
#include <vector>

#include "telemetry/log.h"
#include "telemetry/testing.h"

namespace plantscale::telemetry {
namespace {

namespace fs = std::filesystem;

fs::path TempLog(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("plantscale_replay_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

// 21 events 100 ms apart (2 s of log), alternating channels A and B.
fs::path TwoSecondLog(const std::string& name) {
  const fs::path path = TempLog(name);
  LogWriter w(path);
  for (int i = 0; i <= 20; ++i) {
    const char c = static_cast<char>('0' + i % 10);
    w.Write(i % 2 ? "B" : "A", &c, 1, 7'000'000 + 100'000LL * i);
  }
  return path;
}

// Replays at 10× and times each publish: what is under test is the replay's
// pacing, not how soon a receiving thread gets scheduled on a loaded machine.
// No event is sent before its time ((t − t0) / 10, 1 ms clock tolerance).
// Late it can be, by what the scheduler adds to every sleep_until: about
// 0.1 ms on a quiet machine, several ms under other builds and ASan. So the
// lateness, counted from the first publish (not from before Replay, which
// would add opening the log and compiling the channel pattern), is bounded by
// the median overshoot this process gets from the same sleeps at the same
// moment (SleepOvershoot, the worse of a run just before and one just after
// the replay) plus 2 ms for the replay's own work between two sleeps
// (reading and matching one event takes µs). A replay that ignores the speed
// or stalls exceeds it, and so does one that drifts (sleeping a period per
// event rather than until each event's time: its overshoots add up, 22–44 ms
// by the median event on the loaded machine this was checked on).
using Clock = std::chrono::steady_clock;

class TimingTransport : public Transport {
 public:
  Clock::time_point start = Clock::now();
  std::vector<double> sent;  // seconds after start
  void Publish(const std::string&, const void*, size_t) override {
    sent.push_back(std::chrono::duration<double>(Clock::now() - start).count());
  }
  void Subscribe(const std::string&, Handler) override {}
  bool Handle(int) override { return false; }
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Overshoot {
  double median = 0.0;  // s
  double max = 0.0;     // s
};

// What sleep_until overshoots now: 21 deadlines 10 ms apart, as the replay sleeps.
Overshoot SleepOvershoot() {
  const Clock::time_point start = Clock::now();
  std::vector<double> late;
  for (int i = 0; i <= 20; ++i) {
    const Clock::time_point deadline = start + std::chrono::milliseconds(10 * i);
    std::this_thread::sleep_until(deadline);
    late.push_back(std::chrono::duration<double>(Clock::now() - deadline).count());
  }
  return {Median(late), *std::max_element(late.begin(), late.end())};
}

TEST(Replay, KeepsOriginalTimingScaledBySpeed) {
  const fs::path path = TwoSecondLog("timing.lcmlog");
  const Overshoot before = SleepOvershoot();
  TimingTransport t;
  t.start = Clock::now();
  const ReplaySummary s = Replay(path, t, ReplayOptions{10.0, 0.0, ".*"});
  const Overshoot after = SleepOvershoot();
  const Overshoot scheduler{std::max(before.median, after.median), std::max(before.max, after.max)};
  EXPECT_EQ(s.published, 21);
  EXPECT_NEAR(s.log_seconds, 2.0, 1e-9);
  EXPECT_GE(s.wall_seconds, 0.2 - 0.001);
  EXPECT_LE(s.wall_seconds, 0.2 + scheduler.max + 0.05) << "overshoot " << scheduler.max << " s";
  ASSERT_EQ(t.sent.size(), 21u);
  std::vector<double> lateness;
  for (size_t i = 0; i < t.sent.size(); ++i) {
    const double expected = 0.01 * static_cast<double>(i);
    EXPECT_GE(t.sent[i], expected - 0.001) << "event " << i << " sent early";
    lateness.push_back(t.sent[i] - t.sent[0] - expected);
  }
  EXPECT_LE(Median(lateness), scheduler.median + 0.002)
      << "the scheduler's median overshoot is " << scheduler.median << " s";
}

TEST(Replay, StartOffsetAndChannelFilter) {
  const fs::path path = TwoSecondLog("filter.lcmlog");
  testing::RecordingTransport t;
  const ReplaySummary s = Replay(path, t, ReplayOptions{1000.0, 1.0, "B"});
  // Events at 1.0..2.0 s are i = 10..20; odd i are on B: 11, 13, ..., 19.
  EXPECT_EQ(s.published, 5);
  EXPECT_EQ(t.Count("A"), 0);
  EXPECT_EQ(t.sent.front().bytes[0], '1');
}

TEST(Replay, TruncatedLogReplaysUpToItsLastWholeEvent) {
  const fs::path path = TwoSecondLog("cut.lcmlog");
  fs::resize_file(path, fs::file_size(path) - 1);
  testing::RecordingTransport t;
  const ReplaySummary s = Replay(path, t, ReplayOptions{1000.0, 0.0, ".*"});
  EXPECT_EQ(s.published, 20);
  EXPECT_NE(s.error.find("cut.lcmlog"), std::string::npos) << s.error;
  EXPECT_NE(s.error.find("byte offset"), std::string::npos) << s.error;
}

TEST(Replay, BadOptionsAreRejectedNamingTheKey) {
  ReplayOptions o{0.0, -1.0, "("};
  const OptionErrors errors = o.Validate();
  ASSERT_EQ(errors.size(), 3u);
  EXPECT_EQ(errors[0].key, "speed");
  EXPECT_EQ(errors[2].key, "channels");
}

}  // namespace
}  // namespace plantscale::telemetry
