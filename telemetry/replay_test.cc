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

// Replays at 10× over memq:// while another thread receives. Pacing means no
// event arrives before its time ((t − t0) / 10, 1 ms clock tolerance); on a
// loaded machine events can only be late, so lateness is bounded loosely:
// median ≤ 5 ms and the whole replay within 50 ms of 0.2 s.
// Times each publish: what is under test is the replay's pacing, not how
// soon a receiving thread gets scheduled on a loaded machine.
class TimingTransport : public Transport {
 public:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start = Clock::now();
  std::vector<double> sent;  // seconds after start
  void Publish(const std::string&, const void*, size_t) override {
    sent.push_back(std::chrono::duration<double>(Clock::now() - start).count());
  }
  void Subscribe(const std::string&, Handler) override {}
  bool Handle(int) override { return false; }
};

TEST(Replay, KeepsOriginalTimingScaledBySpeed) {
  const fs::path path = TwoSecondLog("timing.lcmlog");
  TimingTransport t;
  t.start = TimingTransport::Clock::now();
  const ReplaySummary s = Replay(path, t, ReplayOptions{10.0, 0.0, ".*"});
  EXPECT_EQ(s.published, 21);
  EXPECT_NEAR(s.log_seconds, 2.0, 1e-9);
  EXPECT_GE(s.wall_seconds, 0.2 - 0.001);
  EXPECT_LE(s.wall_seconds, 0.2 + 0.05);
  ASSERT_EQ(t.sent.size(), 21u);
  std::vector<double> lateness;
  for (size_t i = 0; i < t.sent.size(); ++i) {
    const double expected = 0.01 * static_cast<double>(i);
    EXPECT_GE(t.sent[i], expected - 0.001) << "event " << i << " sent early";
    lateness.push_back(t.sent[i] - expected);
  }
  std::sort(lateness.begin(), lateness.end());
  EXPECT_LE(lateness[lateness.size() / 2], 0.005);  // median 5 ms: sleep_until overshoot only
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
