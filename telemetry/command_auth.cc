#include "telemetry/command_auth.h"

#include <fcntl.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <utility>

namespace plantscale::telemetry {
namespace {

std::string Quoted(const std::filesystem::path& file) { return "command key file " + file.string(); }

std::string Mode(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof text, "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

// Closes a file descriptor on every path out.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  int Release() { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool ParseHexKey(const std::string& text, CommandKey& key) {
  const size_t begin = text.find_first_not_of(" \t\r\n");
  const size_t end = text.find_last_not_of(" \t\r\n");
  if (begin == std::string::npos || end - begin + 1 != 2 * kCommandKeyBytes) return false;
  for (size_t i = 0; i < kCommandKeyBytes; ++i) {
    const int hi = HexDigit(text[begin + 2 * i]), lo = HexDigit(text[begin + 2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    key.bytes[i] = static_cast<uint8_t>(hi * 16 + lo);
  }
  return true;
}

}  // namespace

CommandKey ReadCommandKey(const std::filesystem::path& file) {
  Fd fd(::open(file.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) {
    throw CommandAuthError(Quoted(file) + ": cannot open: " + std::strerror(errno));
  }
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) {
    throw CommandAuthError(Quoted(file) + ": cannot stat: " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) throw CommandAuthError(Quoted(file) + ": not a regular file");
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    throw CommandAuthError(Quoted(file) + " has mode " + Mode(st.st_mode) +
                           ": a shared key must be readable by its owner only (mode 0600: "
                           "chmod 600 " + file.string() + ")");
  }
  constexpr size_t kMaxBytes = 4096;  // a key file is 65 bytes; do not read a stray large file
  std::string text;
  char buffer[512];
  for (;;) {
    const ssize_t n = ::read(fd.get(), buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw CommandAuthError(Quoted(file) + ": cannot read: " + std::strerror(errno));
    if (n == 0) break;
    text.append(buffer, static_cast<size_t>(n));
    if (text.size() > kMaxBytes) break;
  }
  CommandKey key;
  key.file = file;
  if (ParseHexKey(text, key)) return key;
  if (text.size() == kCommandKeyBytes) {
    std::memcpy(key.bytes.data(), text.data(), kCommandKeyBytes);
    return key;
  }
  throw CommandAuthError(Quoted(file) + ": holds no key: expected 64 hex digits (as plantscale keygen "
                         "writes) or 32 raw bytes, found " +
                         (text.size() > kMaxBytes ? "more than " + std::to_string(kMaxBytes)
                                                  : std::to_string(text.size())) +
                         " bytes");
}

void WriteNewCommandKey(const std::filesystem::path& file) {
  std::array<uint8_t, kCommandKeyBytes> bytes{};
  if (RAND_bytes(bytes.data(), static_cast<int>(bytes.size())) != 1) {
    throw CommandAuthError("cannot generate a command key: OpenSSL has no random bytes");
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string text;
  for (const uint8_t b : bytes) text += {kHex[b >> 4], kHex[b & 15]};
  text += '\n';
  OPENSSL_cleanse(bytes.data(), bytes.size());
  Fd fd(::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600));
  if (fd.get() < 0) {
    const int error = errno;
    if (error == EEXIST) {
      throw CommandAuthError(Quoted(file) +
                             " already exists: keygen never overwrites a key (remove it first)");
    }
    throw CommandAuthError(Quoted(file) + ": cannot create: " + std::strerror(error));
  }
  const auto fail = [&](const std::string& what) {
    const int error = errno;
    ::close(fd.Release());
    std::filesystem::remove(file);
    OPENSSL_cleanse(text.data(), text.size());
    throw CommandAuthError(Quoted(file) + ": cannot " + what + ": " + std::strerror(error));
  };
  // Exactly 0600 whatever the umask (which could only remove bits).
  if (::fchmod(fd.get(), 0600) != 0) fail("set its mode to 0600");
  size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd.get(), text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("write");
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd.get()) != 0) fail("sync");
  OPENSSL_cleanse(text.data(), text.size());
  if (::close(fd.Release()) != 0) {
    const int error = errno;
    std::filesystem::remove(file);
    throw CommandAuthError(Quoted(file) + ": cannot close: " + std::strerror(error));
  }
}

Bytes CanonicalCommandBytes(const plantscale_command_t& command) {
  plantscale_command_t c = command;
  c.mac_size = 0;
  c.mac.clear();
  return Encode(c);
}

std::array<uint8_t, plantscale_command_t::MAC_SIZE> CommandMac(const plantscale_command_t& command,
                                                               const CommandKey& key) {
  const Bytes bytes = CanonicalCommandBytes(command);
  std::array<uint8_t, plantscale_command_t::MAC_SIZE> mac{};
  unsigned int size = 0;
  if (HMAC(EVP_sha256(), key.bytes.data(), static_cast<int>(key.bytes.size()), bytes.data(), bytes.size(),
           mac.data(), &size) == nullptr ||
      size != mac.size()) {
    throw CommandAuthError("HMAC-SHA-256 failed (OpenSSL)");
  }
  return mac;
}

void Sign(plantscale_command_t& command, const CommandKey& key) {
  const auto mac = CommandMac(command, key);
  command.mac.assign(mac.begin(), mac.end());
  command.mac_size = static_cast<int16_t>(mac.size());
}

int64_t CommandReplayState::last_seq(const std::string& origin) const {
  const auto it = last_seq_.find(origin);
  return it == last_seq_.end() ? std::numeric_limits<int64_t>::min() : it->second;
}

CommandCheck Verify(const plantscale_command_t& command, const CommandKey& key, int64_t now_utime,
                    CommandReplayState& state, int64_t window_us) {
  if (command.mac_size == 0 && command.mac.empty()) {
    return {CommandVerdict::kUnsigned, "unsigned (no signature)"};
  }
  const auto expected = CommandMac(command, key);
  if (command.mac_size != plantscale_command_t::MAC_SIZE || command.mac.size() != expected.size() ||
      CRYPTO_memcmp(command.mac.data(), expected.data(), expected.size()) != 0) {
    return {CommandVerdict::kForged, "forged (bad signature)"};
  }
  const int64_t last = state.last_seq(command.origin);
  if (command.seq <= last) {
    return {CommandVerdict::kReplayed, "replayed (seq " + std::to_string(command.seq) +
                                           ", not after the last accepted " + std::to_string(last) + ")"};
  }
  // In doubles: a station's clock may be anything, and an int64 difference
  // could overflow.
  const double off_s = 1e-6 * (static_cast<double>(command.utime) - static_cast<double>(now_utime));
  if (std::abs(off_s) > 1e-6 * static_cast<double>(window_us)) {
    std::ostringstream why;
    why.precision(1);
    why << std::fixed << "stale (sent " << std::abs(off_s) << " s " << (off_s < 0 ? "before" : "after")
        << " the vehicle's clock, window ±" << 1e-6 * static_cast<double>(window_us) << " s)";
    return {CommandVerdict::kStale, why.str()};
  }
  state.Accept(command.origin, command.seq);
  return {};
}

}  // namespace plantscale::telemetry
