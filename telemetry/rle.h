#pragma once
// Run-length encoding of map cells as (count, value) byte pairs, count 1–255.
// Map tiles are mostly long runs of soil or one class, so this shrinks them
// ~10–50× without a new dependency.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace plantscale::telemetry {

std::vector<uint8_t> RleEncode(const std::vector<uint8_t>& cells);
// Throws DataError when `encoded` has an odd length, a zero count, or does
// not expand to exactly `expected_cells`.
std::vector<uint8_t> RleDecode(const std::vector<uint8_t>& encoded, size_t expected_cells);

}  // namespace plantscale::telemetry
