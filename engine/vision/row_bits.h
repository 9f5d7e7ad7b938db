#pragma once
// One mask row as bits (blobs.cc, holes.cc): bit u % 64 of words[u / 64] is
// set where row[u] != 0; bits past `width` are clear. Sixteen pixels a
// compare with SSE2 (baseline x86-64).

#include <bit>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace plantscale::vision::detail {

inline void RowBits(const uint8_t* row, int width, uint64_t* words) {
  int u = 0;
#if defined(__SSE2__)
  const __m128i zero = _mm_setzero_si128();
  for (; u + 64 <= width; u += 64) {
    uint64_t bits = 0;
    for (int k = 0; k < 4; ++k) {
      const __m128i px = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + u + 16 * k));
      const auto soil = static_cast<uint32_t>(_mm_movemask_epi8(_mm_cmpeq_epi8(px, zero)));
      bits |= static_cast<uint64_t>(~soil & 0xFFFFu) << (16 * k);
    }
    words[u / 64] = bits;
  }
#endif
  for (int w = u / 64; w < (width + 63) / 64; ++w) words[w] = 0;
  for (; u < width; ++u) {
    if (row[u] != 0) words[u / 64] |= uint64_t{1} << (u % 64);
  }
}

// Calls run(begin, end) for every run of set bits [begin, end) of a row of
// `width` pixels held in `words`, left to right.
template <typename F>
void ForEachRun(const uint64_t* words, int width, F&& run) {
  const int n = (width + 63) / 64;
  int begin = -1;
  uint64_t carry = 0;
  for (int w = 0; w < n; ++w) {
    const uint64_t bits = words[w];
    // Runs start and end where a bit differs from the one before it.
    uint64_t edges = bits ^ ((bits << 1) | carry);
    carry = bits >> 63;
    while (edges != 0) {
      const int u = 64 * w + std::countr_zero(edges);
      edges &= edges - 1;
      if (begin < 0) {
        begin = u;
      } else {
        run(begin, u);
        begin = -1;
      }
    }
  }
  if (begin >= 0) run(begin, width);
}

}  // namespace plantscale::vision::detail
