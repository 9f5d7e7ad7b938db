// SprayBar against SimulatedBar over a socketpair carrying struct can_frame:
// the same encoder, decoder and bar logic as on a SocketCAN socket. Time is
// a message clock advanced in 20 ms ticks; the bar sends a heartbeat every
// 50 ms.
#include "telemetry/can/spray_bar.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <memory>
#include <plantscale_lcmtypes/plantscale_health_t.hpp>
#include <plantscale_lcmtypes/plantscale_nozzles_t.hpp>

#include "engine/common/check.h"
#include "telemetry/can/simulated_bar.h"
#include "telemetry/can/nozzle_bar.h"
#include "telemetry/can/testing.h"
#include "telemetry/channels.h"
#include "telemetry/testing.h"

namespace plantscale::telemetry::can {
namespace {

using ::testing::AllOf;
using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

class SprayBarTest : public testing::BarPairTest {};

constexpr int64_t kTick = testing::BarPairTest::kTick;

TEST_F(SprayBarTest, StartsFailSafeAndOpensAfterThreeGoodHeartbeats) {
  EXPECT_TRUE(status().failsafe);
  EXPECT_THAT(status().reasons, Contains(HasSubstr("waiting for the bar's first heartbeat")));
  // Heartbeats at ticks 1, 4, 6 (every 50 ms on a 20 ms tick): ready at tick 6.
  EXPECT_EQ(TicksUntilReady(0b1011), 6);
  EXPECT_EQ(status().heartbeats, 3);
  EXPECT_THAT(status().reasons, IsEmpty());
  // Every command before was all-closed and flagged fail-safe; the bar obeyed.
  ASSERT_EQ(sim_->commands().size(), 6u);
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(sim_->commands()[i].open_mask, 0u) << i;
    EXPECT_EQ(sim_->commands()[i].flags, NozzleCommand::kFlagFailsafe) << i;
  }
  EXPECT_EQ(sim_->open_mask(), 0u);
  Tick(0b1011);
  EXPECT_EQ(sim_->open_mask(), 0b1011u);
  EXPECT_EQ(status().applied_mask, 0b1011u);
  EXPECT_EQ(sim_->commands().back().flags, 0);
  EXPECT_EQ(sim_->commands().back().hold_ms, 200);
}

TEST_F(SprayBarTest, FollowsCommandsAndTheBarRecordsEveryValveChange) {
  ASSERT_GT(TicksUntilReady(0), 0);
  const int64_t t0 = t_;
  const std::vector<uint64_t> pattern = {0x1, 0x1, 0x3, 0x0, 0xFF, 0x80};
  for (uint64_t m : pattern) Tick(m);
  ASSERT_EQ(sim_->history().size(), 5u);  // 0x1, 0x3, 0x0, 0xFF, 0x80
  EXPECT_EQ(sim_->history()[0].utime, t0);
  EXPECT_EQ(sim_->history()[0].open_mask, 0x1u);
  EXPECT_EQ(sim_->history()[1].utime, t0 + 2 * kTick);
  EXPECT_EQ(sim_->history()[2].open_mask, 0x0u);
  EXPECT_EQ(sim_->history()[4].utime, t0 + 5 * kTick);
  EXPECT_EQ(sim_->history()[4].open_mask, 0x80u);
  EXPECT_EQ(status().commands_sent, status().acks);
  EXPECT_EQ(status().frames_rejected, 0);
  EXPECT_EQ(status().sequence_gaps, 0);
  EXPECT_FALSE(status().failsafe);
  EXPECT_THAT(sim_->errors(), IsEmpty());
}

TEST(ShotsFromValvesTest, OneShotPerNozzleAndOpening) {
  // Nozzle 0 open 100..300, nozzle 1 open 200..400 and 500..end, nozzle 3 a
  // shot that is open at the end.
  const std::vector<SimulatedBar::Valves> history = {
      {100, 0b0001}, {200, 0b0011}, {300, 0b0010}, {400, 0b0000}, {500, 0b1010}};
  const std::vector<NozzleShot> shots = ShotsFromValves(history, 900);
  ASSERT_EQ(shots.size(), 4u);
  EXPECT_EQ(shots[0].nozzle, 0);
  EXPECT_EQ(shots[0].open_utime, 100);
  EXPECT_EQ(shots[0].close_utime, 300);
  EXPECT_EQ(shots[1].nozzle, 1);
  EXPECT_EQ(shots[1].open_utime, 200);
  EXPECT_EQ(shots[1].close_utime, 400);
  EXPECT_EQ(shots[2].nozzle, 1);
  EXPECT_EQ(shots[2].open_utime, 500);
  EXPECT_EQ(shots[2].close_utime, 900);
  EXPECT_EQ(shots[3].nozzle, 3);
  EXPECT_EQ(shots[3].open_utime, 500);
  EXPECT_EQ(shots[3].close_utime, 900);
  EXPECT_EQ(shots[3].plant_id, -1);
}

TEST_F(SprayBarTest, SilentBarTimesOutAndNozzlesAreCommandedClosed) {
  ASSERT_GT(TicksUntilReady(0xF), 0);
  Tick(0xF);
  ASSERT_EQ(sim_->open_mask(), 0xFu);
  const int64_t last_heartbeat = status().last_heartbeat_utime;
  sim_->SetSilent(true);
  const int64_t silent_from = t_;
  // The scheduler keeps asking for 0xF; the bar hears but never answers.
  int64_t failsafe_at = -1;
  for (int i = 0; i < 20 && failsafe_at < 0; ++i) {
    Tick(0xF);
    if (status().failsafe) failsafe_at = t_ - kTick;
  }
  ASSERT_GT(failsafe_at, 0);
  // The acknowledgement watchdog (100 ms) trips first: the first unanswered
  // command went out at silent_from, checked every 20 ms.
  EXPECT_GT(failsafe_at - silent_from, 100'000);
  EXPECT_LE(failsafe_at - silent_from, 100'000 + kTick);
  EXPECT_THAT(status().reasons, Contains(HasSubstr("not acknowledged in")));
  EXPECT_EQ(sim_->open_mask(), 0u);
  EXPECT_EQ(sim_->commands().back().open_mask, 0u);
  EXPECT_EQ(sim_->commands().back().flags, NozzleCommand::kFlagFailsafe);
  while (t_ - last_heartbeat <= 300'000) Tick(0xF);
  EXPECT_THAT(status().reasons, Contains(AllOf(HasSubstr("no heartbeat from the bar for 0.3"),
                                               HasSubstr("(timeout 0.250 s)"))));
  EXPECT_THAT(vehicle_->HealthFaults(),
              Contains(HasSubstr("spray bar socketpair: fail-safe: no heartbeat from the bar")));
  EXPECT_EQ(sim_->open_mask(), 0u);
  const NozzleBar nozzles = ToNozzleBar(status());
  EXPECT_TRUE(nozzles.failsafe);
  for (int f : nozzles.fault) EXPECT_EQ(f, int{plantscale_nozzles_t::FAULT_NO_ANSWER});
}

TEST_F(SprayBarTest, HeartbeatTimeoutAloneClosesAtOnceThenRecovers) {
  ASSERT_GT(TicksUntilReady(0), 0);
  // Open with a long hold so that the closing is the vehicle's, not the bar's.
  BarLinkOptions o;
  o.hold_s = 5.0;
  auto [vehicle, bar] = CanFramePipe();
  vehicle_ = std::make_unique<SprayBar>(std::move(vehicle), o, "socketpair");
  sim_ = std::make_unique<SimulatedBar>(std::move(bar), SimulatedBarOptions{});
  ASSERT_GT(TicksUntilReady(0x6), 0);
  Tick(0x6);
  ASSERT_EQ(sim_->open_mask(), 0x6u);
  sim_->SetSilent(true);
  const int64_t last_heartbeat = status().last_heartbeat_utime;
  // Nobody commands any more (no ack outstanding): only the heartbeat watchdog.
  while (!status().failsafe) {
    sim_->Step(t_);
    vehicle_->Poll(t_);
    t_ += kTick;
    ASSERT_LT(t_ - last_heartbeat, 1'000'000) << "never timed out";
  }
  const int64_t tripped = t_ - kTick;
  EXPECT_GT(tripped - last_heartbeat, 250'000);
  EXPECT_LE(tripped - last_heartbeat, 250'000 + kTick);
  ASSERT_EQ(status().reasons.size(), 1u);
  EXPECT_THAT(status().reasons[0], HasSubstr("no heartbeat from the bar for 0.26"));
  // The all-closed command went out in the same Poll; the bar applies it at its next step.
  sim_->Step(t_);
  EXPECT_EQ(sim_->open_mask(), 0u);
  EXPECT_EQ(sim_->history().back().utime, t_);
  EXPECT_EQ(sim_->commands().back().flags, NozzleCommand::kFlagFailsafe);
  // Silent for another 200 ms (the all-closed command is never acknowledged
  // and given up after 100 ms), then the bar comes back: its counter ran on
  // (a gap), then three good heartbeats.
  for (int i = 0; i < 10; ++i) {
    sim_->Step(t_);
    vehicle_->Poll(t_);
    t_ += kTick;
  }
  EXPECT_TRUE(status().failsafe);
  sim_->SetSilent(false);
  const int64_t gaps = status().sequence_gaps;
  const int ticks = TicksUntilReady(0x6);
  EXPECT_EQ(status().sequence_gaps, gaps + 1);
  // First heartbeat (with the gap) within one 50 ms period, then three more
  // 50 ms apart, seen on the 20 ms tick: 150..220 ms.
  EXPECT_GE(ticks, 150'000 / kTick);
  EXPECT_LE(ticks, 220'000 / kTick);
  Tick(0x6);
  EXPECT_EQ(sim_->open_mask(), 0x6u);
}

TEST_F(SprayBarTest, FrameWithWrongIdentifierFailsSafeUntilThreeGoodHeartbeats) {
  ASSERT_GT(TicksUntilReady(0x3), 0);
  Tick(0x3);
  can_frame f = Encode(ProtocolIds{}, BarHeartbeat{0, BarState::kReady, 8, kProtocolVersion});
  f.can_id = 0x219;
  sim_->SendRaw(f);
  vehicle_->Poll(t_);
  EXPECT_TRUE(status().failsafe);
  EXPECT_EQ(status().frames_rejected, 1);
  EXPECT_THAT(status().last_error,
              AllOf(HasSubstr("id 0x219"), HasSubstr("not in the bar's block")));
  EXPECT_THAT(status().reasons, Contains(HasSubstr("recovering from: CAN frame id 0x219")));
  // Nozzles were commanded closed in that Poll.
  sim_->Step(t_);
  EXPECT_EQ(sim_->open_mask(), 0u);
  t_ += kTick;
  EXPECT_EQ(TicksUntilReady(0x3), 6);
}

TEST_F(SprayBarTest, FrameWithWrongLengthIsRejected) {
  ASSERT_GT(TicksUntilReady(0x1), 0);
  can_frame f = Encode(ProtocolIds{}, NozzleAck{});
  f.can_dlc = 5;
  sim_->SendRaw(f);
  vehicle_->Poll(t_);
  EXPECT_TRUE(status().failsafe);
  EXPECT_THAT(status().last_error, HasSubstr("nozzle ack: DLC 5, expected 8"));
  // A short write: not even a whole can_frame.
  const char junk[10] = {};
  sim_->SendBytes(junk, sizeof junk);
  vehicle_->Poll(t_);
  EXPECT_THAT(status().last_error, HasSubstr("read 10 bytes, a CAN frame is 16"));
  EXPECT_EQ(status().frames_rejected, 2);
}

TEST_F(SprayBarTest, HeartbeatSequenceGapFailsSafe) {
  ASSERT_GT(TicksUntilReady(0x1), 0);
  sim_->SkipHeartbeats(2);
  for (int i = 0; i < 3; ++i) Tick(0x1);  // one heartbeat in 60 ms
  sim_->Step(t_);
  EXPECT_TRUE(status().failsafe);
  EXPECT_EQ(status().sequence_gaps, 1);
  EXPECT_THAT(status().last_error,
              AllOf(HasSubstr("heartbeat sequence gap: expected counter"), HasSubstr("(2 lost)")));
  EXPECT_EQ(sim_->open_mask(), 0u);
}

TEST_F(SprayBarTest, AcknowledgementSequenceGapAndUnknownSequence) {
  ASSERT_GT(TicksUntilReady(0x1), 0);
  // Two commands the bar never sees answered in order: the ack of the
  // second arrives first.
  vehicle_->Command(t_, 0x1);
  const uint8_t first =
      sim_->commands().empty() ? 0 : static_cast<uint8_t>(sim_->commands().back().seq + 1);
  vehicle_->Command(t_, 0x1);
  sim_->SendRaw(
      Encode(ProtocolIds{}, NozzleAck{static_cast<uint8_t>(first + 1), AckStatus::kApplied, 0x1}));
  vehicle_->Poll(t_);
  EXPECT_EQ(status().sequence_gaps, 1);
  EXPECT_THAT(
      status().last_error,
      HasSubstr("acknowledgement sequence gap: expected seq " + std::to_string(first) + ", got " +
                std::to_string(first + 1) + " (1 command(s) never acknowledged)"));
  EXPECT_TRUE(status().failsafe);
  sim_->SendRaw(
      Encode(ProtocolIds{}, NozzleAck{static_cast<uint8_t>(first + 100), AckStatus::kApplied, 0}));
  vehicle_->Poll(t_);
  EXPECT_THAT(status().last_error,
              HasSubstr("seq " + std::to_string(static_cast<uint8_t>(first + 100)) +
                        ", which is not an outstanding command"));
}

TEST_F(SprayBarTest, AcknowledgementOfTheWrongSectionFailsSafe) {
  ASSERT_GT(TicksUntilReady(0x1), 0);
  vehicle_->Command(t_, 0x1);
  const uint8_t seq = static_cast<uint8_t>(status().commands_sent - 1);
  sim_->SendRaw(Encode(ProtocolIds{}, NozzleAck{seq, AckStatus::kApplied, 0x1, 1}));
  vehicle_->Poll(t_);
  EXPECT_TRUE(status().failsafe);
  EXPECT_THAT(status().last_error, HasSubstr("acknowledgement of command seq " +
                                             std::to_string(seq) + " (section 0) names section 1"));
}

TEST(SprayBar64Test, SixtyFourNozzlesTakeTwoFramesPerTickWithFaultsInBothSections) {
  auto [vehicle_end, bar_end] = CanFramePipe();
  BarLinkOptions o;
  o.num_nozzles = 64;
  SprayBar bar(std::move(vehicle_end), o, "socketpair");
  SimulatedBarOptions so;
  so.num_nozzles = 64;
  SimulatedBar sim(std::move(bar_end), so);
  int64_t t = 1'000'000'000;
  const auto tick = [&](uint64_t mask) {
    bar.Command(t, mask);
    sim.Step(t);
    bar.Poll(t);
    t += kTick;
  };
  const uint64_t mask = 0x8000'0001'0000'0003ull;  // nozzles 0, 1, 32 and 63
  for (int i = 0; i < 10; ++i) tick(mask);
  EXPECT_FALSE(bar.status().failsafe);
  EXPECT_EQ(sim.open_mask(), mask);
  EXPECT_EQ(bar.status().applied_mask, mask);
  EXPECT_EQ(bar.status().commands_sent, 20);  // two sections per tick
  EXPECT_EQ(bar.status().acks, 20);
  ASSERT_GE(sim.commands().size(), 2u);
  EXPECT_EQ(sim.commands()[0].section, 0);
  EXPECT_EQ(sim.commands()[1].section, 1);
  EXPECT_EQ(sim.commands().back().open_mask, 0x8000'0001u);
  sim.InjectFault(32, NozzleFault::kOpenCircuit);
  sim.InjectFault(40, NozzleFault::kStuck);
  tick(mask);
  tick(mask);
  EXPECT_FALSE(bar.status().failsafe);
  EXPECT_EQ(bar.status().nozzle_faults[32], NozzleFault::kOpenCircuit);
  EXPECT_EQ(bar.status().nozzle_faults[40], NozzleFault::kStuck);
  EXPECT_EQ(sim.open_mask(), mask & ~(uint64_t{1} << 32));
  EXPECT_THAT(bar.HealthFaults(),
              ::testing::ElementsAre("spray bar socketpair: nozzle 32: valve coil open circuit",
                                     "spray bar socketpair: nozzle 40: valve stuck (flow "
                                     "disagrees with command)"));
  EXPECT_EQ(ToNozzleBar(bar.status()).open.size(), 64u);
  EXPECT_TRUE(ToNozzleBar(bar.status()).open[63]);
  // Every shot of nozzle 63 from the bar's record: one, still open.
  const std::vector<NozzleShot> shots = ShotsFromValves(sim.history(), t);
  int shots63 = 0;
  for (const NozzleShot& s : shots) shots63 += s.nozzle == 63 ? 1 : 0;
  EXPECT_EQ(shots63, 1);
}

TEST_F(SprayBarTest, PerNozzleFaultsAreReportedAndHeldClosedWithoutFailSafe) {
  ASSERT_GT(TicksUntilReady(0xF), 0);
  Tick(0xF);
  sim_->InjectFault(2, NozzleFault::kOpenCircuit);
  sim_->InjectFault(5, NozzleFault::kStuck);
  Tick(0xF);  // the vehicle learns of the faults in this tick's Poll
  Tick(0xF);
  EXPECT_FALSE(status().failsafe);
  EXPECT_EQ(status().nozzle_faults[2], NozzleFault::kOpenCircuit);
  EXPECT_EQ(status().nozzle_faults[5], NozzleFault::kStuck);
  EXPECT_EQ(status().nozzle_faults[0], NozzleFault::kNone);
  EXPECT_EQ(status().commanded_mask, 0xBu);  // nozzle 2 held closed
  EXPECT_EQ(sim_->open_mask(), 0xBu);
  const std::vector<std::string> lines = vehicle_->HealthFaults();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "spray bar socketpair: nozzle 2: valve coil open circuit");
  EXPECT_EQ(lines[1], "spray bar socketpair: nozzle 5: valve stuck (flow disagrees with command)");
  const NozzleBar nozzles = ToNozzleBar(status());
  EXPECT_FALSE(nozzles.failsafe);
  EXPECT_EQ(nozzles.fault[2], int{plantscale_nozzles_t::FAULT_STUCK});
  EXPECT_EQ(nozzles.fault[5], int{plantscale_nozzles_t::FAULT_STUCK});
  EXPECT_EQ(nozzles.fault[0], int{plantscale_nozzles_t::FAULT_NONE});
  EXPECT_EQ(nozzles.open, (std::vector<bool>{true, true, false, true, false, false, false, false}));
  sim_->InjectFault(2, NozzleFault::kNone);
  Tick(0xF);
  Tick(0xF);
  EXPECT_EQ(sim_->open_mask(), 0xFu);
}

TEST_F(SprayBarTest, BarLevelFaultAndWrongNozzleCountFailSafe) {
  ASSERT_GT(TicksUntilReady(0x1), 0);
  sim_->SetBarFault(true);
  for (int i = 0; i < 3; ++i) Tick(0x1);
  EXPECT_TRUE(status().failsafe);
  EXPECT_THAT(status().reasons, Contains(HasSubstr("bar reports a bar-level fault")));
  EXPECT_EQ(sim_->open_mask(), 0u);
  sim_->SetBarFault(false);
  ASSERT_GT(TicksUntilReady(0x1), 0);
  sim_->SetReportedNozzles(6);
  for (int i = 0; i < 3; ++i) Tick(0x1);
  EXPECT_TRUE(status().failsafe);
  EXPECT_THAT(status().last_error, HasSubstr("bar has 6 nozzles, configured for 8"));
}

TEST_F(SprayBarTest, ClosedPeerIsReported) {
  ASSERT_GT(TicksUntilReady(0x1), 0);
  sim_.reset();
  vehicle_->Poll(t_);
  EXPECT_TRUE(status().failsafe);
  EXPECT_THAT(status().last_error, HasSubstr("closed the connection"));
}

TEST_F(SprayBarTest, SinkDrivesTheBarLikeTheScheduler) {
  const auto sink = vehicle_->Sink();
  for (int i = 0; i < 10; ++i) {
    sink(t_, 0x5);
    sim_->Step(t_);
    t_ += kTick;
  }
  EXPECT_FALSE(status().failsafe);
  EXPECT_EQ(sim_->open_mask(), 0x5u);
  EXPECT_EQ(status().requested_mask, 0x5u);
  EXPECT_THROW(sink(t_, uint64_t{1} << 8), InternalError);  // bar has 8 nozzles
}

TEST(SprayBarOpenTest, InterfaceThatDoesNotExistIsAClearError) {
  try {
    SprayBar::Open("nosuchcan0", BarLinkOptions{});
    FAIL() << "opened a CAN interface that does not exist";
  } catch (const CanError& e) {
    EXPECT_THAT(std::string(e.what()),
                AllOf(HasSubstr("cannot open CAN interface 'nosuchcan0'"),
                      HasSubstr("no such network interface"), HasSubstr("No such device")));
  }
}

TEST(SprayBarOpenTest, NoSocketCanOrNotACanInterfaceIsAClearError) {
  // "lo" exists everywhere and is never a CAN interface. Without SocketCAN
  // in the kernel (this machine) socket(PF_CAN) fails; with it, bind does.
  try {
    OpenSocketCan("lo", ProtocolIds{});
    FAIL() << "opened lo as a CAN interface";
  } catch (const CanError& e) {
    const std::string what = e.what();
    EXPECT_THAT(what, HasSubstr("cannot open CAN interface 'lo'"));
    const bool no_socketcan =
        what.find(
            "socket(PF_CAN, SOCK_RAW, CAN_RAW): Address family not supported by protocol "
            "(this kernel has no SocketCAN") != std::string::npos;
    const bool not_can = what.find("bind: ") != std::string::npos;
    EXPECT_TRUE(no_socketcan || not_can) << what;
  }
}

TEST(SprayBarOpenTest, BadInterfaceNamesAndOptions) {
  EXPECT_THROW(
      {
        try {
          OpenSocketCan("", ProtocolIds{});
        } catch (const CanError& e) {
          EXPECT_THAT(std::string(e.what()), HasSubstr("empty interface name"));
          throw;
        }
      },
      CanError);
  EXPECT_THROW(
      {
        try {
          OpenSocketCan("a_very_long_can_name0", ProtocolIds{});
        } catch (const CanError& e) {
          EXPECT_THAT(std::string(e.what()), HasSubstr("name longer than 15 characters"));
          throw;
        }
      },
      CanError);
  BarLinkOptions o;
  o.num_nozzles = 65;
  EXPECT_THROW(SprayBar::Open("can0", o), InvalidOptionsError);
  o = BarLinkOptions{};
  o.ids.base_id = 0x214;
  EXPECT_THROW(SprayBar::Open("can0", o), InvalidOptionsError);
}

}  // namespace
}  // namespace plantscale::telemetry::can
