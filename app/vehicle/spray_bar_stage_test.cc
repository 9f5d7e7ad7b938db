// The spray bar stage in the vehicle runner: the bar's fail-safe reasons
// and nozzle faults in the heartbeat, nozzles commanded closed each frame.
#include "app/vehicle/spray_bar_stage.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <memory>
#include <plantscale_lcmtypes/plantscale_health_t.hpp>

#include "app/vehicle/stages.h"
#include "telemetry/can/testing.h"
#include "telemetry/channels.h"
#include "telemetry/testing.h"

namespace plantscale::vehicle {
namespace {

namespace channels = telemetry::channels;
using telemetry::PublisherOptions;
using telemetry::can::NozzleFault;
using ::testing::Contains;
using ::testing::IsEmpty;

bool AnyHas(const std::vector<std::string>& lines, const std::string& text) {
  for (const std::string& l : lines) {
    if (l.find(text) != std::string::npos) return true;
  }
  return false;
}

class SprayBarStageTest : public telemetry::can::testing::BarPairTest {};

TEST_F(SprayBarStageTest, StageReportsTheBarInTheHeartbeatAndCommandsClosed) {
  telemetry::testing::RecordingTransport transport;
  Publisher publisher(transport, PublisherOptions{});
  SprayBarStage stage(*vehicle_, true);
  RunStatus run;
  run.failsafe = false;  // as if a treatment stage had enabled spraying
  VehicleFrame frame;
  frame.utime = t_;
  stage.Process(frame, run, publisher);
  EXPECT_TRUE(run.failsafe);
  EXPECT_TRUE(
      AnyHas(run.faults, "spray bar socketpair: fail-safe: waiting for the bar's first heartbeat"));
  for (int i = 0; i < 10; ++i) {
    sim_->Step(t_);
    t_ += 40'000;
    frame.utime = t_;
    run = RunStatus{};
    run.failsafe = false;
    stage.Process(frame, run, publisher);
  }
  EXPECT_FALSE(run.failsafe);
  EXPECT_THAT(run.faults, IsEmpty());
  sim_->Step(t_);
  EXPECT_EQ(sim_->commands().size(), 11u);  // one per frame
  EXPECT_EQ(sim_->commands().back().open_mask, 0u);
}

// Frames every 40 ms with no image: enough for the bar and heartbeat stages.
class TickSource : public FrameSource {
 public:
  TickSource(int64_t start_utime, int frames) : utime_(start_utime), left_(frames) {}
  bool Next(VehicleFrame& frame) override {
    if (left_-- <= 0) return false;
    frame.utime = utime_;
    frame.frame_index = index_++;
    utime_ += 40'000;
    return true;
  }
  int dropped_frames() const override { return 0; }
  std::string name() const override { return "test"; }

 private:
  int64_t utime_;
  int left_;
  int index_ = 0;
};

std::vector<plantscale_health_t> HealthMessages(const telemetry::testing::RecordingTransport& transport) {
  std::vector<plantscale_health_t> out;
  for (const auto& sent : transport.sent) {
    if (sent.channel != channels::kHealth) continue;
    plantscale_health_t m;
    EXPECT_GT(m.decode(sent.bytes.data(), 0, static_cast<int>(sent.bytes.size())), 0);
    out.push_back(m);
  }
  return out;
}

TEST_F(SprayBarStageTest, HeartbeatChannelCarriesTheBarsFailSafeReasonsAndNozzleFaults) {
  telemetry::testing::RecordingTransport transport;
  Publisher publisher(transport, PublisherOptions{});
  {
    VehicleRunner runner(publisher, RunnerOptions{false}, t_);
    runner.AddStage(std::make_unique<SprayBarStage>(*vehicle_, true));
    runner.AddStage(std::make_unique<SimulatedBarStage>(*sim_));
    runner.AddStage(std::make_unique<HealthStage>());
    TickSource source(t_, 50);  // 2 s: health at 2 Hz
    runner.Run(source);
    t_ += 50 * 40'000;
  }
  std::vector<plantscale_health_t> health = HealthMessages(transport);
  ASSERT_GE(health.size(), 4u);
  EXPECT_EQ(health.front().failsafe, 1);
  EXPECT_THAT(health.front().faults,
              Contains("spray bar socketpair: fail-safe: waiting for the bar's first heartbeat"));
  EXPECT_THAT(health.back().faults, IsEmpty());  // bar heard and healthy
  EXPECT_FALSE(status().failsafe);

  sim_->InjectFault(3, NozzleFault::kShortCircuit);
  transport.sent.clear();
  {
    VehicleRunner runner(publisher, RunnerOptions{false}, t_);
    runner.AddStage(std::make_unique<SprayBarStage>(*vehicle_, true));
    runner.AddStage(std::make_unique<SimulatedBarStage>(*sim_));
    runner.AddStage(std::make_unique<HealthStage>());
    TickSource source(t_, 25);
    runner.Run(source);
  }
  health = HealthMessages(transport);
  ASSERT_GE(health.size(), 1u);
  EXPECT_THAT(health.back().faults,
              Contains("spray bar socketpair: nozzle 3: valve coil short circuit"));
  EXPECT_FALSE(status().failsafe);
}

}  // namespace
}  // namespace plantscale::vehicle
