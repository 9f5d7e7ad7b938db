#pragma once
// Encoding and decoding of lcm-gen message types to and from bytes, with
// decode failures (truncated bytes, wrong fingerprint, absurd array sizes)
// reported as a message naming the channel, never thrown or crashed on.

#include <cstdint>
#include <exception>
#include <optional>
#include <string>
#include <vector>

class plantscale_map_tile_t;
class plantscale_plant_list_t;
class plantscale_thumbnail_t;

namespace plantscale::telemetry {

using Bytes = std::vector<uint8_t>;

// lcm-gen's decode() sizes a variable-length array from its length field
// before it checks that the bytes are there, so a 70-byte message declaring
// 2^31 map cells made it allocate and zero 2 GB (found by tests/fuzz/lcm_fuzz).
// Decode first checks the 32-bit length fields of the types that have them
// against the bytes received (codec.cc); a 16-bit length costs at most a few
// MB and is left to decode().
template <typename Message>
bool DeclaredLengthsFit(const void* /*data*/, size_t /*size*/) {
  return true;
}
template <>
bool DeclaredLengthsFit<plantscale_map_tile_t>(const void* data, size_t size);
template <>
bool DeclaredLengthsFit<plantscale_plant_list_t>(const void* data, size_t size);
template <>
bool DeclaredLengthsFit<plantscale_thumbnail_t>(const void* data, size_t size);

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
    if (size <= static_cast<size_t>(INT32_MAX) && DeclaredLengthsFit<Message>(data, size)) {
      used = message.decode(data, 0, static_cast<int>(size));
    }
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
