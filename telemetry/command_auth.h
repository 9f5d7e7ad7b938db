#pragma once
// Signed station commands (PLANTSCALE_COMMAND, plantscale_command_t). The
// station and the vehicle share a 32-byte key kept in a file only its owner
// may read (`plantscale keygen FILE`). A command carries an HMAC-SHA-256
// with that key over its canonical bytes (its LCM encoding with mac_size 0
// and no mac: every other field, the type's fingerprint included). The
// vehicle obeys a command only when
//   - it is signed (mac_size != 0), else kUnsigned;
//   - the MAC is the one the key gives, else kForged (compared in constant
//     time; a changed field, a wrong key or a damaged MAC alike);
//   - its seq is greater than the last one accepted from the same origin,
//     else kReplayed;
//   - its utime lies within ±window_us (kCommandWindowUs, 2 s) of the
//     vehicle's clock, else kStale (a command recorded before the vehicle
//     restarted and forgot its seqs).
// Nothing here touches a transport: the station signs what it publishes,
// the vehicle runner verifies what it receives. Errors throw CommandAuthError.

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <plantscale_lcmtypes/plantscale_command_t.hpp>
#include <stdexcept>
#include <string>

#include "telemetry/codec.h"

namespace plantscale::telemetry {

class CommandAuthError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr size_t kCommandKeyBytes = 32;
inline constexpr int64_t kCommandWindowUs = 2'000'000;

struct CommandKey {
  std::array<uint8_t, kCommandKeyBytes> bytes{};
  std::filesystem::path file;  // where it was read from, for messages
};

// Reads a key file: 64 hex digits (what WriteNewCommandKey writes; white
// space around them is ignored) or exactly 32 raw bytes. Throws
// CommandAuthError naming the file when it cannot be opened, is not a
// regular file, has any group or other permission bits (the message gives
// its mode, e.g. 0644, and asks for 0600), or holds no key.
CommandKey ReadCommandKey(const std::filesystem::path& file);

// Writes a new random key (OpenSSL's RAND_bytes) to `file` as 64 hex digits
// and a newline; the file is created with mode 0600. Throws CommandAuthError
// when the file already exists (a key is never overwritten) or cannot be
// written.
void WriteNewCommandKey(const std::filesystem::path& file);

// What the MAC covers: the LCM encoding of `command` with mac_size 0.
Bytes CanonicalCommandBytes(const plantscale_command_t& command);
// HMAC-SHA-256 of the canonical bytes with `key`.
std::array<uint8_t, plantscale_command_t::MAC_SIZE> CommandMac(const plantscale_command_t& command,
                                                               const CommandKey& key);
// Sets command.mac_size and command.mac.
void Sign(plantscale_command_t& command, const CommandKey& key);

enum class CommandVerdict { kAccepted, kUnsigned, kForged, kReplayed, kStale };

struct CommandCheck {
  CommandVerdict verdict = CommandVerdict::kAccepted;
  std::string reason;  // e.g. "forged (bad signature)"; empty when accepted
  bool accepted() const { return verdict == CommandVerdict::kAccepted; }
};

// The highest seq accepted from each origin (only authenticated origins
// are ever recorded).
class CommandReplayState {
 public:
  // The last seq accepted from `origin`, or INT64_MIN.
  int64_t last_seq(const std::string& origin) const;
  void Accept(const std::string& origin, int64_t seq) { last_seq_[origin] = seq; }

 private:
  std::map<std::string, int64_t> last_seq_;
};

// Checks `command` against `key` at `now_utime` on the vehicle's clock; an
// accepted command's seq is recorded in `state`, nothing else changes it.
CommandCheck Verify(const plantscale_command_t& command, const CommandKey& key, int64_t now_utime,
                    CommandReplayState& state, int64_t window_us = kCommandWindowUs);

}  // namespace plantscale::telemetry
