#include "telemetry/gateway/client_protocol.h"

#include <gtest/gtest.h>

#include "telemetry/gateway/foxglove_convert.h"

namespace plantscale::telemetry::gateway {
namespace {

using nlohmann::json;

std::string ErrorOf(const ClientMessage& m) {
  const auto* e = std::get_if<ProtocolError>(&m);
  return e ? e->reason : std::string("(no error)");
}

TEST(GatewayProtocol, SubscribeListsItsSubscriptions) {
  const auto m = ParseClientText(
      R"({"op":"subscribe","subscriptions":[{"id":0,"channelId":3},{"id":7,"channelId":5}]})");
  const auto* s = std::get_if<Subscribe>(&m);
  ASSERT_NE(s, nullptr) << ErrorOf(m);
  ASSERT_EQ(s->subscriptions.size(), 2u);
  EXPECT_EQ(s->subscriptions[1].id, 7u);
  EXPECT_EQ(s->subscriptions[1].channel_id, 5u);
}

TEST(GatewayProtocol, UnsubscribeAndUnadvertiseTakeIds) {
  const auto u = ParseClientText(R"({"op":"unsubscribe","subscriptionIds":[0, 4294967295]})");
  ASSERT_TRUE(std::holds_alternative<Unsubscribe>(u)) << ErrorOf(u);
  EXPECT_EQ(std::get<Unsubscribe>(u).subscription_ids.back(), 4294967295u);
  const auto a = ParseClientText(R"({"op":"unadvertise","channelIds":[2]})");
  ASSERT_TRUE(std::holds_alternative<ClientUnadvertise>(a)) << ErrorOf(a);
  EXPECT_EQ(std::get<ClientUnadvertise>(a).channel_ids, std::vector<uint32_t>{2});
}

TEST(GatewayProtocol, ClientAdvertiseKeepsTopicEncodingAndSchemaName) {
  const auto m = ParseClientText(
      R"({"op":"advertise","channels":[{"id":1,"topic":"PLANTSCALE_COMMAND","encoding":"json","schemaName":"plantscale.Command"}]})");
  const auto* a = std::get_if<ClientAdvertise>(&m);
  ASSERT_NE(a, nullptr) << ErrorOf(m);
  EXPECT_EQ(a->channels[0].topic, "PLANTSCALE_COMMAND");
  EXPECT_EQ(a->channels[0].encoding, "json");
  EXPECT_EQ(a->channels[0].schema_name, "plantscale.Command");
}

TEST(GatewayProtocol, MalformedTextIsAnErrorWithAReason) {
  EXPECT_EQ(ErrorOf(ParseClientText("{")), "not valid JSON");
  EXPECT_EQ(ErrorOf(ParseClientText("[1,2]")), "not a JSON object");
  EXPECT_EQ(ErrorOf(ParseClientText(R"({"op":5})")), "no 'op' string");
  EXPECT_EQ(ErrorOf(ParseClientText(R"({"op":"getParameters"})")),
            "unsupported op 'getParameters'");
  EXPECT_EQ(ErrorOf(ParseClientText(R"({"op":"subscribe","subscriptions":{}})")),
            "'subscriptions' must be an array");
  EXPECT_NE(
      ErrorOf(ParseClientText(R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})"))
          .find("uint32"),
      std::string::npos);
  EXPECT_NE(ErrorOf(ParseClientText(
                        R"({"op":"subscribe","subscriptions":[{"id":4294967296,"channelId":1}]})"))
                .find("uint32"),
            std::string::npos);
  EXPECT_NE(
      ErrorOf(ParseClientText(R"({"op":"subscribe","subscriptions":[{"id":1.5,"channelId":1}]})"))
          .find("uint32"),
      std::string::npos);
  EXPECT_NE(
      ErrorOf(ParseClientText(R"({"op":"unsubscribe","subscriptionIds":["a"]})")).find("uint32"),
      std::string::npos);
  EXPECT_NE(ErrorOf(ParseClientText(
                        R"({"op":"advertise","channels":[{"id":1,"topic":7,"encoding":"json"}]})"))
                .find("topic"),
            std::string::npos);
}

TEST(GatewayProtocol, OversizeInputIsRefusedBeforeParsing) {
  ProtocolLimits limits;
  limits.max_message_bytes = 100;
  const std::string big = R"({"op":"subscribe","subscriptions":[)" + std::string(200, ' ') + "]}";
  EXPECT_EQ(ErrorOf(ParseClientText(big, limits)),
            "message of " + std::to_string(big.size()) + " bytes (at most 100)");
  EXPECT_NE(ErrorOf(ParseClientBinary(std::string(101, '\x01'), limits)).find("at most 100"),
            std::string::npos);
  // Too many items, and a string beyond its bound.
  limits = ProtocolLimits{};
  limits.max_items = 2;
  EXPECT_NE(ErrorOf(ParseClientText(R"({"op":"unsubscribe","subscriptionIds":[1,2,3]})", limits))
                .find("at most 2"),
            std::string::npos);
  const std::string long_topic = R"({"op":"advertise","channels":[{"id":1,"topic":")" +
                                 std::string(300, 'a') + R"(","encoding":"json"}]})";
  EXPECT_FALSE(std::holds_alternative<ClientAdvertise>(ParseClientText(long_topic)));
}

TEST(GatewayProtocol, DeeplyNestedJsonIsRefusedWithoutCrashing) {
  const std::string deep = std::string(20000, '[') + std::string(20000, ']');
  EXPECT_EQ(ErrorOf(ParseClientText(deep)), "not a JSON object");
}

TEST(GatewayProtocol, ClientMessageDataIsLittleEndianChannelThenPayload) {
  const std::string frame = std::string("\x01\x02\x01\x00\x00", 5) + R"({"x":1})";
  const auto m = ParseClientBinary(frame);
  const auto* d = std::get_if<ClientMessageData>(&m);
  ASSERT_NE(d, nullptr) << ErrorOf(m);
  EXPECT_EQ(d->channel_id, 258u);
  EXPECT_EQ(d->payload, R"({"x":1})");
  EXPECT_EQ(ErrorOf(ParseClientBinary("")), "empty binary message");
  EXPECT_EQ(ErrorOf(ParseClientBinary(std::string("\x01\x02", 2))),
            "client message data shorter than its 5-byte header");
  EXPECT_EQ(ErrorOf(ParseClientBinary(std::string("\x02\x00\x00\x00\x00", 5))),
            "unsupported binary opcode 2");
}

TEST(GatewayProtocol, MessageDataHeaderIsOpcodeSubscriptionAndNanoseconds) {
  const std::string h = MessageDataHeader(0x01020304u, 0x1122334455667788ull);
  ASSERT_EQ(h.size(), 13u);
  const std::string expected("\x01\x04\x03\x02\x01\x88\x77\x66\x55\x44\x33\x22\x11", 13);
  EXPECT_EQ(h, expected);
}

TEST(GatewayProtocol, ServerInfoOffersClientPublishOnlyToOperators) {
  const json viewer = json::parse(ServerInfo({"gw", "1", false, "ann", "viewer"}));
  EXPECT_EQ(viewer.at("op"), "serverInfo");
  EXPECT_TRUE(viewer.at("capabilities").empty());
  EXPECT_FALSE(viewer.contains("supportedEncodings"));
  const json op = json::parse(ServerInfo({"gw", "1", true, "bob", "operator"}));
  EXPECT_EQ(op.at("capabilities"), json::array({"clientPublish"}));
  EXPECT_EQ(op.at("supportedEncodings"), json::array({"json"}));
  EXPECT_EQ(op.at("metadata").at("role"), "operator");
}

TEST(GatewayProtocol, AdvertiseNamesEveryTopicWithItsJsonSchema) {
  const json a = json::parse(AdvertiseAll());
  EXPECT_EQ(a.at("op"), "advertise");
  ASSERT_EQ(a.at("channels").size(), Topics().size());
  for (size_t i = 0; i < Topics().size(); ++i) {
    const json& c = a.at("channels")[i];
    EXPECT_EQ(c.at("id"), i + 1);
    EXPECT_EQ(c.at("topic"), Topics()[i].name);
    EXPECT_EQ(c.at("encoding"), "json");
    EXPECT_EQ(c.at("schemaEncoding"), "jsonschema");
    EXPECT_EQ(json::parse(c.at("schema").get<std::string>()).at("title"), Topics()[i].schema_name);
  }
}

}  // namespace
}  // namespace plantscale::telemetry::gateway
