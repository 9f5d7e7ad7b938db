#include "engine/vision/soil_growth.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "engine/common/vectorise.h"
#include "engine/vision/cell_grid.h"
#include "engine/vision/row_bits.h"
#include "engine/vision/smoothing.h"

namespace plantscale::vision {

OptionErrors SoilGrowthOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "z", z, 0.0, 20.0);
  RequireInRange(e, "trim_z", trim_z, 0.0, 20.0);
  if (reach_px < 1 || reach_px > 50) e.push_back({"reach_px", "must be in [1, 50]"});
  if (cell_px < 8 || cell_px > 64 || !std::has_single_bit(static_cast<unsigned>(cell_px))) {
    e.push_back({"cell_px", "must be a power of two in [8, 64]"});
  }
  if (window_cells < 1 || window_cells > 101 || window_cells % 2 == 0) {
    e.push_back({"window_cells", "must be odd and in [1, 101]"});
  }
  if (clearance_px < 0 || clearance_px > 50) e.push_back({"clearance_px", "must be in [0, 50]"});
  if (min_soil_samples < 2) e.push_back({"min_soil_samples", "must be >= 2"});
  if (min_area_px < 1) e.push_back({"min_area_px", "must be >= 1"});
  if (join_min_area_px < 0) e.push_back({"join_min_area_px", "must be >= 0"});
  return e;
}

namespace {

// Soil samples: every second pixel of every fourth row (a 7-cell window of
// 8 px holds up to 392). With every second row the step took 455 µs on the
// benchmark frame, 374 µs with every fourth.
constexpr int kRowStride = 4;

const SoilGrowthOptions& Validated(const SoilGrowthOptions& options) {
  ThrowIfInvalid("soil growth options", options.Validate());
  return options;
}

// out = in with rows v − s and v + s ORed into row v (rows of `words`
// words, the rows beyond the image empty): two passes over the buffer, each
// one contiguous block, so the loops are long and vectorised.
void ShiftOrAlongV(const std::vector<uint64_t>& in, size_t words, int s,
                   std::vector<uint64_t>& out) {
  out = in;
  const size_t shift = static_cast<size_t>(s) * words;
  if (shift >= in.size()) return;
  const size_t n = in.size() - shift;
  const uint64_t* __restrict x = in.data();
  uint64_t* __restrict o = out.data();
  for (size_t i = 0; i < n; ++i) o[i + shift] |= x[i];
  for (size_t i = 0; i < n; ++i) o[i] |= x[i + shift];
}

// out[i](r, c) = the sum of in[i] (rows × cols, row-major) over rows r ± h
// and columns c ± h within the grid, for the three grids at once: running
// sums down the columns (all columns at once), then along each row, in
// 64-bit integers (exact, and without a floating-point add's latency in
// the running sums). The column sums' rows are padded with h + 1 zeros
// before and h after, so the running sums along a row need no bounds.
void BoxSums(const std::array<const std::vector<int32_t>*, 3>& in, int rows, int cols, int h,
             std::array<std::vector<int64_t>, 3>& down,
             const std::array<std::vector<double>*, 3>& out) {
  const auto c = static_cast<size_t>(cols), half = static_cast<size_t>(h);
  const size_t stride = c + 2 * half + 1;
  for (size_t i = 0; i < 3; ++i) {
    const auto row = [&](int r) { return in[i]->data() + static_cast<size_t>(r) * c; };
    down[i].assign(static_cast<size_t>(rows) * stride, 0);
    out[i]->resize(static_cast<size_t>(rows) * c);
    int64_t* first = down[i].data() + half + 1;
    for (int r = 0; r < std::min(h, rows); ++r) {
      const int32_t* x = row(r);
      for (size_t k = 0; k < c; ++k) first[k] += x[k];
    }
    for (int r = 0; r < rows; ++r) {
      int64_t* d = down[i].data() + static_cast<size_t>(r) * stride + half + 1;
      if (r > 0) std::copy(d - stride, d - stride + c, d);
      if (r + h < rows) {
        const int32_t* x = row(r + h);
        for (size_t k = 0; k < c; ++k) d[k] += x[k];
      }
      if (r - h - 1 >= 0) {
        const int32_t* x = row(r - h - 1);
        for (size_t k = 0; k < c; ++k) d[k] -= x[k];
      }
    }
  }
  for (int r = 0; r < rows; ++r) {
    // p[j] is column j − h − 1; out(r, k) sums p[k + 1 .. k + 2h + 1].
    const size_t offset = static_cast<size_t>(r) * stride;
    const int64_t* p0 = down[0].data() + offset;
    const int64_t* p1 = down[1].data() + offset;
    const int64_t* p2 = down[2].data() + offset;
    double* o0 = out[0]->data() + static_cast<size_t>(r) * c;
    double* o1 = out[1]->data() + static_cast<size_t>(r) * c;
    double* o2 = out[2]->data() + static_cast<size_t>(r) * c;
    int64_t s0 = 0, s1 = 0, s2 = 0;
    for (size_t j = 1; j <= 2 * half; ++j) {
      s0 += p0[j];
      s1 += p1[j];
      s2 += p2[j];
    }
    for (size_t k = 0; k < c; ++k) {
      const size_t add = k + 2 * half + 1;
      s0 += p0[add] - p0[k];
      s1 += p1[add] - p1[k];
      s2 += p2[add] - p2[k];
      o0[k] = static_cast<double>(s0);
      o1[k] = static_cast<double>(s1);
      o2[k] = static_cast<double>(s2);
    }
  }
}

// The samples among 16 pixels (bit k of `samples`: pixel k is one) at or
// below their group's cap (pixels 0–7 `cap_a`, 8–15 `cap_b`): count, sum
// and sum of squares of each 8-pixel group, added to n, s1 and s2 [0] and
// [1]. SSE2: a masked sum of absolute differences and a multiply-add.
inline void AddGroupSums(const uint8_t* px, uint32_t samples, uint8_t cap_a, uint8_t cap_b,
                         int32_t* n, int32_t* s1, int32_t* s2) {
#if defined(__SSE2__)
  constexpr uint64_t kSpread = 0x0101010101010101ULL;
  const auto lanes = [](uint64_t high, uint64_t low) {
    return _mm_set_epi64x(static_cast<long long>(high), static_cast<long long>(low));
  };
  const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(px));
  const __m128i bit = lanes(0x8040201008040201ULL, 0x8040201008040201ULL);
  __m128i keep = lanes(((samples >> 8) & 0xFFu) * kSpread, (samples & 0xFFu) * kSpread);
  keep = _mm_cmpeq_epi8(_mm_and_si128(keep, bit), bit);
  const __m128i cap = lanes(cap_b * kSpread, cap_a * kSpread);
  keep = _mm_and_si128(keep, _mm_cmpeq_epi8(_mm_min_epu8(x, cap), x));
  const __m128i zero = _mm_setzero_si128();
  const __m128i y = _mm_and_si128(x, keep);
  const __m128i sum = _mm_sad_epu8(y, zero);
  const __m128i qa = _mm_madd_epi16(_mm_unpacklo_epi8(y, zero), _mm_unpacklo_epi8(y, zero));
  const __m128i qb = _mm_madd_epi16(_mm_unpackhi_epi8(y, zero), _mm_unpackhi_epi8(y, zero));
  __m128i q = _mm_add_epi32(_mm_unpacklo_epi32(qa, qb), _mm_unpackhi_epi32(qa, qb));
  q = _mm_add_epi32(q, _mm_srli_si128(q, 8));
  const __m128i count = _mm_sad_epu8(_mm_and_si128(keep, _mm_set1_epi8(1)), zero);
  n[0] += _mm_cvtsi128_si32(count);
  n[1] += _mm_extract_epi16(count, 4);
  s1[0] += _mm_cvtsi128_si32(sum);
  s1[1] += _mm_extract_epi16(sum, 4);
  s2[0] += _mm_cvtsi128_si32(q);
  s2[1] += _mm_cvtsi128_si32(_mm_srli_si128(q, 4));
#else
  for (int k = 0; k < 16; ++k) {
    const int value = px[k], g = k / 8;
    if (((samples >> k) & 1u) == 0 || value > (g == 0 ? cap_a : cap_b)) continue;
    ++n[g];
    s1[g] += value;
    s2[g] += value * value;
  }
#endif
}

// mean = s1 / n and sd = max(√(s2 / n − mean²), 1) per cell; both −1
// where n < min_n (no statistics). Branch-free, so vectorised (with
// -fno-math-errno: sqrt sets no errno).
PLANTSCALE_VECTOR_CLONES
void MeanAndSd(const double* __restrict n, const double* __restrict s1,
               const double* __restrict s2, size_t cells, double min_n, double* __restrict mean,
               double* __restrict sd) {
  for (size_t i = 0; i < cells; ++i) {
    const double count = std::max(n[i], 1.0);
    const double m = s1[i] / count;
    const double s = std::max(std::sqrt(std::max(s2[i] / count - m * m, 0.0)), 1.0);
    const bool valid = n[i] >= min_n;
    mean[i] = valid ? m : -1.0;
    sd[i] = valid ? s : -1.0;
  }
}

// Bit u of the result is set where bit u of `want` is (u < n ≤ 64) and
// in[u] reaches the threshold interpolated between the expanded cell rows
// a and b (wb/256 of b, wa = 256 − wb of a), unless that threshold is 255
// (no statistics). 16-bit arithmetic, as cell_grid.h's Interpolate; SSE2,
// 16 pixels a compare, for the 16-pixel chunks of a whole word that hold a
// wanted bit (the rest of in, a and b is not read).
uint64_t CandidateWord(const uint8_t* in, const uint8_t* a, const uint8_t* b,
                       [[maybe_unused]] uint16_t wa, uint16_t wb, int n, uint64_t want) {
  uint64_t bits = 0;
#if defined(__SSE2__)
  if (n == 64) {
    const __m128i zero = _mm_setzero_si128(), round = _mm_set1_epi16(128);
    const __m128i va = _mm_set1_epi16(static_cast<short>(wa));
    const __m128i vb = _mm_set1_epi16(static_cast<short>(wb));
    const __m128i none = _mm_set1_epi8(static_cast<char>(255));
    const auto half = [&](__m128i x, __m128i y) {
      return _mm_srli_epi16(
          _mm_add_epi16(_mm_add_epi16(_mm_mullo_epi16(x, va), _mm_mullo_epi16(y, vb)), round), 8);
    };
    for (int u = 0; u < 64; u += 16) {
      if (((want >> u) & 0xFFFFu) == 0) continue;
      const auto load = [&](const uint8_t* p) {
        return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + u));
      };
      const __m128i x = load(in), ta = load(a), tb = load(b);
      const __m128i t = _mm_packus_epi16(
          half(_mm_unpacklo_epi8(ta, zero), _mm_unpacklo_epi8(tb, zero)),
          half(_mm_unpackhi_epi8(ta, zero), _mm_unpackhi_epi8(tb, zero)));
      const __m128i reaches = _mm_cmpeq_epi8(_mm_max_epu8(x, t), x);
      const __m128i yes = _mm_andnot_si128(_mm_cmpeq_epi8(t, none), reaches);
      bits |= static_cast<uint64_t>(static_cast<uint32_t>(_mm_movemask_epi8(yes))) << u;
    }
    return bits & want;
  }
#endif
  for (uint64_t left = want & (n == 64 ? ~uint64_t{0} : (uint64_t{1} << n) - 1); left != 0;
       left &= left - 1) {
    const int u = std::countr_zero(left);
    const uint8_t t = Interpolate(a[u], b[u], wb);
    if (in[u] >= t && t != 255) bits |= uint64_t{1} << u;
  }
  return bits;
}

// bits dilated by `r` pixels along u (rows of `words` words; bits past
// `width` cleared): shifted copies ORed in with radii 1, 3, 7, ... up to r
// (r < 64), over the whole buffer as one bit string (vectorised), then each
// row's end words again without the carries across rows.
void DilateAlongU(std::vector<uint64_t>& bits, size_t words, int rows, int width, int r,
                  std::vector<uint64_t>& scratch) {
  const uint64_t last = width % 64 == 0 ? ~uint64_t{0} : (uint64_t{1} << (width % 64)) - 1;
  const size_t n = bits.size();
  for (int c = 0; c < r;) {
    const int s = std::min(c + 1, r - c);
    scratch.resize(n);
    const uint64_t* __restrict x = bits.data();
    uint64_t* __restrict o = scratch.data();
    for (size_t i = 1; i + 1 < n; ++i) {
      o[i] = x[i] | (x[i] << s) | (x[i - 1] >> (64 - s)) | (x[i] >> s) | (x[i + 1] << (64 - s));
    }
    for (int v = 0; v < rows; ++v) {
      const size_t first = static_cast<size_t>(v) * words, end = first + words - 1;
      const auto one = [&](size_t i) {
        uint64_t y = x[i] | (x[i] << s) | (x[i] >> s);
        if (i > first) y |= x[i - 1] >> (64 - s);
        if (i < end) y |= x[i + 1] << (64 - s);
        o[i] = y;
      };
      one(first);
      if (end != first) one(end);
      o[end] &= last;
    }
    bits.swap(scratch);
    c += s;
  }
}

// The same along v, radii 1, 3, 7, ... up to r.
void DilateAlongV(std::vector<uint64_t>& bits, size_t words, int r,
                  std::vector<uint64_t>& scratch) {
  for (int c = 0; c < r;) {
    const int s = std::min(c + 1, r - c);
    ShiftOrAlongV(bits, words, s, scratch);
    bits.swap(scratch);
    c += s;
  }
}

}  // namespace

SoilGrower::SoilGrower(const SoilGrowthOptions& options) : options_(Validated(options)) {}

void SoilGrower::ClearanceBits(int width, int height) {
  // The mask dilated by a (2c + 1)² square, on the sampled rows only (the
  // only ones the statistics read): dilated along u as the band is, then
  // the OR of the rows within c.
  const auto words = static_cast<size_t>((width + 63) / 64);
  const int c = options_.clearance_px;
  scratch_ = mask_bits_;
  DilateAlongU(scratch_, words, height, width, c, near_bits_);
  near_bits_.assign(scratch_.size(), 0);
  for (int v = 0; v < height; v += kRowStride) {
    uint64_t* out = near_bits_.data() + static_cast<size_t>(v) * words;
    for (int j = std::max(v - c, 0); j <= std::min(v + c, height - 1); ++j) {
      const uint64_t* in = scratch_.data() + static_cast<size_t>(j) * words;
      for (size_t w = 0; w < words; ++w) out[w] |= in[w];
    }
  }
}

void SoilGrower::SoilStatistics(bool capped) {
  const auto cells = static_cast<size_t>(cells_w_) * static_cast<size_t>(cells_h_);
  n_.assign(cells, 0);
  s1_.assign(cells, 0);
  s2_.assign(cells, 0);
  const int width = smooth_.cols, height = smooth_.rows, cell = options_.cell_px;
  const int shift = std::countr_zero(static_cast<unsigned>(cell / 8));  // 8-px groups to cells
  const auto words = static_cast<size_t>((width + 63) / 64);
  uint8_t tail[16] = {};
  // Every second pixel of every fourth row, 16 at a time.
  for (int v = 0; v < height; v += kRowStride) {
    const uint8_t* x = smooth_.ptr<uint8_t>(v);
    const uint64_t* near = near_bits_.data() + static_cast<size_t>(v) * words;
    const size_t row = static_cast<size_t>(v / cell) * static_cast<size_t>(cells_w_);
    int32_t* n = n_.data() + row;
    int32_t* s1 = s1_.data() + row;
    int32_t* s2 = s2_.data() + row;
    const uint8_t* cap = capped ? cap_.data() + row : nullptr;
    for (int u = 0; u < width; u += 16) {
      auto samples = static_cast<uint32_t>((~near[u / 64] >> (u % 64)) & 0x5555u);
      const uint8_t* px = x + u;
      if (width - u < 16) {
        samples &= (1u << (width - u)) - 1;
        std::copy(x + u, x + width, tail);
        px = tail;
      }
      if (samples == 0) continue;
      const int a = (u / 8) >> shift, b = std::min((u / 8 + 1) >> shift, cells_w_ - 1);
      int32_t gn[2] = {0, 0}, gs1[2] = {0, 0}, gs2[2] = {0, 0};
      AddGroupSums(px, samples, cap ? cap[a] : uint8_t{255}, cap ? cap[b] : uint8_t{255}, gn, gs1,
                   gs2);
      n[a] += gn[0];
      n[b] += gn[1];
      s1[a] += gs1[0];
      s1[b] += gs1[1];
      s2[a] += gs2[0];
      s2[b] += gs2[1];
    }
  }
  const int h = options_.window_cells / 2;
  BoxSums({&n_, &s1_, &s2_}, cells_h_, cells_w_, h, down_, {&box_n_, &box_s1_, &box_s2_});
  mean_.resize(cells);
  sd_.resize(cells);
  MeanAndSd(box_n_.data(), box_s1_.data(), box_s2_.data(), cells,
            static_cast<double>(options_.min_soil_samples), mean_.data(), sd_.data());
}

void SoilGrower::Band(int width, int height) {
  // The seeds dilated by a (2·reach_px + 1)² square, less the mask.
  const auto words = static_cast<size_t>((width + 63) / 64);
  band_ = seed_bits_;
  DilateAlongU(band_, words, height, width, options_.reach_px, scratch_);
  DilateAlongV(band_, words, options_.reach_px, scratch_);
  for (size_t i = 0; i < band_.size(); ++i) band_[i] &= ~mask_bits_[i];
}

void SoilGrower::Smooth(const cv::Mat& plant, bool everywhere) {
  const int width = plant.cols, height = plant.rows;
  const auto words = static_cast<size_t>((width + 63) / 64);
  smooth_.create(plant.size(), CV_8UC1);
  for (int v = 0; v < height; ++v) {
    uint8_t* out = smooth_.ptr<uint8_t>(v);
    const auto span = [&](int u0, int u1) { Gaussian3x3Span(plant, v, u0, u1, col_, out); };
    if (everywhere || v % kRowStride == 0) {
      span(0, width);
      continue;
    }
    // Whole words of the band: fewer, longer spans than its chunks.
    const uint64_t* band = band_.data() + static_cast<size_t>(v) * words;
    for (size_t w = 0; w < words;) {
      if (band[w] == 0) {
        ++w;
        continue;
      }
      const size_t w0 = w;
      while (w < words && band[w] != 0) ++w;
      span(static_cast<int>(64 * w0), std::min(static_cast<int>(64 * w), width));
    }
  }
}

void SoilGrower::Thresholds() {
  // Per cell: ceil(μ + z·σ), 255 where there are no statistics or it is at
  // least 255 (then no pixel is a candidate: CandidateWord).
  cell_threshold_.create(cells_h_, cells_w_, CV_8U);
  for (int r = 0; r < cells_h_; ++r) {
    const size_t row = static_cast<size_t>(r) * static_cast<size_t>(cells_w_);
    uint8_t* t = cell_threshold_.ptr<uint8_t>(r);
    for (int c = 0; c < cells_w_; ++c) {
      const double mean = mean_[row + static_cast<size_t>(c)];
      const double level = std::ceil(mean + options_.z * sd_[row + static_cast<size_t>(c)]);
      t[c] = mean < 0.0 || level >= 255.0 ? uint8_t{255} : static_cast<uint8_t>(level);
    }
  }
  expander_.Expand(cell_threshold_, options_.cell_px, smooth_.cols, expanded_);
}

void SoilGrower::CandidateBits(bool everywhere, std::vector<uint64_t>& bits) {
  const int width = smooth_.cols, height = smooth_.rows;
  const auto words = static_cast<size_t>((width + 63) / 64);
  bits.assign(mask_bits_.size(), 0);
  for (int v = 0; v < height; ++v) {
    int r0, r1, w;
    CellCoordinate(v, options_.cell_px, cells_h_, r0, r1, w);
    const uint8_t* a = expanded_.ptr<uint8_t>(r0);
    const uint8_t* b = expanded_.ptr<uint8_t>(r1);
    const uint8_t* x = smooth_.ptr<uint8_t>(v);
    const size_t row = static_cast<size_t>(v) * words;
    const auto wb = static_cast<uint16_t>(w), wa = static_cast<uint16_t>(256 - w);
    for (size_t k = 0; k < words; ++k) {
      const uint64_t want = everywhere ? ~mask_bits_[row + k] : band_[row + k];
      if (want == 0) continue;
      const int u0 = static_cast<int>(64 * k), n = std::min(64, width - u0);
      bits[row + k] = CandidateWord(x + u0, a + u0, b + u0, wa, wb, n, want);
    }
  }
}

cv::Mat SoilGrower::Candidates() {
  cv::Mat out(plant_.size(), CV_8UC1, cv::Scalar(0));
  if (expanded_.empty() || plant_.empty()) return out;
  Smooth(plant_, true);
  CandidateBits(true, all_bits_);
  const auto words = static_cast<size_t>((plant_.cols + 63) / 64);
  for (int v = 0; v < plant_.rows; ++v) {
    uint8_t* o = out.ptr<uint8_t>(v);
    detail::ForEachRun(all_bits_.data() + static_cast<size_t>(v) * words, plant_.cols,
                       [&](int u0, int u1) { std::fill(o + u0, o + u1, uint8_t{255}); });
  }
  return out;
}

void SoilGrower::GrowBits(int width, int height) {
  const auto words = static_cast<size_t>((width + 63) / 64);
  CandidateBits(false, candidate_bits_);
  // Geodesic growth: one 3×3 dilation a step, kept to the seeds and the
  // candidates.
  for (size_t i = 0; i < candidate_bits_.size(); ++i) candidate_bits_[i] |= seed_bits_[i];
  grown_bits_ = seed_bits_;
  for (int k = 0; k < options_.reach_px; ++k) {
    detail::StepAlongU<true>(grown_bits_, static_cast<int>(words), height, width, scratch_);
    ShiftOrAlongV(scratch_, words, 1, grown_bits_);
    for (size_t i = 0; i < grown_bits_.size(); ++i) grown_bits_[i] &= candidate_bits_[i];
  }
}

int SoilGrower::Grow(const cv::Mat& plant, cv::Mat& mask) {
  if (plant.type() != CV_8UC1 || mask.type() != CV_8UC1 || plant.size() != mask.size()) {
    throw DataError("soil growth needs a CV_8UC1 plant image and mask of one size (got " +
                    std::to_string(plant.cols) + "x" + std::to_string(plant.rows) + " type " +
                    std::to_string(plant.type()) + " and " + std::to_string(mask.cols) + "x" +
                    std::to_string(mask.rows) + " type " + std::to_string(mask.type()) + ")");
  }
  // Labelled first so that mask_runs() hold this frame's whatever follows.
  LabelBlobs(mask);
  plant_ = plant;
  expanded_.release();  // Candidates(): none judged yet
  if (mask.empty() || !options_.enabled()) return 0;
  if (!SeedBits(static_cast<size_t>((mask.cols + 63) / 64))) return 0;
  ModelSoilAndGrow(plant);
  return AddGrowth(mask);
}

void SoilGrower::LabelBlobs(const cv::Mat& mask) {
  const int width = mask.cols, height = mask.rows;
  const auto words = static_cast<size_t>((width + 63) / 64);
  mask_bits_.resize(words * static_cast<size_t>(height));
  for (int v = 0; v < height; ++v) {
    detail::RowBits(mask.ptr<uint8_t>(v), width, mask_bits_.data() + static_cast<size_t>(v) * words);
  }
  keep_.LabelMask(mask_bits_, width, height);  // 8-connected
}

bool SoilGrower::SeedBits(size_t words) {
  const std::vector<detail::RowRun>& runs = keep_.runs();
  const std::vector<int>& parent = keep_.parent();
  area_.assign(runs.size(), 0);
  for (size_t i = 0; i < runs.size(); ++i) {
    area_[static_cast<size_t>(parent[i])] += runs[i].u_end - runs[i].u_begin;
  }
  seed_bits_.assign(mask_bits_.size(), 0);
  bool seeds = false;
  for (size_t i = 0; i < runs.size(); ++i) {
    const auto root = static_cast<size_t>(parent[i]);
    if (area_[root] < options_.min_area_px) continue;
    detail::SetBits(seed_bits_.data() + static_cast<size_t>(runs[i].v) * words, runs[i].u_begin,
                    runs[i].u_end);
    seeds = true;
  }
  return seeds;
}

void SoilGrower::ModelSoilAndGrow(const cv::Mat& plant) {
  // The soil statistics need the smoothed image on the sampled rows, the
  // candidates only within reach of a seed (band_).
  const int width = plant.cols, height = plant.rows;
  Band(width, height);
  Smooth(plant, false);
  cells_w_ = (width + options_.cell_px - 1) / options_.cell_px;
  cells_h_ = (height + options_.cell_px - 1) / options_.cell_px;
  ClearanceBits(width, height);
  SoilStatistics(false);
  if (options_.trim_z > 0.0) {
    // Caps of the second pass: ⌊μ + trim_z·σ⌋ (255 keeps every sample).
    cap_.resize(mean_.size());
    for (size_t i = 0; i < mean_.size(); ++i) {
      const double top = mean_[i] < 0.0 ? 255.0 : std::min(mean_[i] + options_.trim_z * sd_[i], 255.0);
      cap_[i] = static_cast<uint8_t>(std::floor(top));
    }
    SoilStatistics(true);
  }
  Thresholds();
  GrowBits(width, height);
}

int SoilGrower::AddGrowth(cv::Mat& mask) {
  if (options_.join_min_area_px > 0) {
    // Growth may join blobs only where one of them is small.
    const std::vector<detail::RowRun>& runs = keep_.runs();
    const std::vector<int>& parent = keep_.parent();
    small_.assign(runs.size(), 0);
    for (size_t i = 0; i < runs.size(); ++i) {
      const auto root = static_cast<size_t>(parent[i]);
      small_[root] = area_[root] < options_.join_min_area_px ? 1 : 0;
    }
    for (size_t i = 0; i < grown_bits_.size(); ++i) grown_bits_[i] |= mask_bits_[i];
    return keep_.Add(mask_bits_, grown_bits_, nullptr, mask, &small_);
  }
  const auto words = static_cast<size_t>((mask.cols + 63) / 64);
  int added = 0;
  for (int v = 0; v < mask.rows; ++v) {
    const size_t row = static_cast<size_t>(v) * words;
    uint8_t* m = mask.ptr<uint8_t>(v);
    for (size_t w = 0; w < words; ++w) {
      uint64_t fresh = grown_bits_[row + w] & ~mask_bits_[row + w];
      while (fresh != 0) {
        m[64 * w + static_cast<size_t>(std::countr_zero(fresh))] = 255;
        fresh &= fresh - 1;
        ++added;
      }
    }
  }
  return added;
}

}  // namespace plantscale::vision
