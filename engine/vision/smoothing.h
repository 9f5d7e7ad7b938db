#pragma once
// Fast smoothing of the plant image: a Gaussian of σ pixels replaced by the
// tent (two passes of an n×n box) of the same variance, 2(n² − 1)/12 = σ²,
// where such an odd n exists: σ = 2 is two 5×5 boxes. On presets A–D the
// tent's AUC matches cv::GaussianBlur's to 0.0002 (σ = 2) at a fraction of
// its cost; every other σ falls back to cv::GaussianBlur.
//
// Integer arithmetic throughout: the horizontal tent of each row is exact
// in 16 bits, is scaled down by 2^s so that the vertical tent still fits 16
// bits, and the result is rounded back to bytes (within ±1 grey level of the
// exact tent). Borders reflect (BORDER_REFLECT_101, like cv::blur). Buffers
// are kept: frames after the first of a size allocate nothing.

#include <opencv2/core.hpp>
#include <vector>

namespace plantscale::vision {

// The odd box width n whose tent has standard deviation `sigma_px`, or 0
// when there is none in the range this smoother supports (n = 3, 5, 7).
int TentBoxForSigma(double sigma_px);

// Pixels [u0, u1) of row v of the 3×3 Gaussian of `grey` (CV_8UC1; kernel
// [1 2 1]/4 each way, borders replicated) into out[u0, u1): the same bytes
// as cv::GaussianBlur(grey, out, {3, 3}, 0, 0, cv::BORDER_REPLICATE), for a
// part of a row (soil_growth.h smooths only where it looks). `col` is a
// buffer, reused.
void Gaussian3x3Span(const cv::Mat& grey, int v, int u0, int u1, std::vector<uint16_t>& col,
                     uint8_t* out);

class Smoother {
 public:
  // σ in pixels (> 0).
  explicit Smoother(double sigma_px);

  // `out` (CV_8UC1, same size) is reused when it has the right size and type.
  void Apply(const cv::Mat& grey, cv::Mat& out);

  int box_px() const { return box_; }  // 0: cv::GaussianBlur

 private:
  template <int N>
  void Apply(const cv::Mat& grey, cv::Mat& out);

  double sigma_px_;
  int box_ = 0;
  std::vector<uint8_t> padded_;   // one row, reflected at both ends
  std::vector<uint16_t> row_;     // its horizontal box
  std::vector<uint16_t> tent_;    // the running vertical tent
  cv::Mat horizontal_;  // CV_16UC1: every row's scaled horizontal tent
  cv::Mat boxes_;       // CV_16UC1: ring of n + 1 vertical boxes of horizontal_
};

}  // namespace plantscale::vision
