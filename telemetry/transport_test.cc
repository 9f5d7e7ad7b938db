#include "telemetry/transport.h"

#include <gtest/gtest.h>

#include <string>
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
