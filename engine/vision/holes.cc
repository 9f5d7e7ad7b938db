#include "engine/vision/holes.h"

#include <algorithm>
#include <cstring>

#include "engine/common/check.h"
#include "engine/vision/row_bits.h"

namespace plantscale::vision {

int HoleFiller::Find(int i) {
  auto& p = parent_;
  while (p[static_cast<size_t>(i)] != i) {
    p[static_cast<size_t>(i)] = p[static_cast<size_t>(p[static_cast<size_t>(i)])];
    i = p[static_cast<size_t>(i)];
  }
  return i;
}

int HoleFiller::Fill(cv::Mat& mask, int max_area_px) {
  PLANTSCALE_CHECK(mask.type() == CV_8UC1, "mask must be CV_8UC1");
  if (mask.empty() || max_area_px <= 0) return 0;
  const int width = mask.cols, height = mask.rows, words = (width + 63) / 64;
  bits_.resize(static_cast<size_t>(words));
  runs_.clear();
  parent_.clear();
  int prev_begin = 0, prev_end = 0;
  for (int v = 0; v < height; ++v) {
    detail::RowBits(mask.ptr<uint8_t>(v), width, bits_.data());
    // Soil bits: the complement within the row.
    for (int w = 0; w < words; ++w) bits_[static_cast<size_t>(w)] = ~bits_[static_cast<size_t>(w)];
    if (width % 64 != 0) bits_.back() &= (uint64_t{1} << (width % 64)) - 1;
    const int cur_begin = static_cast<int>(runs_.size());
    detail::ForEachRun(bits_.data(), width, [&](int begin, int end) {
      parent_.push_back(static_cast<int>(runs_.size()));
      runs_.push_back({v, begin, end});
    });
    const int cur_end = static_cast<int>(runs_.size());
    // 4-connectivity: runs of adjacent rows join when they share a column.
    int j = prev_begin;
    for (int i = cur_begin; i < cur_end; ++i) {
      const Run& cur = runs_[static_cast<size_t>(i)];
      while (j < prev_end && runs_[static_cast<size_t>(j)].u_end <= cur.u_begin) ++j;
      for (int k = j; k < prev_end && runs_[static_cast<size_t>(k)].u_begin < cur.u_end; ++k) {
        const int a = Find(i), b = Find(k);
        if (a < b) parent_[static_cast<size_t>(b)] = a;
        if (b < a) parent_[static_cast<size_t>(a)] = b;
      }
    }
    prev_begin = cur_begin;
    prev_end = cur_end;
  }
  area_.assign(runs_.size(), 0);
  border_.assign(runs_.size(), 0);
  for (size_t i = 0; i < runs_.size(); ++i) {
    const Run& r = runs_[i];
    const auto root = static_cast<size_t>(Find(static_cast<int>(i)));
    area_[root] += r.u_end - r.u_begin;
    if (r.v == 0 || r.v == height - 1 || r.u_begin == 0 || r.u_end == width) border_[root] = 1;
  }
  int filled = 0;
  for (size_t i = 0; i < runs_.size(); ++i) {
    const auto root = static_cast<size_t>(parent_[i]);  // compressed by the pass above
    if (border_[root] || area_[root] > max_area_px) continue;
    const Run& r = runs_[i];
    std::memset(mask.ptr<uint8_t>(r.v) + r.u_begin, 255, static_cast<size_t>(r.u_end - r.u_begin));
    filled += r.u_end - r.u_begin;
  }
  return filled;
}

}  // namespace plantscale::vision
