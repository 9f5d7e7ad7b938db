#include "engine/vision/holes.h"

#include <algorithm>
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

// out = in dilated (kDilate) or eroded by one pixel along u; `in` holds
// rows of `words` words one after the other. One flat pass over every word
// (vectorised), then the first and last word of each row are redone
// without their neighbour across the row's ends (pixels beyond the image
// are soil); bits past `width` are cleared.
template <bool kDilate>
void StepAlongU(const std::vector<uint64_t>& in, int words, int rows, int width,
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
    StepAlongU<true>(steps_[static_cast<size_t>(k - 1)], words_per_row, height, width, steps_[static_cast<size_t>(k)]);
  }
  scratch_.assign(mask_bits_.size(), 0);
  for (int v = 0; v < height; ++v) {
    uint64_t* o = scratch_.data() + static_cast<size_t>(v) * words;
    for (int dv = -r; dv <= r; ++dv) {
      if (v + dv < 0 || v + dv >= height) continue;
      const uint64_t* in = steps_[static_cast<size_t>(half(dv))].data() +
                           static_cast<size_t>(v + dv) * words;
      for (size_t w = 0; w < words; ++w) o[w] |= in[w];
    }
  }
  // Erosion: AND over the disk's rows of each row eroded by its half-width;
  // rows beyond the image count as soil.
  steps_[0] = scratch_;
  for (int k = 1; k <= r; ++k) {
    StepAlongU<false>(steps_[static_cast<size_t>(k - 1)], words_per_row, height, width, steps_[static_cast<size_t>(k)]);
  }
  closed_bits_.assign(mask_bits_.size(), 0);
  for (int v = r; v < height - r; ++v) {
    uint64_t* o = closed_bits_.data() + static_cast<size_t>(v) * words;
    std::fill(o, o + words, ~uint64_t{0});
    for (int dv = -r; dv <= r; ++dv) {
      const uint64_t* in = steps_[static_cast<size_t>(half(dv))].data() +
                           static_cast<size_t>(v + dv) * words;
      for (size_t w = 0; w < words; ++w) o[w] &= in[w];
    }
  }
  for (size_t i = 0; i < closed_bits_.size(); ++i) closed_bits_[i] |= mask_bits_[i];
  // Blobs before and after: a closed region keeps its new pixels only when it
  // holds one blob of the mask.
  const auto label = [&](const std::vector<uint64_t>& bits, std::vector<detail::RowRun>& runs,
                         std::vector<int>& parent, std::vector<int>& row_start) {
    detail::LabelRuns(
        width, height, true, [&](int v) { return bits.data() + static_cast<size_t>(v) * words; },
        runs, parent, &row_start);
  };
  label(mask_bits_, mask_runs_, mask_parent_, mask_row_start_);
  label(closed_bits_, closed_runs_, closed_parent_, closed_row_start_);
  first_blob_.assign(closed_runs_.size(), -1);
  joins_.assign(closed_runs_.size(), 0);
  for (int v = 0; v < height; ++v) {
    int c = closed_row_start_[static_cast<size_t>(v)];
    const int c_end = closed_row_start_[static_cast<size_t>(v) + 1];
    for (int m = mask_row_start_[static_cast<size_t>(v)];
         m < mask_row_start_[static_cast<size_t>(v) + 1]; ++m) {
      // The closed run containing mask run m (the closing contains the mask).
      while (c < c_end && closed_runs_[static_cast<size_t>(c)].u_end <= mask_runs_[static_cast<size_t>(m)].u_begin) ++c;
      PLANTSCALE_CHECK(c < c_end, "closing lost a pixel of the mask");
      const auto root = static_cast<size_t>(closed_parent_[static_cast<size_t>(c)]);
      const int blob = mask_parent_[static_cast<size_t>(m)];
      if (first_blob_[root] < 0) {
        first_blob_[root] = blob;
      } else if (first_blob_[root] != blob) {
        joins_[root] = 1;
      }
    }
  }
  // New pixels: closed bits that were soil, in runs of regions that join
  // nothing.
  int added = 0;
  for (size_t i = 0; i < closed_runs_.size(); ++i) {
    if (joins_[static_cast<size_t>(closed_parent_[i])]) continue;
    const detail::RowRun& run = closed_runs_[i];
    const size_t base = static_cast<size_t>(run.v) * words;
    uint8_t* row = mask.ptr<uint8_t>(run.v);
    for (int w = run.u_begin / 64; w <= (run.u_end - 1) / 64; ++w) {
      uint64_t fresh = closed_bits_[base + static_cast<size_t>(w)] &
                       ~mask_bits_[base + static_cast<size_t>(w)];
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
  }
  return added;
}

int HullGrower::Grow(cv::Mat& mask, const cv::Mat& low, int min_area_px) {
  PLANTSCALE_CHECK(mask.type() == CV_8UC1 && low.type() == CV_8UC1 && low.size() == mask.size(),
                   "hull growth needs two CV_8UC1 masks of one size");
  if (mask.empty()) return 0;
  const int width = mask.cols, height = mask.rows;
  bits_.resize(static_cast<size_t>((width + 63) / 64));
  detail::LabelRuns(
      width, height, true,
      [&](int v) {
        detail::RowBits(mask.ptr<uint8_t>(v), width, bits_.data());
        return bits_.data();
      },
      runs_, parent_);
  // Each blob's area, and its runs' end points chained per root.
  area_.assign(runs_.size(), 0);
  first_point_.assign(runs_.size(), -1);
  ends_.clear();
  next_point_.clear();
  for (size_t i = 0; i < runs_.size(); ++i) {
    const detail::RowRun& r = runs_[i];
    const auto root = static_cast<size_t>(parent_[i]);
    area_[root] += r.u_end - r.u_begin;
    for (const int u : {r.u_begin, r.u_end - 1}) {
      next_point_.push_back(first_point_[root]);
      first_point_[root] = static_cast<int>(ends_.size());
      ends_.push_back({u, r.v});
    }
  }
  hull_.create(mask.size(), CV_8UC1);
  hull_.setTo(0);
  bool any = false;
  for (size_t i = 0; i < runs_.size(); ++i) {
    if (static_cast<size_t>(parent_[i]) != i || area_[i] < min_area_px) continue;
    points_.clear();
    for (int k = first_point_[i]; k >= 0; k = next_point_[static_cast<size_t>(k)]) {
      points_.push_back(ends_[static_cast<size_t>(k)]);
    }
    cv::convexHull(points_, hull_points_);
    cv::fillConvexPoly(hull_, hull_points_, cv::Scalar(255), cv::LINE_8);
    any = true;
  }
  if (!any) return 0;
  // The grown mask, labelled; a grown region holding two or more blobs of
  // the mask (of the size that gets a hull) keeps its pixels as they were.
  grown_.create(mask.size(), CV_8UC1);
  for (int v = 0; v < height; ++v) {
    const uint8_t* m = mask.ptr<uint8_t>(v);
    const uint8_t* l = low.ptr<uint8_t>(v);
    const uint8_t* h = hull_.ptr<uint8_t>(v);
    uint8_t* g = grown_.ptr<uint8_t>(v);
    for (int u = 0; u < width; ++u) g[u] = m[u] | (l[u] & h[u]);
  }
  detail::LabelRuns(
      width, height, true,
      [&](int v) {
        detail::RowBits(grown_.ptr<uint8_t>(v), width, bits_.data());
        return bits_.data();
      },
      grown_runs_, grown_parent_, &grown_row_start_);
  first_blob_.assign(grown_runs_.size(), -1);
  joins_.assign(grown_runs_.size(), 0);
  for (size_t i = 0; i < runs_.size(); ++i) {
    if (static_cast<size_t>(parent_[i]) != i || area_[i] < min_area_px) continue;
    const detail::RowRun& r = runs_[i];
    // The grown run holding this blob's first run: the last one starting at or before it.
    const auto row_begin = grown_runs_.begin() + grown_row_start_[static_cast<size_t>(r.v)];
    const auto row_end = grown_runs_.begin() + grown_row_start_[static_cast<size_t>(r.v) + 1];
    const auto it = std::upper_bound(row_begin, row_end, r.u_begin,
                                     [](int u, const detail::RowRun& g) { return u < g.u_begin; });
    const auto g = static_cast<size_t>(grown_parent_[static_cast<size_t>(it - 1 - grown_runs_.begin())]);
    if (first_blob_[g] < 0) {
      first_blob_[g] = static_cast<int>(i);
    } else if (first_blob_[g] != static_cast<int>(i)) {
      joins_[g] = 1;
    }
  }
  int added = 0;
  for (size_t i = 0; i < grown_runs_.size(); ++i) {
    if (joins_[static_cast<size_t>(grown_parent_[i])]) continue;
    const detail::RowRun& r = grown_runs_[i];
    uint8_t* m = mask.ptr<uint8_t>(r.v);
    for (int u = r.u_begin; u < r.u_end; ++u) {
      added += m[u] == 0;
      m[u] = 255;
    }
  }
  return added;
}

}  // namespace plantscale::vision
