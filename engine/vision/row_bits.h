#pragma once
// One mask row as bits (blobs.cc, holes.cc): bit u % 64 of words[u / 64] is
// set where row[u] != 0; bits past `width` are clear. Sixteen pixels a
// compare with SSE2 (baseline x86-64).

#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

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

// Sets bits [begin, end) of a row's words (begin < end).
inline void SetBits(uint64_t* words, int begin, int end) {
  if (begin >= end) return;
  const int first = begin / 64, last = (end - 1) / 64;
  const uint64_t head = ~uint64_t{0} << (begin % 64);
  const uint64_t tail = ~uint64_t{0} >> (63 - (end - 1) % 64);
  if (first == last) {
    words[first] |= head & tail;
    return;
  }
  words[first] |= head;
  for (int w = first + 1; w < last; ++w) words[w] = ~uint64_t{0};
  words[last] |= tail;
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

// Runs of set pixels and their connected sets (holes.cc): pixels
// [u_begin, u_end) of image row v; `parent` holds, per run, a run of the
// same set with a smaller index (the set's root is its first run).
struct RowRun {
  int v, u_begin, u_end;
};

inline int FindRoot(std::vector<int>& parent, int i) {
  while (parent[static_cast<size_t>(i)] != i) {
    parent[static_cast<size_t>(i)] = parent[static_cast<size_t>(parent[static_cast<size_t>(i)])];
    i = parent[static_cast<size_t>(i)];
  }
  return i;
}

// Joins the runs [cur_begin, cur_end) of a row with those [prev_begin,
// prev_end) of the row above that touch them: sharing a column, or with
// `diagonal` also meeting at a corner (8-connectivity). Two pointers, since
// both rows' runs are sorted by u.
inline void UniteAdjacentRows(const std::vector<RowRun>& runs, std::vector<int>& parent,
                              int prev_begin, int prev_end, int cur_begin, int cur_end,
                              bool diagonal) {
  const int reach = diagonal ? 1 : 0;
  int j = prev_begin;
  for (int i = cur_begin; i < cur_end; ++i) {
    const RowRun& cur = runs[static_cast<size_t>(i)];
    while (j < prev_end && runs[static_cast<size_t>(j)].u_end + reach <= cur.u_begin) ++j;
    for (int k = j; k < prev_end && runs[static_cast<size_t>(k)].u_begin < cur.u_end + reach;
         ++k) {
      const int a = FindRoot(parent, i), b = FindRoot(parent, k);
      if (a < b) parent[static_cast<size_t>(b)] = a;
      if (b < a) parent[static_cast<size_t>(a)] = b;
    }
  }
}

// Every run's parent becomes its set's root: parents precede their children,
// so one pass in order suffices.
inline void ResolveRoots(std::vector<int>& parent) {
  for (size_t i = 0; i < parent.size(); ++i) parent[i] = parent[static_cast<size_t>(parent[i])];
}

// The runs of set bits of `height` rows of `width` pixels, row_words(v)
// giving row v's words, into `runs` (raster order) and their connected sets
// into `parent`, each run pointing at its set's root (`diagonal`: 8-, else
// 4-connectivity). With `row_start`, row v's runs are [row_start[v],
// row_start[v + 1]).
template <typename RowWords>
void LabelRuns(int width, int height, bool diagonal, RowWords&& row_words,
               std::vector<RowRun>& runs, std::vector<int>& parent,
               std::vector<int>* row_start = nullptr) {
  runs.clear();
  parent.clear();
  if (row_start) row_start->assign(static_cast<size_t>(height) + 1, 0);
  int prev_begin = 0, prev_end = 0;
  for (int v = 0; v < height; ++v) {
    const int cur_begin = static_cast<int>(runs.size());
    if (row_start) (*row_start)[static_cast<size_t>(v)] = cur_begin;
    ForEachRun(row_words(v), width, [&](int begin, int end) {
      parent.push_back(static_cast<int>(runs.size()));
      runs.push_back({v, begin, end});
    });
    const int cur_end = static_cast<int>(runs.size());
    UniteAdjacentRows(runs, parent, prev_begin, prev_end, cur_begin, cur_end, diagonal);
    prev_begin = cur_begin;
    prev_end = cur_end;
  }
  if (row_start) (*row_start)[static_cast<size_t>(height)] = static_cast<int>(runs.size());
  ResolveRoots(parent);
}

// out = in dilated (kDilate) or eroded by one pixel along u; `in` holds
// rows of `words` words one after the other. One flat pass over every word
// (vectorised), then the first and last word of each row are redone
// without their neighbour across the row's ends (pixels beyond the image
// are soil); bits past `width` are cleared.
template <bool kDilate>
inline void StepAlongU(const std::vector<uint64_t>& in, int words, int rows, int width,
                std::vector<uint64_t>& out) {
  out.resize(in.size());
  const size_t n = in.size();
  const uint64_t* __restrict x = in.data();
  uint64_t* __restrict o = out.data();
  for (size_t i = 1; i + 1 < n; ++i) {
    const uint64_t up = (x[i] << 1) | (x[i - 1] >> 63), down = (x[i] >> 1) | (x[i + 1] << 63);
    o[i] = kDilate ? (x[i] | up | down) : (x[i] & up & down);
  }
  const uint64_t last = width % 64 == 0 ? ~uint64_t{0} : (uint64_t{1} << (width % 64)) - 1;
  const auto one = [&](size_t i, bool first, bool final) {
    const uint64_t up = (x[i] << 1) | (first ? 0 : x[i - 1] >> 63);
    const uint64_t down = (x[i] >> 1) | (final ? 0 : x[i + 1] << 63);
    o[i] = kDilate ? (x[i] | up | down) : (x[i] & up & down);
  };
  for (int v = 0; v < rows; ++v) {
    const size_t begin = static_cast<size_t>(v) * static_cast<size_t>(words);
    const size_t end = begin + static_cast<size_t>(words) - 1;
    one(begin, true, begin == end);
    if (end != begin) one(end, false, true);
    o[end] &= last;
  }
}

}  // namespace plantscale::vision::detail
