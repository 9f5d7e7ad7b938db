#include "telemetry/can/protocol.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>

namespace plantscale::telemetry::can {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::vector<int> Bytes(const can_frame& f) { return std::vector<int>(f.data, f.data + f.can_dlc); }

std::string DecodeError(const ProtocolIds& ids, const can_frame& f) {
  try {
    Decode(ids, f);
  } catch (const CanProtocolError& e) {
    return e.what();
  }
  return "(decoded without error)";
}

TEST(CanProtocolTest, CommandWireLayoutAndRoundTrip) {
  const ProtocolIds ids;
  NozzleCommand c;
  c.seq = 7;
  c.open_mask = 0x800000A5u;
  c.hold_ms = 200;
  const can_frame f = Encode(ids, c);
  EXPECT_EQ(f.can_id, 0x210u);
  EXPECT_EQ(f.can_dlc, 8);
  EXPECT_EQ(Bytes(f), (std::vector<int>{0x07, 0x00, 0xA5, 0x00, 0x00, 0x80, 0xC8, 0x00}));
  const auto back = std::get<NozzleCommand>(Decode(ids, f));
  EXPECT_EQ(back.seq, 7);
  EXPECT_EQ(back.flags, 0);
  EXPECT_EQ(back.open_mask, 0x800000A5u);
  EXPECT_EQ(back.hold_ms, 200);
}

TEST(CanProtocolTest, AckHeartbeatFaultsRoundTripAtAnotherBase) {
  ProtocolIds ids;
  ids.base_id = 0x300;
  NozzleAck a;
  a.seq = 255;
  a.status = AckStatus::kRejected;
  a.applied_mask = 0x12345678u;
  const can_frame fa = Encode(ids, a);
  EXPECT_EQ(fa.can_id, 0x301u);
  EXPECT_EQ(Bytes(fa), (std::vector<int>{0xFF, 0x01, 0x78, 0x56, 0x34, 0x12, 0x00, 0x00}));
  const auto ab = std::get<NozzleAck>(Decode(ids, fa));
  EXPECT_EQ(ab.seq, 255);
  EXPECT_EQ(ab.status, AckStatus::kRejected);
  EXPECT_EQ(ab.applied_mask, 0x12345678u);

  BarHeartbeat h;
  h.counter = 42;
  h.state = BarState::kFault;
  h.num_nozzles = 12;
  const can_frame fh = Encode(ids, h);
  EXPECT_EQ(fh.can_id, 0x302u);
  EXPECT_EQ(Bytes(fh), (std::vector<int>{42, 2, 12, kProtocolVersion}));
  const auto hb = std::get<BarHeartbeat>(Decode(ids, fh));
  EXPECT_EQ(hb.counter, 42);
  EXPECT_EQ(hb.state, BarState::kFault);
  EXPECT_EQ(hb.num_nozzles, 12);

  NozzleFaults n;
  n.fault[0] = NozzleFault::kOpenCircuit;
  n.fault[5] = NozzleFault::kStuck;
  n.fault[31] = NozzleFault::kShortCircuit;
  const can_frame fn = Encode(ids, n);
  EXPECT_EQ(fn.can_id, 0x303u);
  EXPECT_EQ(Bytes(fn), (std::vector<int>{0x01, 0x0C, 0, 0, 0, 0, 0, 0x80}));
  const auto nb = std::get<NozzleFaults>(Decode(ids, fn));
  EXPECT_EQ(nb.section, 0);
  for (int i = 0; i < kSectionNozzles; ++i) EXPECT_EQ(nb.fault[i], n.fault[i]) << "nozzle " << i;
  // Section 1 (nozzles 32..63) on its own identifier.
  n.section = 1;
  const can_frame fn1 = Encode(ids, n);
  EXPECT_EQ(fn1.can_id, 0x304u);
  EXPECT_EQ(Bytes(fn1), Bytes(fn));
  EXPECT_EQ(std::get<NozzleFaults>(Decode(ids, fn1)).section, 1);
}

TEST(CanProtocolTest, SectionsOfABarOfMoreThan32Nozzles) {
  const ProtocolIds ids;
  EXPECT_EQ(Sections(1), 1);
  EXPECT_EQ(Sections(32), 1);
  EXPECT_EQ(Sections(33), 2);
  EXPECT_EQ(Sections(64), 2);
  NozzleCommand c{9, NozzleCommand::kFlagFailsafe, 0, 150, 1};
  const can_frame f = Encode(ids, c);
  EXPECT_EQ(f.data[1], 0x11);  // fail-safe flag, section 1 in the high nibble
  const auto back = std::get<NozzleCommand>(Decode(ids, f));
  EXPECT_EQ(back.section, 1);
  EXPECT_EQ(back.flags, NozzleCommand::kFlagFailsafe);
  NozzleAck a{3, AckStatus::kApplied, 0xF0u, 1};
  const can_frame fa = Encode(ids, a);
  EXPECT_EQ(fa.data[6], 1);
  EXPECT_EQ(std::get<NozzleAck>(Decode(ids, fa)).section, 1);
  can_frame bad = f;
  bad.data[1] = 0x20;  // section 2
  EXPECT_THAT(DecodeError(ids, bad), HasSubstr("nozzle command: section 2 beyond 0..1"));
  bad = fa;
  bad.data[6] = 2;
  EXPECT_THAT(DecodeError(ids, bad), HasSubstr("nozzle ack: section 2 beyond 0..1"));
}

TEST(CanProtocolTest, WrongIdentifierIsRejectedNamingIt) {
  const ProtocolIds ids;
  can_frame f = Encode(ids, BarHeartbeat{0, BarState::kReady, 8, kProtocolVersion});
  f.can_id = 0x218;
  EXPECT_THAT(DecodeError(ids, f),
              AllOf(HasSubstr("id 0x218"), HasSubstr("not in the bar's block 0x210..0x217")));
  f.can_id = 0x215;
  EXPECT_THAT(DecodeError(ids, f),
              AllOf(HasSubstr("id 0x215"), HasSubstr("reserved in the bar's block")));
  f.can_id = 0x20F;
  EXPECT_THAT(DecodeError(ids, f), HasSubstr("id 0x20F"));
  f.can_id = 0x212 | CAN_EFF_FLAG;
  EXPECT_THAT(DecodeError(ids, f), HasSubstr("extended (29-bit) identifier"));
  f.can_id = 0x212 | CAN_RTR_FLAG;
  EXPECT_THAT(DecodeError(ids, f), HasSubstr("remote request"));
  f.can_id = CAN_ERR_FLAG | 0x40;  // CAN_ERR_BUSOFF
  EXPECT_THAT(DecodeError(ids, f), HasSubstr("error frame from the CAN controller (class 0x040)"));
}

TEST(CanProtocolTest, WrongLengthIsRejectedNamingMessageAndDlc) {
  const ProtocolIds ids;
  can_frame f = Encode(ids, BarHeartbeat{0, BarState::kReady, 8, kProtocolVersion});
  f.can_dlc = 8;
  EXPECT_THAT(DecodeError(ids, f),
              AllOf(HasSubstr("bar heartbeat: DLC 8, expected 4"), HasSubstr("id 0x212")));
  can_frame c = Encode(ids, NozzleCommand{1, 0, 0x3, 200});
  c.can_dlc = 6;
  EXPECT_THAT(DecodeError(ids, c), HasSubstr("nozzle command: DLC 6, expected 8"));
  c.can_dlc = 15;  // nonsense DLC from a broken driver: no read past data[8]
  EXPECT_THAT(DecodeError(ids, c), HasSubstr("DLC 15, expected 8"));
  can_frame a = Encode(ids, NozzleAck{});
  a.can_dlc = 0;
  EXPECT_THAT(DecodeError(ids, a), HasSubstr("nozzle ack: DLC 0, expected 8"));
}

TEST(CanProtocolTest, BadFieldsAreRejected) {
  const ProtocolIds ids;
  can_frame h = Encode(ids, BarHeartbeat{0, BarState::kReady, 8, kProtocolVersion});
  h.data[1] = 3;
  EXPECT_THAT(DecodeError(ids, h), HasSubstr("unknown state 3"));
  h.data[1] = 0;
  h.data[2] = 0;
  EXPECT_THAT(DecodeError(ids, h), HasSubstr("nozzle count 0 not in 1..64"));
  h.data[2] = 65;
  EXPECT_THAT(DecodeError(ids, h), HasSubstr("nozzle count 65 not in 1..64"));
  can_frame a = Encode(ids, NozzleAck{});
  a.data[7] = 1;
  EXPECT_THAT(DecodeError(ids, a), HasSubstr("reserved byte 7 is not 0"));
  a.data[7] = 0;
  a.data[1] = 9;
  EXPECT_THAT(DecodeError(ids, a), HasSubstr("unknown status 9"));
  EXPECT_THAT(DecodeError(ids, Encode(ids, NozzleCommand{1, 0, 0x1, 0})),
              HasSubstr("hold_ms is 0"));
  EXPECT_THAT(
      DecodeError(ids, Encode(ids, NozzleCommand{1, NozzleCommand::kFlagFailsafe, 0x1, 100})),
      HasSubstr("fail-safe flag with nozzles open"));
  EXPECT_THAT(DecodeError(ids, Encode(ids, NozzleCommand{1, 0x02, 0x0, 100})),
              HasSubstr("unknown flag"));
}

TEST(CanProtocolTest, IdBlockValidationAndKernelFilter) {
  EXPECT_TRUE(ProtocolIds{0x210}.Validate().empty());
  EXPECT_TRUE(ProtocolIds{0x7F8}.Validate().empty());
  ASSERT_EQ(ProtocolIds{0x214}.Validate().size(), 1u);
  EXPECT_THAT(ProtocolIds{0x214}.Validate()[0].reason, HasSubstr("multiple of 8"));
  EXPECT_EQ(ProtocolIds{0x800}.Validate().size(), 1u);
  const can_filter filter = ProtocolIds{0x210}.Filter();
  const auto passes = [&](canid_t id) {
    return (id & filter.can_mask) == (filter.can_id & filter.can_mask);
  };
  for (canid_t id = 0x210; id <= 0x217; ++id) EXPECT_TRUE(passes(id)) << std::hex << id;
  EXPECT_FALSE(passes(0x20F));
  EXPECT_FALSE(passes(0x218));
  EXPECT_FALSE(passes(0x210 | CAN_EFF_FLAG));
  EXPECT_FALSE(passes(0x210 | CAN_RTR_FLAG));
}

TEST(CanProtocolTest, SequenceDistanceWrapsModulo256) {
  EXPECT_EQ(SeqDistance(5, 5), 0);
  EXPECT_EQ(SeqDistance(5, 7), 2);
  EXPECT_EQ(SeqDistance(254, 1), 3);
  EXPECT_EQ(SeqDistance(5, 4), 255);
}

}  // namespace
}  // namespace plantscale::telemetry::can
