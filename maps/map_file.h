#pragma once
// The native map file (".psmap"): a CropMap saved whole so that it can be
// re-read, merged and exported again. Format, version 1:
//
//   line 1 (ASCII):  "plantscale-map 1 <payload bytes> <crc32 hex>\n"
//   payload:         one CBOR item (RFC 8949) – a map with
//     "grid":     {"resolution_m", "origin_x_m", "origin_y_m", "cols", "rows"}
//     "layers":   {"class": bytes (u8), "crop_count": bytes (u16 little-endian),
//                  "weed_count": bytes (u16 LE), "treated": bytes (u8)},
//                 row-major, row 0 = smallest y (MapGrid::Index)
//     "plants":   [{"id", "x_m", "y_m", "class", "confidence", "radius_m",
//                   "treated", "why"}, ...]
//     "rows":     [{"index", "x_m": [...], "y_m": [...]}, ...]
//     "metadata": {"key": "value", ...}
//   The CRC-32 (IEEE 802.3, as zlib's) covers the payload bytes.
//
// Readers refuse other magic, other versions, short files, checksum
// mismatches, malformed CBOR and missing or ill-sized fields with a
// DataError naming the file and what is wrong.

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <string>

#include "maps/crop_map.h"

namespace plantscale::maps {

inline constexpr int kMapFileVersion = 1;
inline constexpr const char* kMapFileMagic = "plantscale-map";

// CRC-32 (reflected polynomial 0xEDB88320).
uint32_t Crc32(const uint8_t* data, size_t size);

// Stream level: `name` is used in messages. Write throws MapIoError when the
// stream fails (e.g. disk full); Read throws DataError for corrupt input.
void WriteMap(const CropMap& map, std::ostream& out, const std::string& name);
CropMap ReadMap(std::istream& in, const std::string& name);

// File level: SaveMap writes `path` through a temporary file beside it and
// renames it into place only when complete.
void SaveMap(const CropMap& map, const std::filesystem::path& path);
CropMap LoadMap(const std::filesystem::path& path);
// True when the file starts with the native magic (cheap sniffing for the CLI).
bool LooksLikeMapFile(const std::filesystem::path& path);

}  // namespace plantscale::maps
