#pragma once
// Encoding and decoding of lcm-gen message types to and from bytes, with
// decode failures (truncated bytes, wrong fingerprint, absurd array sizes)
// reported as a message naming the channel, never thrown or crashed on.

#include <cstdint>
#include <exception>
#include <optional>
#include <string>
#include <vector>

namespace plantscale::telemetry {

using Bytes = std::vector<uint8_t>;

template <typename Message>
Bytes Encode(const Message& message) {
  Bytes bytes(static_cast<size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// Decodes `size` bytes received on `channel`; on failure returns nullopt and
// sets `*error` (when given) to a line naming the channel and the type.
template <typename Message>
std::optional<Message> Decode(const std::string& channel, const void* data, size_t size,
                              std::string* error = nullptr) {
  Message message;
  int used = -1;
  try {
    used = message.decode(data, 0, static_cast<int>(size));
  } catch (const std::exception&) {  // absurd array length: bad_alloc, length_error
    used = -1;
  }
  if (used >= 0) return message;
  if (error) {
    *error = "channel " + channel + ": cannot decode " + std::to_string(size) + " bytes as " +
             Message::getTypeName() + " (truncated, corrupt or wrong fingerprint)";
  }
  return std::nullopt;
}

}  // namespace plantscale::telemetry
