#include "telemetry/publisher.h"

#include <gtest/gtest.h>

#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>

#include "telemetry/channels.h"
#include "telemetry/testing.h"

namespace plantscale::telemetry {
namespace {

using testing::RecordingTransport;

plantscale_odometry_t Odometry(int64_t utime) {
  plantscale_odometry_t m{};
  m.utime = utime;
  return m;
}

plantscale_thumbnail_t Thumbnail(int64_t utime, int bytes) {
  plantscale_thumbnail_t m{};
  m.utime = utime;
  m.jpeg.assign(static_cast<size_t>(bytes), 0x55);
  m.jpeg_size = bytes;
  return m;
}

TEST(Publisher, RateLimitsA50HzStreamTo12_5Hz) {
  RecordingTransport t;
  Publisher p(t, PublisherOptions{});
  for (int i = 0; i < 500; ++i) p.Publish(channels::kOdometry, Odometry(20'000LL * i));  // 10 s
  // 12.5 Hz over 10 s: 125 messages ± 1 (the first slot may be taken early).
  EXPECT_NEAR(t.Count(channels::kOdometry), 125, 1);
  EXPECT_EQ(p.counters().at(channels::kOdometry).dropped_rate, 500 - t.Count(channels::kOdometry));
}


// The network gone (the station's link): a message the transport cannot
// send is counted as failed, not thrown, and the next one goes out.
TEST(Publisher, TransportFailuresAreCountedNotThrown) {
  class Broken : public RecordingTransport {
   public:
    void Publish(const std::string& channel, const void* data, size_t size) override {
      if (down) throw TransportError("LCM URL 'memq://': publish on " + channel + " failed");
      RecordingTransport::Publish(channel, data, size);
    }
    bool down = true;
  } t;
  Publisher p(t, PublisherOptions{});
  plantscale_event_t e{};
  e.utime = 1'000'000;
  EXPECT_FALSE(p.Publish(channels::kEvents, e));
  EXPECT_EQ(p.counters().at(channels::kEvents).failed, 1);
  EXPECT_EQ(p.counters().at(channels::kEvents).sent, 0);
  EXPECT_EQ(p.transport_failures().count, 1);
  EXPECT_EQ(p.transport_failures().last_utime, 1'000'000);
  EXPECT_NE(p.transport_failures().last_error.find("publish on PLANTSCALE_EVENTS failed"), std::string::npos);
  t.down = false;
  e.utime = 2'000'000;
  EXPECT_TRUE(p.Publish(channels::kEvents, e));
  EXPECT_EQ(t.Count(channels::kEvents), 1);
}

TEST(Publisher, ThumbnailsAt2HzFromJitteryFrames) {
  RecordingTransport t;
  Publisher p(t, PublisherOptions{});
  int sent = 0;
  for (int i = 0; i < 250; ++i) {  // 20 s of 12.5 Hz frames with ±1.5 ms jitter
    const int64_t utime = 80'000LL * i + (i % 3 - 1) * 1'500;
    sent += p.Publish(channels::kThumbnail, Thumbnail(utime, 100)) ? 1 : 0;
  }
  // 2 Hz over 20 s: 40 ± 1 (first and last slot).
  EXPECT_NEAR(sent, 40, 1);
}

TEST(Publisher, SequenceNumbersCountSentMessages) {
  RecordingTransport t;
  Publisher p(t, PublisherOptions{});
  for (int i = 0; i < 3; ++i) p.Publish(channels::kOdometry, Odometry(100'000LL * i));
  const auto last =
      Decode<plantscale_odometry_t>("x", t.sent.back().bytes.data(), t.sent.back().bytes.size());
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->seq, 2);
}

TEST(Publisher, BudgetDropsBulkButNeverEssentialMessages) {
  RecordingTransport t;
  PublisherOptions o;
  o.budget_kbit_s = 80.0;  // 10 kB/s
  o.burst_s = 1.0;
  o.channels[channels::kThumbnail].max_rate_hz = 0.0;  // only the budget limits
  Publisher p(t, o);
  int thumbs = 0;
  for (int i = 0; i < 100; ++i) {  // 10 s of 4 kB thumbnails at 10 Hz: 40 kB/s offered
    const int64_t utime = 100'000LL * i;
    thumbs += p.Publish(channels::kThumbnail, Thumbnail(utime, 4000)) ? 1 : 0;
    plantscale_event_t e{};
    e.utime = utime;
    e.kind = "tick";
    EXPECT_TRUE(p.Publish(channels::kEvents, e));
  }
  // 10 kB/s for 10 s plus a 10 kB burst, less the events (~40 B each):
  // about 110 kB / 4 kB ≈ 26 thumbnails.
  EXPECT_NEAR(thumbs, 26, 2);
  EXPECT_EQ(p.counters().at(channels::kThumbnail).dropped_budget, 100 - thumbs);
  EXPECT_EQ(p.counters().at(channels::kEvents).sent, 100);
  EXPECT_EQ(p.total_dropped(), 100 - thumbs);
}

// A tile is sent once, when the bar has passed it: over budget the
// thumbnails go, never a tile.
TEST(Publisher, MapTilesAreNeverDroppedByTheBudget) {
  RecordingTransport t;
  PublisherOptions o;
  o.budget_kbit_s = 8.0;  // 1 kB/s
  o.burst_s = 0.5;
  Publisher p(t, o);
  for (int i = 0; i < 50; ++i) {
    const int64_t utime = 500'000LL * i;
    p.Publish(channels::kThumbnail, Thumbnail(utime, 2000));
    for (int k = 0; k < 4; ++k) {
      plantscale_map_tile_t tile{};
      tile.utime = utime;
      tile.tile_x = k;
      tile.tile_y = i;
      tile.width = tile.height = 16;
      tile.cells.assign(256, 1);
      tile.num_bytes = 256;
      EXPECT_TRUE(p.Publish(channels::kMapTiles, tile)) << i << "," << k;
    }
  }
  EXPECT_EQ(p.counters().at(channels::kMapTiles).sent, 200);
  EXPECT_GT(p.counters().at(channels::kThumbnail).dropped_budget, 40);
}

TEST(Publisher, InvalidOptionsNameTheKey) {
  RecordingTransport t;
  PublisherOptions o;
  o.budget_kbit_s = -1.0;
  o.channels["PLANTSCALE_X"].max_rate_hz = -2.0;
  const OptionErrors errors = o.Validate();
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0].key, "budget_kbit_s");
  EXPECT_EQ(errors[1].key, "channels.PLANTSCALE_X.max_rate_hz");
  EXPECT_THROW(Publisher(t, o), InvalidOptionsError);
}

}  // namespace
}  // namespace plantscale::telemetry
