#pragma once
// A test fixture: SprayBar (the vehicle's end) against SimulatedBar (the
// bar's end) over a socketpair carrying struct can_frame, on a message clock
// advanced in 20 ms ticks.

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>

#include "telemetry/can/simulated_bar.h"
#include "telemetry/can/spray_bar.h"

namespace plantscale::telemetry::can::testing {

class BarPairTest : public ::testing::Test {
 public:
  static constexpr int64_t kTick = 20'000;  // us

 protected:
  BarPairTest() {
    auto [vehicle, bar] = CanFramePipe();
    vehicle_ = std::make_unique<SprayBar>(std::move(vehicle), BarLinkOptions{}, "socketpair");
    sim_ = std::make_unique<SimulatedBar>(std::move(bar), SimulatedBarOptions{});
  }
  // One scheduler tick: command, the bar answers, the vehicle reads.
  void Tick(uint64_t mask) {
    vehicle_->Command(t_, mask);
    sim_->Step(t_);
    vehicle_->Poll(t_);
    t_ += kTick;
  }
  // Ticks until the vehicle is out of fail-safe (at most `limit`).
  int TicksUntilReady(uint64_t mask, int limit = 50) {
    for (int i = 0; i < limit; ++i) {
      Tick(mask);
      if (!vehicle_->status().failsafe) return i + 1;
    }
    return -1;
  }
  const SprayBarStatus& status() const { return vehicle_->status(); }

  int64_t t_ = 1'000'000'000;
  std::unique_ptr<SprayBar> vehicle_;
  std::unique_ptr<SimulatedBar> sim_;
};

}  // namespace plantscale::telemetry::can::testing
