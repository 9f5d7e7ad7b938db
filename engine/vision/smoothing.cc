#include "engine/vision/smoothing.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"
#include "engine/common/vectorise.h"

namespace plantscale::vision {
namespace {

int Reflect(int i, int n) { return cv::borderInterpolate(i, n, cv::BORDER_REFLECT_101); }

// Fixed-point constants of the N-wide tent. The horizontal tent (≤ 255·N²)
// is shifted right by `shift` so that the vertical one (N² times that) fits
// 16 bits; the byte is tent · 2^shift / N⁴ = ((tent · scale) >> 16) >> k,
// with the largest k whose multiplier fits 16 bits.
template <int N>
struct Tent {
  static constexpr int kSquare = N * N;
  static constexpr int Shift() {
    int s = 0;
    while (kSquare * ((255 * kSquare + (s > 0 ? 1 << (s - 1) : 0)) >> s) > 65535) ++s;
    return s;
  }
  static constexpr int kShift = Shift();
  static constexpr uint64_t kFourth = static_cast<uint64_t>(kSquare) * kSquare;
  static constexpr uint64_t Multiplier(int k) {
    return ((uint64_t{1} << (16 + k + kShift)) + kFourth / 2) / kFourth;
  }
  static constexpr int ScaleShift() {
    int k = 1;
    while (Multiplier(k + 1) < 65536) ++k;
    return k;
  }
  static constexpr int kScaleShift = ScaleShift();
  static constexpr auto kScale = static_cast<uint16_t>(Multiplier(kScaleShift));
  static_assert(kScaleShift >= 1 && Multiplier(kScaleShift) < 65536);

  static uint8_t Byte(uint16_t tent) {
    const auto hi = static_cast<uint16_t>((static_cast<uint32_t>(tent) * kScale) >> 16);
    return static_cast<uint8_t>(static_cast<uint16_t>(hi + (1 << (kScaleShift - 1))) >> kScaleShift);
  }
};

// The N-wide tent along a row already padded by N − 1 reflected pixels at
// each end, exact in 16 bits, then scaled by 2^-shift with rounding. `box`
// holds width + N − 1 entries.
template <int N>
PLANTSCALE_VECTOR_CLONES void TentRow(const uint8_t* __restrict padded, int width,
                                      uint16_t* __restrict box, uint16_t* __restrict out) {
  const int count = width + N - 1;
  for (int u = 0; u < count; ++u) {
    uint16_t sum = padded[u];
    for (int k = 1; k < N; ++k) sum = static_cast<uint16_t>(sum + padded[u + k]);
    box[u] = sum;
  }
  constexpr int kShift = Tent<N>::kShift;
  constexpr auto kHalf = static_cast<uint16_t>(kShift > 0 ? 1 << (kShift - 1) : 0);
  for (int u = 0; u < width; ++u) {
    uint16_t sum = box[u];
    for (int k = 1; k < N; ++k) sum = static_cast<uint16_t>(sum + box[u + k]);
    out[u] = static_cast<uint16_t>(static_cast<uint16_t>(sum + kHalf) >> kShift);
  }
}

// One step of the two running vertical sums, then the byte:
//   box_new = box_prev + add − sub,  tent += box_new − box_old.
// 16-bit arithmetic wraps, but every sum it stands for fits.
template <int N>
PLANTSCALE_VECTOR_CLONES void VerticalStep(
    const uint16_t* __restrict box_prev, const uint16_t* __restrict add,
    const uint16_t* __restrict sub, const uint16_t* __restrict box_old,
    uint16_t* __restrict box_new, uint16_t* __restrict tent, int width, uint8_t* __restrict out) {
  for (int u = 0; u < width; ++u) {
    const auto b = static_cast<uint16_t>(box_prev[u] + add[u] - sub[u]);
    box_new[u] = b;
    const auto t = static_cast<uint16_t>(tent[u] + b - box_old[u]);
    tent[u] = t;
    out[u] = Tent<N>::Byte(t);
  }
}

void AddRow(const uint16_t* row, int width, uint16_t* sum) {
  for (int u = 0; u < width; ++u) sum[u] = static_cast<uint16_t>(sum[u] + row[u]);
}

// col[i] = a[i] + 2·b[i] + c[i]: the vertical taps of the 3×3 Gaussian.
PLANTSCALE_VECTOR_CLONES
void VerticalTaps(const uint8_t* __restrict a, const uint8_t* __restrict b,
                  const uint8_t* __restrict c, int n, uint16_t* __restrict col) {
  for (int i = 0; i < n; ++i) col[i] = static_cast<uint16_t>(a[i] + 2 * b[i] + c[i]);
}

// out[i] = (col[i] + 2·col[i + 1] + col[i + 2] + 8) / 16: the horizontal
// taps, rounded as cv::GaussianBlur's fixed-point 3×3 kernel rounds.
PLANTSCALE_VECTOR_CLONES
void HorizontalTaps(const uint16_t* __restrict col, int n, uint8_t* __restrict out) {
  for (int i = 0; i < n; ++i) {
    out[i] = static_cast<uint8_t>(
        static_cast<uint16_t>(col[i] + 2 * col[i + 1] + col[i + 2] + 8) >> 4);
  }
}

}  // namespace

void Gaussian3x3Span(const cv::Mat& grey, int v, int u0, int u1, std::vector<uint16_t>& col,
                     uint8_t* out) {
  const int width = grey.cols, height = grey.rows;
  PLANTSCALE_CHECK(grey.type() == CV_8UC1 && v >= 0 && v < height && 0 <= u0 && u0 < u1 &&
                       u1 <= width,
                   "Gaussian3x3Span needs CV_8UC1 and a span inside the image");
  const uint8_t* above = grey.ptr<uint8_t>(std::max(v - 1, 0));
  const uint8_t* row = grey.ptr<uint8_t>(v);
  const uint8_t* below = grey.ptr<uint8_t>(std::min(v + 1, height - 1));
  // col[k] holds the vertical taps of pixel u0 − 1 + k, the end pixels
  // replicated.
  col.resize(static_cast<size_t>(u1 - u0) + 2);
  const int lo = std::max(u0 - 1, 0), hi = std::min(u1 + 1, width);
  VerticalTaps(above + lo, row + lo, below + lo, hi - lo, col.data() + (lo - u0 + 1));
  if (u0 == 0) col[0] = col[1];
  if (u1 == width) col[static_cast<size_t>(u1 - u0 + 1)] = col[static_cast<size_t>(u1 - u0)];
  HorizontalTaps(col.data(), u1 - u0, out + u0);
}

int TentBoxForSigma(double sigma_px) {
  for (int n = 3; n <= 7; n += 2) {
    if (std::abs(std::sqrt((n * n - 1) / 6.0) - sigma_px) < 1e-9) return n;
  }
  return 0;
}

Smoother::Smoother(double sigma_px) : sigma_px_(sigma_px), box_(TentBoxForSigma(sigma_px)) {
  PLANTSCALE_CHECK(sigma_px > 0.0, "smoothing sigma must be positive");
}

void Smoother::Apply(const cv::Mat& grey, cv::Mat& out) {
  PLANTSCALE_CHECK(grey.type() == CV_8UC1 && !grey.empty(), "smoothing needs CV_8UC1");
  switch (box_) {
    case 3: return Apply<3>(grey, out);
    case 5: return Apply<5>(grey, out);
    case 7: return Apply<7>(grey, out);
  }
  cv::GaussianBlur(grey, out, cv::Size(0, 0), sigma_px_);
}

template <int N>
void Smoother::Apply(const cv::Mat& grey, cv::Mat& out) {
  const int w = grey.cols, h = grey.rows, r = N / 2, pad = N - 1;
  const auto width = static_cast<size_t>(w);
  padded_.resize(width + 2 * static_cast<size_t>(pad));
  row_.resize(width + static_cast<size_t>(N));
  tent_.resize(width);
  horizontal_.create(h, w, CV_16UC1);
  boxes_.create(N + 1, w, CV_16UC1);
  out.create(h, w, CV_8UC1);
  for (int v = 0; v < h; ++v) {
    const auto* row = grey.ptr<uint8_t>(v);
    for (int i = 0; i < pad; ++i) {
      padded_[static_cast<size_t>(i)] = row[Reflect(i - pad, w)];
      padded_[static_cast<size_t>(pad + w + i)] = row[Reflect(w + i, w)];
    }
    std::memcpy(padded_.data() + pad, row, width);
    TentRow<N>(padded_.data(), w, row_.data(), horizontal_.ptr<uint16_t>(v));
  }
  // Running vertical sums over the reflected row sequence: box(j) is the
  // sum of rows j − r..j + r, tent(v) that of boxes v − r..v + r. A ring of
  // N + 1 boxes holds box(v − r − 1)..box(v + r).
  const auto q = [&](int i) { return horizontal_.ptr<uint16_t>(Reflect(i, h)); };
  const auto box = [&](int j) { return boxes_.ptr<uint16_t>((j + 2 * r + 2 * (N + 1)) % (N + 1)); };
  std::fill(box(-r), box(-r) + w, uint16_t{0});
  for (int i = -2 * r; i <= 0; ++i) AddRow(q(i), w, box(-r));
  std::fill(tent_.begin(), tent_.end(), uint16_t{0});
  AddRow(box(-r), w, tent_.data());
  for (int j = -r + 1; j <= r; ++j) {
    uint16_t* b = box(j);
    std::memcpy(b, box(j - 1), width * sizeof(uint16_t));
    AddRow(q(j + r), w, b);
    const uint16_t* sub = q(j - r - 1);
    for (int u = 0; u < w; ++u) b[u] = static_cast<uint16_t>(b[u] - sub[u]);
    AddRow(b, w, tent_.data());
  }
  auto* first = out.ptr<uint8_t>(0);
  for (int u = 0; u < w; ++u) first[u] = Tent<N>::Byte(tent_[static_cast<size_t>(u)]);
  for (int v = 1; v < h; ++v) {
    VerticalStep<N>(box(v + r - 1), q(v + 2 * r), q(v - 1), box(v - r - 1), box(v + r),
                    tent_.data(), w, out.ptr<uint8_t>(v));
  }
}

}  // namespace plantscale::vision
