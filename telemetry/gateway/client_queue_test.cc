#include "telemetry/gateway/client_queue.h"

#include <gtest/gtest.h>

namespace plantscale::telemetry::gateway {
namespace {

OutMessage Message(DropClass c, size_t bytes, const std::string& tag) {
  OutMessage m;
  m.drop = c;
  m.header = tag;
  m.payload = std::make_shared<const std::string>(bytes - tag.size(), 'x');
  return m;
}

TEST(GatewayQueue, DropsThumbnailsFirstThenDetailNeverEssential) {
  ClientQueueOptions o;
  o.max_bytes = 1000;
  ClientQueue q(o);
  ASSERT_TRUE(q.Push(Message(DropClass::kEssential, 300, "e1")));
  ASSERT_TRUE(q.Push(Message(DropClass::kThumbnail, 300, "t1")));
  ASSERT_TRUE(q.Push(Message(DropClass::kDetail, 300, "d1")));
  EXPECT_EQ(q.bytes(), 900u);
  ASSERT_TRUE(
      q.Push(Message(DropClass::kThumbnail, 300, "t2")));  // 1200: the oldest thumbnail goes
  EXPECT_EQ(q.dropped(DropClass::kThumbnail), 1);
  EXPECT_EQ(q.bytes(), 900u);
  ASSERT_TRUE(q.Push(Message(DropClass::kEssential, 300, "e2")));  // t2 goes, then still 900
  EXPECT_EQ(q.dropped(DropClass::kThumbnail), 2);
  ASSERT_TRUE(q.Push(Message(DropClass::kEssential, 300, "e3")));  // no thumbnail left: d1 goes
  EXPECT_EQ(q.dropped(DropClass::kDetail), 1);
  ASSERT_TRUE(q.Push(Message(DropClass::kEssential, 300, "e4")));  // nothing droppable: kept
  EXPECT_EQ(q.bytes(), 1200u);
  std::vector<std::string> order;
  while (auto m = q.Pop()) order.push_back(m->header);
  EXPECT_EQ(order, (std::vector<std::string>{"e1", "e2", "e3", "e4"}));
  EXPECT_EQ(q.bytes(), 0u);
}

TEST(GatewayQueue, SaysWhenEssentialsAloneOutgrowTheirBound) {
  ClientQueueOptions o;
  o.max_bytes = 1000;
  o.essential_max_bytes = 2000;
  ClientQueue q(o);
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(q.Push(Message(DropClass::kEssential, 300, "e")));
  EXPECT_EQ(q.bytes(), 1800u);
  EXPECT_FALSE(q.Push(Message(DropClass::kEssential, 300, "e")));
}

TEST(GatewayQueue, GridStaysAtTwoHertzWhenDetailIsDropped) {
  ClientQueue q;
  int essential = 0;
  // 12.5 Hz for 10 s: every 80 ms.
  for (int i = 0; i < 125; ++i) {
    const int64_t t = 1'000'000 + int64_t{i} * 80'000;
    if (q.Classify(TopicClass::kGrid, t) == DropClass::kEssential) ++essential;
    // The scene of the same state gets the same class.
    EXPECT_EQ(q.Classify(TopicClass::kGrid, t), q.Classify(TopicClass::kGrid, t));
  }
  // One every 5th (400 ms): 25 in 10 s, 2.5 Hz.
  EXPECT_EQ(essential, 25);
  EXPECT_EQ(q.Classify(TopicClass::kThumbnail, 0), DropClass::kThumbnail);
  EXPECT_EQ(q.Classify(TopicClass::kDetail, 0), DropClass::kDetail);
  EXPECT_EQ(q.Classify(TopicClass::kEssential, 0), DropClass::kEssential);
}

TEST(GatewayQueue, InvalidOptionsAreRefused) {
  ClientQueueOptions o;
  o.essential_max_bytes = o.max_bytes - 1;
  EXPECT_THROW(ClientQueue{o}, InvalidOptionsError);
}

TEST(GatewayRefusals, ABurstThenOnePerIntervalWithTheRestCounted) {
  RefusalLimiter limiter(3, 10'000'000);
  int published = 0;
  for (int i = 0; i < 1000; ++i) {  // 1,000 bad logins in one second
    if (limiter.Refused(int64_t{i} * 1000, "bad token")) ++published;
  }
  EXPECT_EQ(published, 3);
  EXPECT_EQ(limiter.held_back(), 997);
  EXPECT_FALSE(limiter.Flush(2'000'000));  // no token yet
  const auto summary = limiter.Flush(11'000'000);
  ASSERT_TRUE(summary);
  EXPECT_EQ(*summary, "997 refusals held back by the rate limit, the last: bad token");
  EXPECT_EQ(limiter.held_back(), 0);
  EXPECT_FALSE(limiter.Flush(30'000'000));  // nothing held back
  const auto next = limiter.Refused(30'000'001, "no token");
  ASSERT_TRUE(next);
  EXPECT_EQ(*next, "no token");
}

}  // namespace
}  // namespace plantscale::telemetry::gateway
