#include "app/vehicle/odometry_input.h"

#include <gtest/gtest.h>

#include <limits>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>

#include "telemetry/channels.h"
#include "telemetry/codec.h"

namespace plantscale::vehicle {
namespace {

namespace channels = telemetry::channels;
using telemetry::Bytes;
using telemetry::Encode;
using telemetry::LcmTransport;

plantscale_odometry_t Sample(int64_t utime, double left, int8_t valid = 1) {
  plantscale_odometry_t m{};
  m.utime = utime;
  m.left_m_s = left;
  m.right_m_s = 0.5;
  m.valid = valid;
  return m;
}

TEST(OdometryInput, QueuesValidSamplesAndReportsBadOnesAsFaults) {
  LcmTransport t("memq://");
  OdometryInput in;
  in.Attach(t);
  auto send = [&](const Bytes& b) { t.Publish(channels::kOdometryIn, b.data(), b.size()); };
  send(Encode(Sample(1'000'000, 0.5)));
  send(Encode(Sample(1'020'000, std::numeric_limits<double>::quiet_NaN())));
  send(Encode(Sample(1'040'000, 0.5, 0)));
  send(Bytes{1, 2, 3});
  send(Encode(Sample(1'060'000, 0.52)));
  while (t.Handle(0)) {
  }
  const auto samples = in.Take();
  ASSERT_EQ(samples.size(), 2u);
  EXPECT_DOUBLE_EQ(samples[1].left_m_s, 0.52);
  EXPECT_TRUE(in.Take().empty());
  EXPECT_EQ(in.received(), 5);
  const auto faults = in.Faults(1'100'000);
  ASSERT_EQ(faults.size(), 1u);
  EXPECT_NE(faults[0].find("3 bad messages"), std::string::npos) << faults[0];
  // 0.6 s after the last sample: stale as well.
  EXPECT_EQ(in.Faults(1'660'000).size(), 2u);
  EXPECT_EQ(OdometryInput().Faults(0).size(), 1u);  // nothing received at all
}

}  // namespace
}  // namespace plantscale::vehicle
