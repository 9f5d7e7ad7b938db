#include "telemetry/command_auth.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace plantscale::telemetry {
namespace {

namespace fs = std::filesystem;

constexpr int64_t kNow = 1'700'000'000'000'000;

class CommandAuthTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plantscale_command_auth_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    key_.bytes.fill(0x5a);
    other_key_.bytes.fill(0xa5);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static plantscale_command_t Command(int64_t seq, int64_t utime = kNow) {
    plantscale_command_t c{};
    c.utime = utime;
    c.seq = seq;
    c.command = plantscale_command_t::COMMAND_PAUSE;
    c.origin = "station@test";
    return c;
  }
  plantscale_command_t Signed(int64_t seq, int64_t utime = kNow) const {
    plantscale_command_t c = Command(seq, utime);
    Sign(c, key_);
    return c;
  }
  // What the vehicle receives: the bytes on the wire, decoded.
  static plantscale_command_t OverTheWire(const plantscale_command_t& c) {
    const Bytes bytes = Encode(c);
    const auto decoded = Decode<plantscale_command_t>("PLANTSCALE_COMMAND", bytes.data(), bytes.size());
    EXPECT_TRUE(decoded.has_value());
    return decoded.value_or(plantscale_command_t{});
  }
  fs::path WriteFile(const std::string& name, const std::string& content, mode_t mode) const {
    const fs::path file = dir_ / name;
    { std::ofstream(file, std::ios::binary) << content; }
    ::chmod(file.c_str(), mode);
    return file;
  }
  static mode_t ModeOf(const fs::path& file) {
    struct stat st {};
    EXPECT_EQ(::stat(file.c_str(), &st), 0);
    return st.st_mode & 07777;
  }
  static std::string ErrorOf(const fs::path& file) {
    try {
      ReadCommandKey(file);
    } catch (const CommandAuthError& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
  CommandKey key_, other_key_;
  CommandReplayState state_;
};

TEST_F(CommandAuthTest, SignedCommandIsAccepted) {
  const plantscale_command_t c = OverTheWire(Signed(1));
  EXPECT_EQ(c.mac_size, int16_t{plantscale_command_t::MAC_SIZE});
  ASSERT_EQ(c.mac.size(), 32u);
  const CommandCheck check = Verify(c, key_, kNow, state_);
  EXPECT_TRUE(check.accepted()) << check.reason;
  EXPECT_EQ(check.reason, "");
  EXPECT_EQ(state_.last_seq("station@test"), 1);
  // Every command kind and mode, and the next seqs.
  plantscale_command_t mode = Command(2);
  mode.command = plantscale_command_t::COMMAND_SET_MODE;
  mode.mode = plantscale_command_t::MODE_SPRAY_WEED;
  Sign(mode, key_);
  EXPECT_TRUE(Verify(OverTheWire(mode), key_, kNow, state_).accepted());
  EXPECT_TRUE(Verify(Signed(10), key_, kNow, state_).accepted());  // gaps are fine: seq need only increase
}

TEST_F(CommandAuthTest, TheMacCoversTheLcmEncodingWithoutTheMac) {
  const plantscale_command_t plain = Command(7);
  const plantscale_command_t s = Signed(7);
  EXPECT_EQ(CanonicalCommandBytes(s), Encode(plain));
  EXPECT_EQ(CanonicalCommandBytes(plain), Encode(plain));
  // Deterministic: the same command and key give the same MAC.
  EXPECT_EQ(CommandMac(plain, key_), CommandMac(s, key_));
  EXPECT_NE(CommandMac(plain, key_), CommandMac(plain, other_key_));
}

TEST_F(CommandAuthTest, FlippedMacByteIsForged) {
  for (size_t i : {size_t{0}, size_t{17}, size_t{31}}) {
    plantscale_command_t c = Signed(1);
    c.mac[i] ^= 0x01;
    const CommandCheck check = Verify(OverTheWire(c), key_, kNow, state_);
    EXPECT_EQ(check.verdict, CommandVerdict::kForged) << i;
    EXPECT_EQ(check.reason, "forged (bad signature)");
  }
  EXPECT_EQ(state_.last_seq("station@test"), INT64_MIN);  // nothing recorded
  EXPECT_TRUE(Verify(Signed(1), key_, kNow, state_).accepted());
}

TEST_F(CommandAuthTest, AnyFieldChangedAfterSigningIsForged) {
  const plantscale_command_t good = Signed(5);
  std::vector<plantscale_command_t> changed(6, good);
  changed[0].command = plantscale_command_t::COMMAND_START;
  changed[1].mode = plantscale_command_t::MODE_SPRAY_OFF;
  changed[2].seq = 6;                  // a replay dressed up with a new seq
  changed[3].utime = kNow + 1;         // a stale command dressed up as fresh
  changed[4].origin = "station@other"; // someone else's replay state
  changed[5].mac.resize(16), changed[5].mac_size = 16;  // a truncated MAC
  for (size_t i = 0; i < changed.size(); ++i) {
    EXPECT_EQ(Verify(OverTheWire(changed[i]), key_, kNow, state_).verdict, CommandVerdict::kForged) << i;
  }
  // Signed with another key.
  plantscale_command_t c = Command(5);
  Sign(c, other_key_);
  EXPECT_EQ(Verify(c, key_, kNow, state_).verdict, CommandVerdict::kForged);
  EXPECT_TRUE(Verify(good, key_, kNow, state_).accepted());
}

TEST_F(CommandAuthTest, SameSeqAgainIsReplayed) {
  const plantscale_command_t c = OverTheWire(Signed(3));
  ASSERT_TRUE(Verify(c, key_, kNow, state_).accepted());
  const CommandCheck again = Verify(c, key_, kNow, state_);
  EXPECT_EQ(again.verdict, CommandVerdict::kReplayed);
  EXPECT_EQ(again.reason, "replayed (seq 3, not after the last accepted 3)");
  EXPECT_EQ(Verify(Signed(2), key_, kNow, state_).verdict, CommandVerdict::kReplayed);
  // Per origin: another station's seqs are its own.
  plantscale_command_t other = Command(3);
  other.origin = "station@other";
  Sign(other, key_);
  EXPECT_TRUE(Verify(other, key_, kNow, state_).accepted());
  EXPECT_TRUE(Verify(Signed(4), key_, kNow, state_).accepted());
  EXPECT_EQ(state_.last_seq("station@test"), 4);
}

TEST_F(CommandAuthTest, OldOrFutureTimestampIsStale) {
  const CommandCheck old = Verify(Signed(1, kNow - 3'000'000), key_, kNow, state_);
  EXPECT_EQ(old.verdict, CommandVerdict::kStale);
  EXPECT_EQ(old.reason, "stale (sent 3.0 s before the vehicle's clock, window ±2.0 s)");
  const CommandCheck future = Verify(Signed(2, kNow + 2'500'000), key_, kNow, state_);
  EXPECT_EQ(future.verdict, CommandVerdict::kStale);
  EXPECT_EQ(future.reason, "stale (sent 2.5 s after the vehicle's clock, window ±2.0 s)");
  EXPECT_EQ(Verify(Signed(3, INT64_MIN), key_, kNow, state_).verdict, CommandVerdict::kStale);
  // A stale command leaves the seq alone; the window's edges are inside.
  EXPECT_TRUE(Verify(Signed(1, kNow - 2'000'000), key_, kNow, state_).accepted());
  EXPECT_TRUE(Verify(Signed(2, kNow + 2'000'000), key_, kNow, state_).accepted());
  EXPECT_EQ(Verify(Signed(3, kNow - 600'000), key_, kNow, state_, 500'000).verdict, CommandVerdict::kStale);
}

TEST_F(CommandAuthTest, NoMacIsUnsigned) {
  const CommandCheck check = Verify(OverTheWire(Command(1)), key_, kNow, state_);
  EXPECT_EQ(check.verdict, CommandVerdict::kUnsigned);
  EXPECT_EQ(check.reason, "unsigned (no signature)");
  EXPECT_EQ(state_.last_seq("station@test"), INT64_MIN);
}

TEST_F(CommandAuthTest, KeyFileReadableByOthersIsRefused) {
  const std::string hex(64, 'a');
  for (const mode_t mode : {mode_t{0644}, mode_t{0640}, mode_t{0604}, mode_t{0660}, mode_t{0601}}) {
    const fs::path file = WriteFile("shared.key", hex + "\n", mode);
    ASSERT_EQ(ModeOf(file), mode);
    std::ostringstream m;
    m << "0" << std::oct << mode;
    const std::string error = ErrorOf(file);
    EXPECT_NE(error.find(file.string()), std::string::npos) << error;
    EXPECT_NE(error.find("has mode " + m.str()), std::string::npos) << error;
    EXPECT_NE(error.find("0600"), std::string::npos) << error;
  }
  EXPECT_EQ(ErrorOf(WriteFile("shared.key", hex + "\n", 0644)),
            "command key file " + (dir_ / "shared.key").string() +
                " has mode 0644: a shared key must be readable by its owner only (mode 0600: chmod 600 " +
                (dir_ / "shared.key").string() + ")");
  // 0600 and 0400 are fine.
  EXPECT_EQ(ErrorOf(WriteFile("shared.key", hex + "\n", 0600)), "");
  EXPECT_EQ(ErrorOf(WriteFile("shared.key", hex + "\n", 0400)), "");
}

TEST_F(CommandAuthTest, KeyFileContents) {
  const CommandKey hex = ReadCommandKey(WriteFile("hex.key", "  " + std::string(62, '0') + "Ff\n\n", 0600));
  EXPECT_EQ(hex.bytes[0], 0);
  EXPECT_EQ(hex.bytes[31], 0xff);
  EXPECT_EQ(hex.file, dir_ / "hex.key");
  const CommandKey raw = ReadCommandKey(WriteFile("raw.key", std::string(32, '\x07'), 0600));
  EXPECT_EQ(raw.bytes[5], 7);
  const std::string short_error = ErrorOf(WriteFile("short.key", std::string(63, 'a'), 0600));
  EXPECT_NE(short_error.find("holds no key: expected 64 hex digits"), std::string::npos) << short_error;
  EXPECT_NE(short_error.find("found 63 bytes"), std::string::npos) << short_error;
  EXPECT_NE(ErrorOf(WriteFile("nothex.key", std::string(64, 'g'), 0600)).find("holds no key"), std::string::npos);
  EXPECT_NE(ErrorOf(WriteFile("empty.key", "", 0600)).find("found 0 bytes"), std::string::npos);
  const std::string missing = ErrorOf(dir_ / "missing.key");
  EXPECT_NE(missing.find((dir_ / "missing.key").string() + ": cannot open: No such file"), std::string::npos)
      << missing;
  EXPECT_NE(ErrorOf(dir_).find("not a regular file"), std::string::npos);
}

TEST_F(CommandAuthTest, KeygenWritesARandomKeyWithMode0600AndNeverOverwrites) {
  const mode_t old_umask = ::umask(0);  // whatever the umask, the key is 0600
  const fs::path a = dir_ / "a.key", b = dir_ / "b.key";
  WriteNewCommandKey(a);
  ::umask(0077);
  WriteNewCommandKey(b);
  ::umask(old_umask);
  EXPECT_EQ(ModeOf(a), 0600u);
  EXPECT_EQ(ModeOf(b), 0600u);
  EXPECT_EQ(fs::file_size(a), 65u);  // 64 hex digits and a newline
  const CommandKey ka = ReadCommandKey(a), kb = ReadCommandKey(b);
  EXPECT_NE(ka.bytes, kb.bytes);
  // Signed with one, verified with the same key read again.
  plantscale_command_t c = Command(1);
  Sign(c, ka);
  EXPECT_TRUE(Verify(c, ReadCommandKey(a), kNow, state_).accepted());
  // An existing file is never overwritten.
  try {
    WriteNewCommandKey(a);
    ADD_FAILURE() << "overwrote " << a;
  } catch (const CommandAuthError& e) {
    EXPECT_EQ(std::string(e.what()),
              "command key file " + a.string() + " already exists: keygen never overwrites a key (remove it first)");
  }
  EXPECT_EQ(ReadCommandKey(a).bytes, ka.bytes);
  EXPECT_THROW(WriteNewCommandKey(dir_ / "no" / "such" / "dir.key"), CommandAuthError);
}

}  // namespace
}  // namespace plantscale::telemetry
