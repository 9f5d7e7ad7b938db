#include "telemetry/transport.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

namespace plantscale::telemetry {
namespace {

TEST(LcmTransport, MemqDeliversBytesToRegexSubscribers) {
  LcmTransport t("memq://");
  std::vector<std::string> got;
  t.Subscribe("PLANTSCALE_.*", [&](const ReceivedMessage& m) {
    got.push_back(m.channel + ":" + std::string(static_cast<const char*>(m.data), m.size));
  });
  t.Publish("PLANTSCALE_A", "abc", 3);
  t.Publish("OTHER", "zz", 2);
  t.Publish("PLANTSCALE_B", "de", 2);
  while (t.Handle(0)) {
  }
  EXPECT_EQ(got, (std::vector<std::string>{"PLANTSCALE_A:abc", "PLANTSCALE_B:de"}));
}

// A station busy rendering lets messages pile up: the end-of-run flush is
// some 16 map tiles and an event at once, and LCM's default queue of 30 per
// subscription dropped the rest without a word. Only udpm:// queues (memq://
// hands each message over directly), so this runs inside
// tests/telemetry_udpm_test.sh's private network namespace, which sets
// PLANTSCALE_TEST_UDPM_URL.
TEST(LcmTransport, ABurstWaitingToBeHandledIsKeptWhole) {
  const char* url = std::getenv("PLANTSCALE_TEST_UDPM_URL");
  if (url == nullptr) GTEST_SKIP() << "needs udpm:// (run by tests/telemetry_udpm_test.sh)";
  LcmTransport t(url);
  int got = 0;
  t.Subscribe("PLANTSCALE_BURST", [&](const ReceivedMessage&) { ++got; });
  const std::string tile(2000, 't');
  for (int i = 0; i < 200; ++i) t.Publish("PLANTSCALE_BURST", tile.data(), tile.size());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // all of it waits in LCM
  while (t.Handle(100)) {
  }
  EXPECT_EQ(got, 200);
}

TEST(LcmTransport, HandleTimesOutWhenNothingArrives) {
  LcmTransport t("memq://");
  t.Subscribe(".*", [](const ReceivedMessage&) {});
  EXPECT_FALSE(t.Handle(10));
}

TEST(LcmTransport, BadUrlThrowsNamingIt) {
  try {
    LcmTransport t("nosuchprovider://x");
    FAIL() << "expected TransportError";
  } catch (const TransportError& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchprovider://x"), std::string::npos);
  }
  EXPECT_FALSE(LcmTransportOptions{"memq"}.Validate().empty());
  EXPECT_TRUE(LcmTransportOptions{}.Validate().empty());
}

}  // namespace
}  // namespace plantscale::telemetry
