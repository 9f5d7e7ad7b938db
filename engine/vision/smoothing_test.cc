#include "engine/vision/smoothing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "engine/geometry/test_cameras.h"
#include "engine/sim/simulator.h"

namespace plantscale::vision {
namespace {

TEST(Smoothing, TentBoxOnlyWhereTheVarianceMatches) {
  EXPECT_EQ(TentBoxForSigma(2.0), 5);  // 2(25 − 1)/12 = 4
  EXPECT_EQ(TentBoxForSigma(std::sqrt(8.0 / 6.0)), 3);
  EXPECT_EQ(TentBoxForSigma(std::sqrt(8.0)), 7);
  EXPECT_EQ(TentBoxForSigma(1.0), 0);
  EXPECT_EQ(TentBoxForSigma(2.01), 0);
}

// The tent is two n×n box filters; the reference runs them in floating point
// (cv::blur, reflected borders) and rounds once. Sizes include odd ones and
// images narrower than the kernel's reach.
TEST(Smoothing, TentEqualsTwoBoxFiltersWithinOneGreyLevel) {
  cv::RNG rng(11);
  for (const double sigma : {std::sqrt(8.0 / 6.0), 2.0, std::sqrt(8.0)}) {
    for (const cv::Size size : {cv::Size(640, 480), cv::Size(37, 23), cv::Size(5, 4)}) {
      cv::Mat grey(size, CV_8UC1);
      rng.fill(grey, cv::RNG::UNIFORM, 0, 256);
      grey.setTo(255, grey > 200);  // saturated patches: the 16-bit sums' worst case
      Smoother smoother(sigma);
      const int n = smoother.box_px();
      ASSERT_GT(n, 0);
      cv::Mat out, f, ref;
      smoother.Apply(grey, out);
      grey.convertTo(f, CV_32F);
      cv::blur(f, f, cv::Size(n, n));
      cv::blur(f, f, cv::Size(n, n));
      f.convertTo(ref, CV_8U);
      EXPECT_LE(cv::norm(out, ref, cv::NORM_INF), 1.0) << "n = " << n << ", " << size;
    }
  }
  cv::Mat white(48, 64, CV_8UC1, cv::Scalar(255)), out;
  Smoother(2.0).Apply(white, out);
  EXPECT_EQ(cv::countNonZero(out != 255), 0);  // no overflow, no loss at the top
}

// On a simulated NIR frame the σ = 2 tent is close to the σ = 2 Gaussian it
// replaces; σ without a tent is cv::GaussianBlur itself.
TEST(Smoothing, CloseToTheGaussianOfTheSameSigma) {
  sim::SimulatorOptions o;
  o.camera = geometry::testing::ThesisCamera();
  o.field.crop_radius_m = 0.14;
  o.render.leaf_shadow_fraction = 0.2;
  o.seed = 4;
  sim::Simulator simulator(o);
  sim::SimFrame frame;
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(simulator.Next(frame));
  const cv::Mat& grey = frame.rendered.image;
  cv::Mat tent, gauss;
  Smoother(2.0).Apply(grey, tent);
  cv::GaussianBlur(grey, gauss, cv::Size(0, 0), 2.0);
  cv::Mat diff;
  cv::absdiff(tent, gauss, diff);
  EXPECT_LT(cv::mean(diff)[0], 0.5);
  EXPECT_LE(cv::norm(diff, cv::NORM_INF), 12.0);
  Smoother other(1.0);
  EXPECT_EQ(other.box_px(), 0);
  other.Apply(grey, tent);
  cv::GaussianBlur(grey, gauss, cv::Size(0, 0), 1.0);
  EXPECT_EQ(cv::norm(tent, gauss, cv::NORM_INF), 0.0);
}

TEST(Smoothing, Gaussian3x3SpansAreOpenCvsBytes) {
  // Odd sizes, so spans end off any vector width; every span touching an
  // edge replicates it as BORDER_REPLICATE does.
  cv::Mat grey(37, 131, CV_8UC1);
  cv::randu(grey, 0, 256);
  cv::Mat expected;
  cv::GaussianBlur(grey, expected, cv::Size(3, 3), 0.0, 0.0, cv::BORDER_REPLICATE);
  cv::Mat out(grey.size(), CV_8UC1, cv::Scalar(0));
  std::vector<uint16_t> col;
  for (int v = 0; v < grey.rows; ++v) {
    // The whole row on even rows; three spans (the ends and a middle) on odd.
    const std::vector<std::pair<int, int>> spans =
        v % 2 == 0 ? std::vector<std::pair<int, int>>{{0, 131}}
                   : std::vector<std::pair<int, int>>{{0, 1}, {1, 64}, {64, 131}};
    for (const auto& [u0, u1] : spans) Gaussian3x3Span(grey, v, u0, u1, col, out.ptr<uint8_t>(v));
  }
  EXPECT_EQ(cv::countNonZero(out != expected), 0);
  // A span leaves the rest of its row alone.
  cv::Mat part(grey.size(), CV_8UC1, cv::Scalar(7));
  Gaussian3x3Span(grey, 5, 40, 50, col, part.ptr<uint8_t>(5));
  EXPECT_EQ(cv::countNonZero(part.row(5) != 7), 10 - cv::countNonZero(expected.row(5).colRange(40, 50) == 7));
  EXPECT_THROW(Gaussian3x3Span(grey, 5, 50, 40, col, part.ptr<uint8_t>(5)), std::exception);
}

TEST(Smoothing, BuffersAreReusedAcrossFrames) {
  cv::Mat grey(48, 64, CV_8UC1, cv::Scalar(30)), out;
  Smoother smoother(2.0);
  smoother.Apply(grey, out);
  const uint8_t* data = out.data;
  grey(cv::Rect(10, 10, 8, 8)).setTo(200);
  smoother.Apply(grey, out);
  EXPECT_EQ(out.data, data);
  // (14, 14) sees the 8×8 patch with all of the 9-wide tent but one edge
  // tap: 30 + 170 · (24/25)² = 186.7.
  EXPECT_NEAR(out.at<uint8_t>(14, 14), 186.7, 1.0);
}

}  // namespace
}  // namespace plantscale::vision
