// The station's gateway client: URL and token-file parsing, the reconnect
// policy, and the client against a real gateway (plain ws:// on 127.0.0.1,
// LCM over memq://): the LCM bytes arrive as published, map tiles are sent
// again on reconnecting, a wrong token is refused, an operator's signed
// command reaches LCM and verifies, a viewer's is refused; over wss://
// with certificates made here (test_certificates.h): a valid one connects,
// an expired, a not-yet-valid, a wrong-name and an untrusted one are each
// refused at once with the reason, and a gateway given a key that is not its
// certificate's does not start. The station's command line over TLS is
// tested in tests/station_connect_cli_test.sh.
#include "telemetry/gateway/client.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <atomic>
#include <ctime>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <thread>

#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/command_auth.h"
#include "telemetry/convert.h"
#include "telemetry/gateway/lcm_topics.h"
#include "telemetry/gateway/server.h"
#include "telemetry/gateway/test_certificates.h"

namespace plantscale::telemetry::gateway {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

TEST(GatewayUrl, ParsesHostPortAndPath) {
  const GatewayUrl a = ParseGatewayUrl("wss://vehicle.farm.lan:8765");
  EXPECT_TRUE(a.tls);
  EXPECT_EQ(a.host, "vehicle.farm.lan");
  EXPECT_EQ(a.port, 8765);
  EXPECT_EQ(a.target, "/");
  const GatewayUrl b = ParseGatewayUrl("wss://[::1]:9/gw?x=1");
  EXPECT_EQ(b.host, "::1");
  EXPECT_EQ(b.port, 9);
  EXPECT_EQ(b.target, "/gw?x=1");
  EXPECT_EQ(ParseGatewayUrl("wss://10.1.2.3").port, 443);
  const GatewayUrl c = ParseGatewayUrl("ws://127.0.0.1:18765/");
  EXPECT_FALSE(c.tls);
  EXPECT_EQ(c.port, 18765);
}

TEST(GatewayUrl, RefusesWhatCannotBeUsedNamingWhy) {
  const auto why = [](const std::string& url) {
    try {
      ParseGatewayUrl(url);
    } catch (const GatewayClientError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(why("https://h:1").find("must start with wss://"), std::string::npos);
  EXPECT_NE(why("vehicle:8765").find("must start with wss://"), std::string::npos);
  EXPECT_NE(why("ws://10.0.0.7:8765").find("plain ws:// only to 127.0.0.1"), std::string::npos);
  EXPECT_NE(why("wss://:8765").find("no host"), std::string::npos);
  EXPECT_NE(why("wss://h:0").find("not 1-65535"), std::string::npos);
  EXPECT_NE(why("wss://h:70000").find("not 1-65535"), std::string::npos);
  EXPECT_NE(why("wss://h:port").find("not a number"), std::string::npos);
  EXPECT_NE(why("wss://h:").find("empty port"), std::string::npos);
  EXPECT_NE(why("wss://h:1/?token=abc").find("belongs in --token-file"), std::string::npos);
  EXPECT_NE(why("wss://alice@h:1").find("--token-file"), std::string::npos);
  EXPECT_EQ(why("wss://h:1/?tokens=abc"), "accepted");
}

class TokenFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plantscale_token_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path Write(const std::string& name, const std::string& text, fs::perms perms) {
    const fs::path f = dir_ / name;
    std::ofstream(f) << text;
    fs::permissions(f, perms);
    return f;
  }
  std::string Why(const fs::path& f) {
    try {
      return "token " + ReadTokenFile(f);
    } catch (const GatewayClientError& e) {
      return e.what();
    }
  }
  fs::path dir_;
};

TEST_F(TokenFile, ReadsTheFirstLineTrimmedAndRefusesWhatIsNotAToken) {
  const auto owner = fs::perms::owner_read | fs::perms::owner_write;
  EXPECT_EQ(Why(Write("ok", "  abc123 \nsecond line\n", owner)), "token abc123");
  EXPECT_NE(Why(Write("open", "abc\n", owner | fs::perms::group_read)).find("has mode 0640"), std::string::npos);
  EXPECT_NE(Why(Write("empty", "\n", owner)).find("first line is empty"), std::string::npos);
  EXPECT_NE(Why(Write("nothing", "", owner)).find("empty"), std::string::npos);
  EXPECT_NE(Why(Write("two", "abc def\n", owner)).find("white space"), std::string::npos);
  const std::string missing = Why(dir_ / "missing");
  EXPECT_NE(missing.find("--token-file"), std::string::npos);
  EXPECT_NE(missing.find("missing: cannot read"), std::string::npos) << missing;
}

TEST(ReconnectPolicy, DoublesFromAQuarterSecondToOneSecond) {
  const ReconnectPolicy p;
  EXPECT_DOUBLE_EQ(p.DelayS(1), 0.25);
  EXPECT_DOUBLE_EQ(p.DelayS(2), 0.5);
  EXPECT_DOUBLE_EQ(p.DelayS(3), 1.0);
  EXPECT_DOUBLE_EQ(p.DelayS(4), 1.0);
  for (int n = 5; n < 100; ++n) EXPECT_DOUBLE_EQ(p.DelayS(n), 1.0) << n;
  // A link back at any moment is tried again within the cap plus one
  // attempt's timeout: under the 5 s.
  const GatewayClientOptions o;
  EXPECT_LE(p.max_delay_s + o.connect_timeout_s, 5.0);
  ReconnectPolicy bad;
  bad.max_delay_s = 0.1;
  EXPECT_EQ(bad.Validate().size(), 1u);
}

// A vehicle's LCM (memq://) behind a gateway on ws://127.0.0.1.
// With `tls`, over wss:// with that certificate.
struct Vehicle {
  explicit Vehicle(Users users, int port = 0, const TestCertificate* tls = nullptr) {
    GatewayOptions o;
    o.insecure_loopback = tls == nullptr;
    if (tls) {
      o.cert_file = tls->cert;
      o.key_file = tls->key;
    }
    o.port = port;
    gateway = std::make_unique<Gateway>(o, std::move(users), transport);
    transport.Subscribe(channels::kCommand, [this](const ReceivedMessage& m) {
      std::lock_guard lock(mutex);
      commands.emplace_back(static_cast<const uint8_t*>(m.data), static_cast<const uint8_t*>(m.data) + m.size);
    });
    gateway->Start();
    loop = std::thread([this] { RunTransportLoop(transport, *gateway, stop); });
  }
  ~Vehicle() {
    stop = true;
    loop.join();
    gateway->Stop();
  }
  Bytes PublishTile(int x, int revision) {
    plantscale_map_tile_t t{};
    t.utime = 1000 + revision;
    t.seq = revision;
    t.tile_x = x;
    t.tile_y = 0;
    t.revision = revision;
    t.origin_m[0] = 0.08 * x;
    t.origin_m[1] = 0.0;
    t.resolution_m = 0.02;
    t.width = 4;
    t.height = 4;
    t.encoding = plantscale_map_tile_t::ENC_RAW;
    t.num_bytes = 16;
    t.cells.assign(16, plantscale_map_tile_t::CELL_CROP);
    const Bytes b = Encode(t);
    transport.Publish(channels::kMapTiles, b.data(), b.size());
    return b;
  }

  LcmTransport transport{"memq://"};
  std::unique_ptr<Gateway> gateway;
  std::atomic<bool> stop{false};
  std::thread loop;
  std::mutex mutex;
  std::vector<Bytes> commands;
};

struct Received {
  std::mutex mutex;
  std::vector<std::pair<std::string, Bytes>> messages;
  GatewayClient::OnMessage Callback() {
    return [this](const std::string& channel, const void* data, size_t size, int64_t) {
      std::lock_guard lock(mutex);
      messages.emplace_back(channel, Bytes(static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + size));
    };
  }
  size_t Count(const std::string& channel) {
    std::lock_guard lock(mutex);
    return static_cast<size_t>(std::count_if(messages.begin(), messages.end(),
                                             [&](const auto& m) { return m.first == channel; }));
  }
};

template <typename F>
bool WaitUntil(F ready, std::chrono::milliseconds limit = 5000ms) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (ready()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return ready();
}

class GatewayClientLive : public ::testing::Test {
 protected:
  void SetUp() override {
    viewer_token_ = NewToken();
    operator_token_ = NewToken();
    vehicle_ = std::make_unique<Vehicle>(MakeUsers());
  }
  Users MakeUsers() const {
    Users u;
    u.users = {MakeUser("vera", Role::kViewer, viewer_token_), MakeUser("otto", Role::kOperator, operator_token_)};
    return u;
  }
  GatewayClientOptions Options(const std::string& token) const {
    GatewayClientOptions o;
    o.url = ParseGatewayUrl("ws://127.0.0.1:" + std::to_string(vehicle_->gateway->port()) + "/");
    o.token = token;
    o.reconnect.first_delay_s = 0.05;
    o.reconnect.max_delay_s = 0.2;
    return o;
  }
  std::string viewer_token_, operator_token_;
  std::unique_ptr<Vehicle> vehicle_;
};

TEST_F(GatewayClientLive, GetsTheLcmBytesAsPublishedAndTheMapAgainAfterAReconnect) {
  const Bytes tile1 = vehicle_->PublishTile(1, 1);
  const Bytes tile2 = vehicle_->PublishTile(2, 1);
  ASSERT_TRUE(WaitUntil([&] { return vehicle_->gateway->stats().lcm_messages >= 2; }));
  Received got;
  GatewayClient client(Options(viewer_token_), got.Callback());
  client.WaitFirstAttempt(5.0);
  EXPECT_EQ(client.status().state, LinkState::kConnected);
  EXPECT_EQ(client.status().role, "viewer");
  EXPECT_EQ(client.status().user, "vera");
  // Both tiles from the gateway's cache, byte for byte, then live ones.
  ASSERT_TRUE(WaitUntil([&] { return got.Count(channels::kMapTiles) >= 2; }));
  const Bytes tile3 = vehicle_->PublishTile(1, 2);
  ASSERT_TRUE(WaitUntil([&] { return got.Count(channels::kMapTiles) >= 3; }));
  {
    std::lock_guard lock(got.mutex);
    ASSERT_EQ(got.messages.size(), 3u);
    EXPECT_EQ(got.messages[0].second, tile1);
    EXPECT_EQ(got.messages[1].second, tile2);
    EXPECT_EQ(got.messages[2].second, tile3);
    got.messages.clear();
  }
  // The gateway restarts on the same port: the client reconnects by itself
  // and is sent the new gateway's map.
  const int port = vehicle_->gateway->port();
  vehicle_.reset();
  EXPECT_TRUE(WaitUntil([&] { return client.status().state == LinkState::kWaiting; }));
  EXPECT_NE(LinkText(client.status()).find("GATEWAY LINK DOWN"), std::string::npos) << LinkText(client.status());
  vehicle_ = std::make_unique<Vehicle>(MakeUsers(), port);
  const Bytes tile4 = vehicle_->PublishTile(7, 3);
  const auto back = std::chrono::steady_clock::now();
  ASSERT_TRUE(WaitUntil([&] { return got.Count(channels::kMapTiles) >= 1; }));
  EXPECT_LT(std::chrono::steady_clock::now() - back, 5s);
  EXPECT_EQ(client.status().state, LinkState::kConnected);
  EXPECT_EQ(client.status().connections, 2);
  std::lock_guard lock(got.mutex);
  EXPECT_EQ(got.messages.front().second, tile4);
}

TEST_F(GatewayClientLive, AWrongTokenIsRefusedWithoutRetrying) {
  Received got;
  GatewayClient client(Options(NewToken()), got.Callback());
  try {
    client.WaitFirstAttempt(5.0);
    FAIL() << "a wrong token was accepted";
  } catch (const GatewayClientError& e) {
    EXPECT_NE(std::string(e.what()).find("refused the token (HTTP 401: unknown token"), std::string::npos) << e.what();
  }
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(client.status().state, LinkState::kRefused);
  EXPECT_EQ(vehicle_->gateway->stats().refused, 1);  // no retry
}

TEST_F(GatewayClientLive, AnOperatorsSignedCommandReachesLcmAndVerifiesAViewersIsRefused) {
  CommandKey key;
  for (size_t i = 0; i < key.bytes.size(); ++i) key.bytes[i] = static_cast<uint8_t>(7 * i + 1);
  plantscale_command_t c{};
  c.utime = WallUtime();
  c.seq = c.utime;
  c.command = plantscale_command_t::COMMAND_SET_MODE;
  c.mode = plantscale_command_t::MODE_SPRAY_WEED;
  c.origin = "station@test";
  Sign(c, key);

  Received got;
  GatewayClient viewer(Options(viewer_token_), got.Callback());
  viewer.WaitFirstAttempt(5.0);
  const std::string refused = viewer.PublishCommand(c);
  EXPECT_NE(refused.find("refused: vera has role viewer"), std::string::npos) << refused;

  GatewayClient op(Options(operator_token_), got.Callback());
  op.WaitFirstAttempt(5.0);
  EXPECT_TRUE(op.status().operator_role);
  EXPECT_EQ(op.PublishCommand(c), "sent");
  ASSERT_TRUE(WaitUntil([&] {
    std::lock_guard lock(vehicle_->mutex);
    return !vehicle_->commands.empty();
  }));
  std::lock_guard lock(vehicle_->mutex);
  ASSERT_EQ(vehicle_->commands.size(), 1u);
  EXPECT_EQ(vehicle_->commands[0], Encode(c));  // byte for byte: the gateway forged nothing
  const auto back = Decode<plantscale_command_t>(channels::kCommand, vehicle_->commands[0].data(),
                                                 vehicle_->commands[0].size());
  ASSERT_TRUE(back);
  CommandReplayState state;
  EXPECT_TRUE(Verify(*back, key, WallUtime(), state).accepted());
}

// The gateway over wss:// with a certificate each test chooses, and a
// client that trusts exactly that certificate (--ca) unless told otherwise.
class GatewayClientTls : public ::testing::Test {
 protected:
  static constexpr long kDay = 24 * 3600;
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plantscale_tls_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    token_ = NewToken();
  }
  void TearDown() override {
    vehicle_.reset();
    fs::remove_all(dir_);
  }
  TestCertificate Make(const std::string& name, const std::string& alt_names, long not_before_s,
                       long not_after_s) {
    return MakeTestCertificate(dir_, name, name, alt_names, not_before_s, not_after_s);
  }
  void Serve(const TestCertificate& cert) {
    Users u;
    u.users = {MakeUser("vera", Role::kViewer, token_)};
    vehicle_ = std::make_unique<Vehicle>(std::move(u), 0, &cert);
  }
  GatewayClientOptions Options(const std::string& host, const fs::path& ca) const {
    GatewayClientOptions o;
    o.url = ParseGatewayUrl("wss://" + host + ":" + std::to_string(vehicle_->gateway->port()) + "/");
    o.token = token_;
    o.ca_file = ca;
    o.reconnect.first_delay_s = 0.05;
    o.reconnect.max_delay_s = 0.2;
    return o;
  }
  // Connects and returns the refusal's text, or "connected".
  std::string Attempt(const std::string& host, const fs::path& ca) {
    Received got;
    auto client = std::make_unique<GatewayClient>(Options(host, ca), got.Callback());
    std::string what = "connected";
    try {
      client->WaitFirstAttempt(5.0);
      if (client->status().state != LinkState::kConnected) what = "not connected: " + LinkText(client->status());
    } catch (const GatewayClientError& e) {
      what = e.what();
      // Refused for good: no retry however long one waits.
      std::this_thread::sleep_for(300ms);
      EXPECT_EQ(client->status().state, LinkState::kRefused);
      EXPECT_EQ(client->status().failures, 0);
    }
    return what;
  }
  fs::path dir_;
  std::string token_;
  std::unique_ptr<Vehicle> vehicle_;
};

TEST_F(GatewayClientTls, AValidCertificateConnectsByAddressAndByName) {
  const TestCertificate good = Make("good", "IP:127.0.0.1,DNS:localhost", -3600, kDay);
  Serve(good);
  EXPECT_EQ(Attempt("127.0.0.1", good.cert), "connected");
  EXPECT_EQ(Attempt("localhost", good.cert), "connected");
  EXPECT_EQ(vehicle_->gateway->stats().connections, 2);
}

TEST_F(GatewayClientTls, AnExpiredCertificateIsRefusedSayingWhenItExpired) {
  const TestCertificate old = Make("expired", "IP:127.0.0.1,DNS:localhost", -2 * kDay, -kDay);
  Serve(old);
  const std::string why = Attempt("127.0.0.1", old.cert);
  EXPECT_NE(why.find("the gateway's certificate (CN=expired) has expired: not valid after "), std::string::npos)
      << why;
  // The date it expired, to the second (a day ago, in UTC).
  const std::time_t then = std::time(nullptr) - kDay;
  std::tm tm{};
  gmtime_r(&then, &tm);
  char day[16];
  std::strftime(day, sizeof day, "%Y-%m-%d", &tm);
  EXPECT_NE(why.find(std::string("not valid after ") + day), std::string::npos) << why;
  EXPECT_EQ(vehicle_->gateway->stats().connections, 0);
}

TEST_F(GatewayClientTls, ACertificateNotYetValidIsRefusedSayingFromWhen) {
  const TestCertificate early = Make("early", "IP:127.0.0.1", kDay, 2 * kDay);
  Serve(early);
  const std::string why = Attempt("127.0.0.1", early.cert);
  EXPECT_NE(why.find("(CN=early) is not yet valid: not before "), std::string::npos) << why;
  EXPECT_NE(why.find("clocks"), std::string::npos) << why;
}

TEST_F(GatewayClientTls, ACertificateForAnotherNameIsRefusedNamingTheHostAndWhatItIsFor) {
  const TestCertificate other = Make("vehicle", "DNS:vehicle.farm.example", -3600, kDay);
  Serve(other);
  const std::string by_name = Attempt("localhost", other.cert);
  EXPECT_NE(by_name.find("(CN=vehicle) is not for host 'localhost': it names DNS:vehicle.farm.example"),
            std::string::npos)
      << by_name;
  const std::string by_address = Attempt("127.0.0.1", other.cert);
  EXPECT_NE(by_address.find("is not for address 127.0.0.1: it names DNS:vehicle.farm.example"), std::string::npos)
      << by_address;
  // A certificate naming its host only in the CN is not for that host either.
  const TestCertificate cn_only = MakeTestCertificate(dir_, "cn_only", "127.0.0.1", "", -3600, kDay);
  vehicle_.reset();
  Serve(cn_only);
  const std::string cn = Attempt("127.0.0.1", cn_only.cert);
  EXPECT_NE(cn.find("is not for address 127.0.0.1: it names no subjectAltName, only CN=127.0.0.1"), std::string::npos)
      << cn;
}

TEST_F(GatewayClientTls, ACertificateTheCaDidNotSignIsNotTrusted) {
  const TestCertificate good = Make("good", "IP:127.0.0.1", -3600, kDay);
  const TestCertificate foreign = Make("foreign", "IP:127.0.0.1", -3600, kDay);
  Serve(good);
  const std::string why = Attempt("127.0.0.1", foreign.cert);
  EXPECT_NE(why.find("the gateway's certificate is not trusted: "), std::string::npos) << why;
  EXPECT_NE(why.find("(the gateway's certificate (CN=good); checked against --ca " + foreign.cert.string() + ")"),
            std::string::npos)
      << why;
  EXPECT_EQ(vehicle_->gateway->stats().connections, 0);
}

TEST_F(GatewayClientTls, AGatewayGivenAnotherCertificatesKeyDoesNotStartNamingBothFiles) {
  const TestCertificate a = Make("a", "IP:127.0.0.1", -3600, kDay);
  const TestCertificate b = Make("b", "IP:127.0.0.1", -3600, kDay);
  GatewayOptions o;
  o.port = 0;
  o.cert_file = a.cert;
  o.key_file = b.key;
  LcmTransport t("memq://");
  try {
    Gateway g(o, Users{}, t);
    FAIL() << "started with the key of another certificate";
  } catch (const GatewayError& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("key " + b.key.string() + " does not belong to certificate " + a.cert.string()),
              std::string::npos)
        << why;
  }
}

TEST(LcmTopics, EveryChannelTheStationDecodesWithItsFingerprint) {
  for (const char* ch : {channels::kGrid, channels::kPlants, channels::kMapTiles, channels::kThumbnail,
                         channels::kEvents, channels::kGatewayEvents, channels::kHealth, channels::kNozzles,
                         channels::kOdometry, channels::kPose, channels::kSimTruth, channels::kSimTruthPose,
                         channels::kCommand}) {
    EXPECT_GE(LcmTopicIndex(ch), 0) << ch;
  }
  EXPECT_EQ(LcmTopics()[static_cast<size_t>(LcmTopicIndex(channels::kThumbnail))].drop_class,
            TopicClass::kThumbnail);
  EXPECT_EQ(LcmTopics()[static_cast<size_t>(LcmTopicIndex(channels::kGrid))].drop_class, TopicClass::kGrid);
  EXPECT_EQ(LcmTopics()[static_cast<size_t>(LcmTopicIndex(channels::kMapTiles))].drop_class,
            TopicClass::kEssential);
  EXPECT_EQ(LcmChannelId(0), Topics().size() + 1);
  EXPECT_EQ(FingerprintHex(0x12ab), "00000000000012ab");
  EXPECT_EQ(QueryParameter("/?token=a&lcm=1", "lcm"), "1");
  EXPECT_EQ(QueryParameter("/?xlcm=1", "lcm"), "");
}

}  // namespace
}  // namespace plantscale::telemetry::gateway
