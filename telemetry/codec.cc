#include "telemetry/codec.h"

#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_list_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>

namespace plantscale::telemetry {
namespace {

// LCM integers are big-endian.
int64_t Int32At(const void* data, size_t offset) {
  const auto* p = static_cast<const uint8_t*>(data) + offset;
  return static_cast<int32_t>((uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) |
                              (uint32_t{p[2]} << 8) | uint32_t{p[3]});
}

// `count` elements of `element` bytes each in the `size - at` bytes left.
bool Fits(int64_t count, int64_t element, size_t size, size_t at) {
  return count >= 0 && at <= size && count * element <= static_cast<int64_t>(size - at);
}

// The encoded size (fingerprint included) of `M` with its arrays empty: in
// these types the 32-bit length field is the last field before its array.
template <typename M>
size_t EmptySize() {
  static const size_t n = static_cast<size_t>(M{}.getEncodedSize());
  return n;
}

}  // namespace

// ... int8_t encoding; int32_t num_bytes; byte cells[num_bytes]
template <>
bool DeclaredLengthsFit<plantscale_map_tile_t>(const void* data, size_t size) {
  const size_t end = EmptySize<plantscale_map_tile_t>();
  if (size < end) return true;  // num_bytes itself is cut: decode() reports it
  return Fits(Int32At(data, end - 4), 1, size, end);
}

// ... int32_t num_plants; plantscale_plant_t plants[num_plants]
template <>
bool DeclaredLengthsFit<plantscale_plant_list_t>(const void* data, size_t size) {
  const size_t end = EmptySize<plantscale_plant_list_t>();
  if (size < end) return true;
  static const int64_t plant = plantscale_plant_t{}._getEncodedSizeNoHash();
  return Fits(Int32At(data, end - 4), plant, size, end);
}

// ... int32_t jpeg_size; byte jpeg[jpeg_size]; int32_t num_blobs; plantscale_blob_t blobs[num_blobs]
template <>
bool DeclaredLengthsFit<plantscale_thumbnail_t>(const void* data, size_t size) {
  const size_t jpeg_at = EmptySize<plantscale_thumbnail_t>() - 4;  // num_blobs is last
  if (size < jpeg_at) return true;  // jpeg_size itself is cut: decode() reports it
  const int64_t jpeg = Int32At(data, jpeg_at - 4);
  if (!Fits(jpeg, 1, size, jpeg_at)) return false;
  const size_t blobs_at = jpeg_at + static_cast<size_t>(jpeg) + 4;
  if (size < blobs_at) return true;  // num_blobs is cut
  static const int64_t blob = plantscale_blob_t{}._getEncodedSizeNoHash();
  return Fits(Int32At(data, blobs_at - 4), blob, size, blobs_at);
}

}  // namespace plantscale::telemetry
