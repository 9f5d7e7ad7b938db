#include "telemetry/subscriber.h"

#include <gtest/gtest.h>

#include <atomic>
#include <limits>
#include <thread>

#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"

namespace plantscale::telemetry {
namespace {

plantscale_grid_state_t Grid(int frame, int64_t seq) {
  GridEstimate e;
  e.utime = 80'000LL * frame;
  e.frame_index = frame;
  e.state.offset_m = 0.001 * frame;
  e.mode = FilterMode::kTracking;
  plantscale_grid_state_t m = ToLcm(e);
  m.seq = seq;
  return m;
}

void Send(LcmTransport& t, const std::string& channel, const Bytes& b) {
  t.Publish(channel, b.data(), b.size());
  while (t.Handle(0)) {
  }
}

TEST(Subscriber, KeepsLatestStateAndBoundedHistory) {
  LcmTransport t("memq://");
  SubscriberOptions o;
  o.history_length = 10;
  Subscriber s(o);
  s.Attach(t);
  for (int i = 0; i < 25; ++i) Send(t, channels::kGrid, Encode(Grid(i, i)));
  const TelemetrySnapshot snap = s.Snapshot();
  ASSERT_TRUE(snap.grid.has_value());
  EXPECT_EQ(snap.grid->frame_index, 24);
  EXPECT_NEAR(snap.grid->state.offset_m, 0.024, 1e-12);
  ASSERT_EQ(snap.grid_history.size(), 10u);
  EXPECT_EQ(snap.grid_history.front().frame_index, 15);
  EXPECT_FALSE(snap.truth.has_value());  // the tracker channel is not the truth channel
  EXPECT_EQ(snap.channels.at(channels::kGrid).received, 25);
  EXPECT_EQ(snap.channels.at(channels::kGrid).lost, 0);
}

TEST(Subscriber, MalformedMessagesAreCountedAndNamedNeverThrown) {
  LcmTransport t("memq://");
  Subscriber s;
  s.Attach(t);
  Bytes good = Encode(Grid(1, 0));
  Bytes truncated(good.begin(), good.begin() + 20);
  Send(t, channels::kGrid, truncated);
  plantscale_event_t e{};
  e.kind = "x";
  Send(t, channels::kGrid, Encode(e));  // wrong fingerprint for the channel
  plantscale_grid_state_t nan = Grid(2, 1);
  nan.state[2] = std::numeric_limits<double>::quiet_NaN();
  Send(t, channels::kGrid, Encode(nan));
  Send(t, "SOMEONE_ELSES", Bytes{1, 2, 3});
  Send(t, "LCM_SELF_TEST", Bytes{4, 5});  // LCM's own udpm start-up check: not a problem
  Send(t, channels::kGrid, Encode(Grid(5, 4)));  // seq 2 and 3 lost
  const TelemetrySnapshot snap = s.Snapshot();
  const ChannelStats& g = snap.channels.at(channels::kGrid);
  EXPECT_EQ(g.received, 4);
  EXPECT_EQ(g.decode_failures, 2);
  EXPECT_EQ(g.invalid, 1);
  EXPECT_EQ(g.lost, 2);
  EXPECT_EQ(snap.unknown_channel_messages, 1);
  ASSERT_EQ(snap.problems.size(), 4u);
  EXPECT_NE(snap.problems[0].find("channel PLANTSCALE_GRID"), std::string::npos)
      << snap.problems[0];
  EXPECT_NE(snap.problems[2].find("state"), std::string::npos) << snap.problems[2];
  EXPECT_NE(snap.problems[3].find("SOMEONE_ELSES"), std::string::npos);
  ASSERT_TRUE(snap.grid.has_value());
  EXPECT_EQ(snap.grid->frame_index, 5);  // the good message after the bad ones
}

TEST(Subscriber, ARestartedSenderIsCountedAsARestart) {
  Subscriber s;
  for (int64_t seq : {0, 1, 2, 0, 1}) {
    const Bytes b = Encode(Grid(static_cast<int>(seq), seq));
    s.Feed(channels::kSimTruth, b.data(), b.size(), 0);
  }
  const TelemetrySnapshot snap = s.Snapshot();
  EXPECT_EQ(snap.channels.at(channels::kSimTruth).restarts, 1);
  EXPECT_EQ(snap.channels.at(channels::kSimTruth).lost, 0);
  EXPECT_EQ(snap.truth_history.size(), 5u);
}

// The transport thread feeds while a UI thread takes snapshots: every
// snapshot must be internally consistent (latest == history's newest, the
// history contiguous), and the last one complete.
TEST(Subscriber, SnapshotsAreConsistentWhileAnotherThreadFeeds) {
  constexpr int kMessages = 3000;
  SubscriberOptions o;
  o.history_length = 50;
  Subscriber s(o);
  std::atomic<bool> done{false};
  std::thread producer([&] {
    LcmTransport t("memq://");
    s.Attach(t);
    for (int i = 0; i < kMessages; ++i) Send(t, channels::kGrid, Encode(Grid(i, i)));
    done = true;
  });
  int snapshots = 0;
  int inconsistent = 0;
  while (!done) {
    const TelemetrySnapshot snap = s.Snapshot();
    ++snapshots;
    if (!snap.grid) continue;
    const auto& h = snap.grid_history;
    if (h.back().frame_index != snap.grid->frame_index) ++inconsistent;
    if (h.back().frame_index - h.front().frame_index != static_cast<int>(h.size()) - 1)
      ++inconsistent;
  }
  producer.join();
  EXPECT_EQ(inconsistent, 0) << "of " << snapshots << " snapshots";
  const TelemetrySnapshot last = s.Snapshot();
  EXPECT_EQ(last.grid->frame_index, kMessages - 1);
  EXPECT_EQ(last.channels.at(channels::kGrid).received, kMessages);
}

}  // namespace
}  // namespace plantscale::telemetry

namespace plantscale::telemetry {
namespace {

TEST(Subscriber, GatewayEventsJoinTheEventsWithTheirOwnSequence) {
  Subscriber s;
  const auto feed = [&](const char* channel, int64_t seq, const std::string& kind) {
    plantscale_event_t e{};
    e.utime = seq;
    e.seq = seq;
    e.kind = kind;
    const Bytes b = Encode(e);
    s.Feed(channel, b.data(), b.size(), seq);
  };
  feed(channels::kEvents, 0, "run_started");
  feed(channels::kGatewayEvents, 0, "gateway_refused");
  feed(channels::kEvents, 1, "frame_dropped");
  const TelemetrySnapshot snap = s.Snapshot();
  ASSERT_EQ(snap.events.size(), 3u);
  EXPECT_EQ(snap.events[1].kind, "gateway_refused");
  EXPECT_EQ(snap.unknown_channel_messages, 0);
  // Two senders, two sequences: neither looks like a restart or a loss.
  EXPECT_EQ(snap.channels.at(channels::kEvents).restarts, 0);
  EXPECT_EQ(snap.channels.at(channels::kEvents).lost, 0);
  EXPECT_EQ(snap.channels.at(channels::kGatewayEvents).received, 1);
}

}  // namespace
}  // namespace plantscale::telemetry
