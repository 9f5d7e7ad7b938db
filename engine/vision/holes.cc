#include "engine/vision/holes.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"
#include "engine/vision/row_bits.h"

namespace plantscale::vision {

int HoleFiller::Fill(cv::Mat& mask, int max_area_px) {
  PLANTSCALE_CHECK(mask.type() == CV_8UC1, "mask must be CV_8UC1");
  if (mask.empty() || max_area_px <= 0) return 0;
  const int width = mask.cols, height = mask.rows, words = (width + 63) / 64;
  bits_.resize(static_cast<size_t>(words));
  // Soil: the complement of each row within the image, 4-connected.
  detail::LabelRuns(
      width, height, false,
      [&](int v) {
        detail::RowBits(mask.ptr<uint8_t>(v), width, bits_.data());
        for (uint64_t& w : bits_) w = ~w;
        if (width % 64 != 0) bits_.back() &= (uint64_t{1} << (width % 64)) - 1;
        return bits_.data();
      },
      runs_, parent_);
  area_.assign(runs_.size(), 0);
  border_.assign(runs_.size(), 0);
  for (size_t i = 0; i < runs_.size(); ++i) {
    const detail::RowRun& r = runs_[i];
    const auto root = static_cast<size_t>(parent_[i]);
    area_[root] += r.u_end - r.u_begin;
    if (r.v == 0 || r.v == height - 1 || r.u_begin == 0 || r.u_end == width) border_[root] = 1;
  }
  int filled = 0;
  for (size_t i = 0; i < runs_.size(); ++i) {
    const auto root = static_cast<size_t>(parent_[i]);
    if (border_[root] || area_[root] > max_area_px) continue;
    const detail::RowRun& r = runs_[i];
    std::memset(mask.ptr<uint8_t>(r.v) + r.u_begin, 255, static_cast<size_t>(r.u_end - r.u_begin));
    filled += r.u_end - r.u_begin;
  }
  return filled;
}

namespace {

// The lower (sign 1) or upper (sign −1) convex envelope of the points
// (v, rows[.][column]) of `rows` (v descending), as points (x = v, y = u)
// in ascending v: Andrew's monotone chain, the points already sorted.
void Envelope(const std::vector<std::array<int, 3>>& rows, int column, int sign,
              std::vector<cv::Point>& hull) {
  hull.clear();
  for (auto it = rows.rbegin(); it != rows.rend(); ++it) {
    const cv::Point p((*it)[0], (*it)[static_cast<size_t>(column)]);
    while (hull.size() >= 2) {
      const cv::Point o = hull[hull.size() - 2], a = hull.back();
      const long cross = static_cast<long>(a.x - o.x) * (p.y - o.y) -
                         static_cast<long>(a.y - o.y) * (p.x - o.x);
      if (sign * cross > 0) break;
      hull.pop_back();
    }
    hull.push_back(p);
  }
}

// The envelope's u at each row from its first vertex's to its last's.
void Interpolate(const std::vector<cv::Point>& hull, std::vector<double>& u) {
  const int v0 = hull.front().x;
  u.assign(static_cast<size_t>(hull.back().x - v0 + 1), 0.0);
  u[0] = hull.front().y;
  for (size_t k = 0; k + 1 < hull.size(); ++k) {
    const cv::Point a = hull[k], b = hull[k + 1];
    for (int v = a.x + 1; v <= b.x; ++v) {
      u[static_cast<size_t>(v - v0)] = a.y + (b.y - a.y) * static_cast<double>(v - a.x) / (b.x - a.x);
    }
  }
}

}  // namespace

int NotchCloser::DiskHalfWidth(int radius_px, int dv) {
  return static_cast<int>(std::floor(std::sqrt(radius_px * radius_px - dv * dv + 0.5)));
}

int NotchCloser::Close(cv::Mat& mask, int radius_px) {
  PLANTSCALE_CHECK(mask.type() == CV_8UC1, "mask must be CV_8UC1");
  const int width = mask.cols, height = mask.rows, r = radius_px;
  if (mask.empty() || r <= 0 || 2 * r >= height) return 0;
  const int words_per_row = (width + 63) / 64;
  const auto words = static_cast<size_t>(words_per_row);
  mask_bits_.resize(words * static_cast<size_t>(height));
  for (int v = 0; v < height; ++v) {
    detail::RowBits(mask.ptr<uint8_t>(v), width, mask_bits_.data() + static_cast<size_t>(v) * words);
  }
  half_.resize(static_cast<size_t>(2 * r + 1));
  for (int dv = -r; dv <= r; ++dv) half_[static_cast<size_t>(dv + r)] = DiskHalfWidth(r, dv);
  const auto half = [&](int dv) { return half_[static_cast<size_t>(dv + r)]; };
  steps_.resize(static_cast<size_t>(r) + 1);
  // Dilation: OR over the disk's rows of each row dilated by its half-width.
  steps_[0] = mask_bits_;
  for (int k = 1; k <= r; ++k) {
    detail::StepAlongU<true>(steps_[static_cast<size_t>(k - 1)], words_per_row, height, width, steps_[static_cast<size_t>(k)]);
  }
  // One pass over the buffer per row offset dv (rows v and v + dv both in
  // the image: one contiguous block), so the loop is long and vectorised.
  scratch_.assign(mask_bits_.size(), 0);
  for (int dv = -r; dv <= r; ++dv) {
    const int v0 = std::max(0, -dv), v1 = std::min(height, height - dv);
    uint64_t* __restrict o = scratch_.data() + static_cast<size_t>(v0) * words;
    const uint64_t* __restrict in =
        steps_[static_cast<size_t>(half(dv))].data() + static_cast<size_t>(v0 + dv) * words;
    const size_t n = static_cast<size_t>(v1 - v0) * words;
    for (size_t i = 0; i < n; ++i) o[i] |= in[i];
  }
  // Erosion: AND over the disk's rows of each row eroded by its half-width;
  // rows beyond the image count as soil.
  steps_[0] = scratch_;
  for (int k = 1; k <= r; ++k) {
    detail::StepAlongU<false>(steps_[static_cast<size_t>(k - 1)], words_per_row, height, width, steps_[static_cast<size_t>(k)]);
  }
  closed_bits_.assign(mask_bits_.size(), 0);
  const size_t inner = static_cast<size_t>(height - 2 * r) * words;
  std::fill_n(closed_bits_.data() + static_cast<size_t>(r) * words, inner, ~uint64_t{0});
  for (int dv = -r; dv <= r; ++dv) {
    uint64_t* __restrict o = closed_bits_.data() + static_cast<size_t>(r) * words;
    const uint64_t* __restrict in =
        steps_[static_cast<size_t>(half(dv))].data() + static_cast<size_t>(r + dv) * words;
    for (size_t i = 0; i < inner; ++i) o[i] &= in[i];
  }
  for (size_t i = 0; i < closed_bits_.size(); ++i) closed_bits_[i] |= mask_bits_[i];
  // A closed region keeps its new pixels only when it holds one blob.
  keep_.LabelMask(mask_bits_, width, height);
  return keep_.Add(mask_bits_, closed_bits_, nullptr, mask);
}

namespace detail {

void GrowthWithoutJoins::LabelMask(const std::vector<uint64_t>& mask_bits, int width,
                                   int height) {
  width_ = width;
  height_ = height;
  const auto words = static_cast<size_t>((width + 63) / 64);
  LabelRuns(
      width, height, true, [&](int v) { return mask_bits.data() + static_cast<size_t>(v) * words; },
      mask_runs_, mask_parent_, &mask_row_start_);
}

int GrowthWithoutJoins::Add(const std::vector<uint64_t>& mask_bits,
                            const std::vector<uint64_t>& grown_bits,
                            const std::vector<uint8_t>* counted, cv::Mat& mask,
                            const std::vector<uint8_t>* small) {
  const auto words = static_cast<size_t>((width_ + 63) / 64);
  LabelRuns(
      width_, height_, true, [&](int v) { return grown_bits.data() + static_cast<size_t>(v) * words; },
      grown_runs_, grown_parent_, &grown_row_start_);
  FindJoins(counted, small);
  // New pixels: grown bits that were soil, in runs of regions that join
  // nothing.
  int added = 0;
  for (size_t i = 0; i < grown_runs_.size(); ++i) {
    const auto root = static_cast<size_t>(grown_parent_[i]);
    if (joins_[root] && (small == nullptr || small_[root])) continue;
    added += PaintFresh(grown_runs_[i], mask_bits, grown_bits, words, mask);
  }
  return added;
}

// Per grown region: the first blob of the mask inside it, whether it holds
// another (joins_) and whether it holds a small one (small_).
void GrowthWithoutJoins::FindJoins(const std::vector<uint8_t>* counted,
                                   const std::vector<uint8_t>* small) {
  first_blob_.assign(grown_runs_.size(), -1);
  joins_.assign(grown_runs_.size(), 0);
  small_.assign(grown_runs_.size(), 0);
  for (int v = 0; v < height_; ++v) {
    int g = grown_row_start_[static_cast<size_t>(v)];
    const int g_end = grown_row_start_[static_cast<size_t>(v) + 1];
    for (int m = mask_row_start_[static_cast<size_t>(v)];
         m < mask_row_start_[static_cast<size_t>(v) + 1]; ++m) {
      const int blob = mask_parent_[static_cast<size_t>(m)];
      if (counted && !(*counted)[static_cast<size_t>(blob)]) continue;
      // The grown run containing mask run m (the growth contains the mask).
      while (g < g_end && grown_runs_[static_cast<size_t>(g)].u_end <= mask_runs_[static_cast<size_t>(m)].u_begin) ++g;
      PLANTSCALE_CHECK(g < g_end, "growth lost a pixel of the mask");
      const auto root = static_cast<size_t>(grown_parent_[static_cast<size_t>(g)]);
      if (small && (*small)[static_cast<size_t>(blob)]) small_[root] = 1;
      if (first_blob_[root] < 0) {
        first_blob_[root] = blob;
      } else if (first_blob_[root] != blob) {
        joins_[root] = 1;
      }
    }
  }
}

// Sets the pixels of one grown run that were soil in the mask; how many.
int GrowthWithoutJoins::PaintFresh(const RowRun& run, const std::vector<uint64_t>& mask_bits,
                                   const std::vector<uint64_t>& grown_bits, size_t words,
                                   cv::Mat& mask) {
  int added = 0;
  const size_t base = static_cast<size_t>(run.v) * words;
  uint8_t* row = mask.ptr<uint8_t>(run.v);
  for (int w = run.u_begin / 64; w <= (run.u_end - 1) / 64; ++w) {
    uint64_t fresh = grown_bits[base + static_cast<size_t>(w)] & ~mask_bits[base + static_cast<size_t>(w)];
    // Only this run's span of the word.
    const int lo = std::max(run.u_begin - 64 * w, 0), hi = std::min(run.u_end - 64 * w, 64);
    if (lo > 0) fresh &= ~uint64_t{0} << lo;
    if (hi < 64) fresh &= (uint64_t{1} << hi) - 1;
    while (fresh != 0) {
      row[64 * w + std::countr_zero(fresh)] = 255;
      fresh &= fresh - 1;
      ++added;
    }
  }
  return added;
}

}  // namespace detail

int HullGrower::Grow(cv::Mat& mask, const cv::Mat& low, int min_area_px) {
  PLANTSCALE_CHECK(mask.type() == CV_8UC1 && low.type() == CV_8UC1 && low.size() == mask.size(),
                   "hull growth needs two CV_8UC1 masks of one size");
  const int width = mask.cols, height = mask.rows;
  const auto words = static_cast<size_t>((width + 63) / 64);
  mask_bits_.resize(words * static_cast<size_t>(height));
  for (int v = 0; v < height; ++v) {
    detail::RowBits(mask.ptr<uint8_t>(v), width, mask_bits_.data() + static_cast<size_t>(v) * words);
  }
  keep_.LabelMask(mask_bits_, width, height);  // mask_runs() hold this frame's even when empty
  if (mask.empty()) return 0;
  const std::vector<detail::RowRun>& runs = keep_.runs();
  const std::vector<int>& parent = keep_.parent();
  // Each blob's area, and its runs chained per root (last run first).
  area_.assign(runs.size(), 0);
  first_run_.assign(runs.size(), -1);
  next_run_.resize(runs.size());
  for (size_t i = 0; i < runs.size(); ++i) {
    const auto root = static_cast<size_t>(parent[i]);
    area_[root] += runs[i].u_end - runs[i].u_begin;
    next_run_[i] = first_run_[root];
    first_run_[root] = static_cast<int>(i);
  }
  // The hulls' rows as bits. A blob's convex hull is that of its rows'
  // extreme pixels; at row v it spans [L(v), R(v)], L the lower convex
  // envelope of the rows' first pixels (u as a function of v) and R the
  // upper concave envelope of their last ones (monotone chains, the rows
  // already in order). Pixels whose centres are within half a pixel of the
  // span are set, as a filled polygon with its edges drawn.
  hull_bits_.assign(mask_bits_.size(), 0);
  counted_.assign(runs.size(), 0);
  bool any = false;
  for (size_t i = 0; i < runs.size(); ++i) {
    if (static_cast<size_t>(parent[i]) != i || area_[i] < min_area_px) continue;
    counted_[i] = 1;
    any = true;
    rows_.clear();  // (v, first u, last u), v descending
    for (int k = first_run_[i]; k >= 0; k = next_run_[static_cast<size_t>(k)]) {
      const detail::RowRun& r = runs[static_cast<size_t>(k)];
      if (!rows_.empty() && rows_.back()[0] == r.v) {
        rows_.back()[1] = std::min(rows_.back()[1], r.u_begin);
        rows_.back()[2] = std::max(rows_.back()[2], r.u_end - 1);
      } else {
        rows_.push_back({r.v, r.u_begin, r.u_end - 1});
      }
    }
    Envelope(rows_, 1, 1, left_);
    Envelope(rows_, 2, -1, right_);
    Interpolate(left_, left_u_);
    Interpolate(right_, right_u_);
    const int v0 = left_.front().x;
    for (size_t k = 0; k < left_u_.size(); ++k) {
      const int begin = static_cast<int>(std::ceil(left_u_[k] - 0.5));
      const int end = static_cast<int>(std::floor(right_u_[k] + 0.5)) + 1;
      detail::SetBits(hull_bits_.data() + (static_cast<size_t>(v0) + k) * words, begin, end);
    }
  }
  if (!any) return 0;
  // The grown mask: the mask, and the low mask inside the hulls.
  grown_bits_ = mask_bits_;
  low_bits_.resize(words);
  for (int v = 0; v < height; ++v) {
    const uint64_t* h = hull_bits_.data() + static_cast<size_t>(v) * words;
    if (std::all_of(h, h + words, [](uint64_t w) { return w == 0; })) continue;
    detail::RowBits(low.ptr<uint8_t>(v), width, low_bits_.data());
    uint64_t* g = grown_bits_.data() + static_cast<size_t>(v) * words;
    for (size_t w = 0; w < words; ++w) g[w] |= low_bits_[w] & h[w];
  }
  // A grown region holding two or more blobs of the mask (of the size that
  // gets a hull) keeps its pixels as they were.
  return keep_.Add(mask_bits_, grown_bits_, &counted_, mask);
}

}  // namespace plantscale::vision
