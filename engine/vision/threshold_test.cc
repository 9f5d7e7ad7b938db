#include "engine/vision/threshold.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "engine/common/rng.h"
#include "engine/vision/colour_index.h"
#include "engine/vision/local_threshold.h"

namespace plantscale::vision {
namespace {

TEST(Threshold, FixedIsGreaterOrEqualAsEquation214) {
  cv::Mat grey = (cv::Mat_<uint8_t>(1, 4) << 99, 100, 101, 255);
  cv::Mat mask;
  FixedThreshold(grey, 100.0, mask);
  EXPECT_EQ(mask.at<uint8_t>(0, 0), 0);
  EXPECT_EQ(mask.at<uint8_t>(0, 1), 255);  // I == τ is plant
  EXPECT_EQ(mask.at<uint8_t>(0, 3), 255);
  FixedThreshold(grey, 100.5, mask);  // fractional τ: 100 < 100.5
  EXPECT_EQ(mask.at<uint8_t>(0, 1), 0);
  EXPECT_EQ(mask.at<uint8_t>(0, 2), 255);
}

TEST(Threshold, OtsuSplitsTwoModes) {
  cv::Mat grey(10, 100, CV_8UC1, cv::Scalar(60));
  grey.colRange(70, 100).setTo(180);
  cv::Mat mask;
  const double tau = OtsuThreshold(grey, mask);
  EXPECT_GT(tau, 60.0);
  EXPECT_LE(tau, 180.0);
  EXPECT_EQ(cv::countNonZero(mask), 300);
}

TEST(Threshold, AdaptiveMeansInterpolateThroughTheHalfCentres) {
  // Top half 40, bottom half 80: μ(v) passes 40 at v = h/4 and 80 at 3h/4.
  cv::Mat grey(100, 10, CV_8UC1, cv::Scalar(40));
  grey.rowRange(50, 100).setTo(80);
  const InterpolatedMean m = ComputeInterpolatedMean(grey);
  EXPECT_NEAR(m.top, 40.0, 1e-12);
  EXPECT_NEAR(m.bottom, 80.0, 1e-12);
  EXPECT_NEAR(m.At(24) + m.At(25), 80.0, 1e-9);     // centres 24.5, 25.5 straddle 25
  EXPECT_NEAR(m.At(74) + m.At(75), 160.0, 1e-9);
  EXPECT_NEAR(m.At(0), 40.0 - 40.0 * 24.5 / 50.0, 1e-9);  // extrapolated above
}

TEST(Threshold, AdaptiveMaskMatchesEquation215PixelByPixel) {
  cv::Mat grey(64, 48, CV_8UC1);
  cv::randu(grey, 0, 256);
  const double alpha = 1.37;
  cv::Mat mask;
  AdaptiveInterpolatingThreshold(grey, alpha, mask);
  const InterpolatedMean m = ComputeInterpolatedMean(grey);
  for (int v = 0; v < grey.rows; ++v) {
    for (int u = 0; u < grey.cols; ++u) {
      const bool plant = grey.at<uint8_t>(v, u) >= alpha * m.At(v);
      ASSERT_EQ(mask.at<uint8_t>(v, u), plant ? 255 : 0) << u << "," << v;
    }
  }
}

// A hard shadow over the bottom quarter: soil 60 / plants 150 in sun, soil
// 22 / plants 55 in shadow. The local soil level finds every plant and no soil
// on both sides; one interpolated gradient cannot.
TEST(LocalThreshold, ShadowedAndSunlitPlantsBothFound) {
  cv::Mat grey(240, 320, CV_8UC1, cv::Scalar(60));
  grey.rowRange(180, 240).setTo(22);
  cv::Mat truth(grey.size(), CV_8UC1, cv::Scalar(0));
  for (int k = 0; k < 8; ++k) {
    const cv::Rect sun(20 + 36 * k, 40, 12, 12), shade(20 + 36 * k, 205, 12, 12);
    grey(sun).setTo(150);
    grey(shade).setTo(55);
    truth(sun).setTo(255);
    truth(shade).setTo(255);
  }
  LocalThreshold local;
  cv::Mat mask;
  local.Apply(grey, mask);
  cv::Mat wrong = mask != truth;
  wrong.rowRange(172, 188).setTo(0);  // one cell either side of the edge
  EXPECT_EQ(cv::countNonZero(wrong), 0);
  cv::Mat adaptive;
  AdaptiveInterpolatingThreshold(grey, 1.6, adaptive);
  // Hague's threshold misses the shadowed plants (8 × 144 pixels).
  EXPECT_GE(cv::countNonZero(adaptive != truth), 8 * 144);
}

// The soil level is the grey-level opening of the block means; our own
// block means and separable min/max give OpenCV's INTER_AREA and
// morphologyEx (square element, replicated borders) cell for cell, also on
// grids narrower than the element and
// a grid whose size is not a multiple of the cell (INTER_AREA itself).
TEST(LocalThreshold, CellLevelsEqualOpenCvsAreaResizeAndOpening) {
  cv::RNG rng(5);
  for (const cv::Size size : {cv::Size(640, 480), cv::Size(100, 60), cv::Size(203, 157)}) {
    cv::Mat grey(size, CV_8UC1);
    rng.fill(grey, cv::RNG::NORMAL, 70, 25);
    for (int k = 0; k < 30; ++k) {
      cv::circle(grey, {rng.uniform(0, size.width), rng.uniform(0, size.height)},
                 rng.uniform(2, 20), rng.uniform(120, 255), cv::FILLED);
    }
    LocalThresholdOptions o;
    for (const auto& [cell, opening] : {std::pair{8, 5}, std::pair{4, 5}, std::pair{8, 21}}) {
      o.cell_px = cell;
      o.opening_cells = opening;
      LocalThreshold local(o);
      cv::Mat mask;
      local.Apply(grey, mask);
      cv::Mat cells, opened, expected;
      cv::resize(grey, cells, cv::Size(size.width / cell, size.height / cell), 0.0, 0.0,
                 cv::INTER_AREA);
      cv::morphologyEx(cells, opened, cv::MORPH_OPEN,
                       cv::getStructuringElement(cv::MORPH_RECT, cv::Size(opening, opening)),
                       cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
      cv::max(opened, o.min_level, opened);
      opened.convertTo(expected, CV_8U, o.gain);
      ASSERT_EQ(local.cell_thresholds().size(), expected.size());
      EXPECT_EQ(cv::norm(local.cell_thresholds(), expected, cv::NORM_INF), 0.0)
          << size << ", cell " << cell << ", opening " << opening;
      // The mask: α·B interpolated between cell centres (in 1/256ths, along
      // u first, then v), compared pixel by pixel.
      const auto at = [&](int i, int n, int& c0, int& c1) {
        const double c = std::clamp((i + 0.5) / cell - 0.5, 0.0, n - 1.0);
        c0 = static_cast<int>(c);
        c1 = std::min(c0 + 1, n - 1);
        return static_cast<int>((c - c0) * 256.0 + 0.5);
      };
      const cv::Mat& t = expected;
      int wrong = 0;
      for (int v = 0; v < size.height; ++v) {
        int r0, r1;
        const int wv = at(v, t.rows, r0, r1);
        for (int u = 0; u < size.width; ++u) {
          int c0, c1;
          const int wu = at(u, t.cols, c0, c1);
          const auto row = [&](int r) {
            return (t.at<uint8_t>(r, c0) * (256 - wu) + t.at<uint8_t>(r, c1) * wu + 128) >> 8;
          };
          const int threshold = (row(r0) * (256 - wv) + row(r1) * wv + 128) >> 8;
          wrong += (grey.at<uint8_t>(v, u) >= threshold) != (mask.at<uint8_t>(v, u) == 255);
        }
      }
      EXPECT_EQ(wrong, 0) << size << ", cell " << cell;
    }
  }
}

// ApplyAtGain over the last Apply's soil level is the mask a threshold of
// that gain would give.
TEST(LocalThreshold, ApplyAtGainEqualsAThresholdOfThatGain) {
  Rng rng(5);
  cv::Mat grey(96, 128, CV_8UC1);
  for (int v = 0; v < grey.rows; ++v) {
    for (int u = 0; u < grey.cols; ++u) {
      grey.at<uint8_t>(v, u) = static_cast<uint8_t>(40 + 30 * ((u / 20 + v / 16) % 2) +
                                                    120 * rng.Uniform() * ((u * v) % 7 == 0));
    }
  }
  LocalThresholdOptions high;
  high.gain = 2.3;
  LocalThreshold at_high(high);
  cv::Mat mask_high, mask_low_again;
  at_high.Apply(grey, mask_high);
  const cv::Mat cells = at_high.cell_thresholds().clone();
  at_high.ApplyAtGain(grey, 1.6, mask_low_again);
  LocalThresholdOptions low = high;
  low.gain = 1.6;
  LocalThreshold at_low(low);
  cv::Mat mask_low;
  at_low.Apply(grey, mask_low);
  EXPECT_EQ(cv::countNonZero(mask_low != mask_low_again), 0);
  EXPECT_GT(cv::countNonZero(mask_low), cv::countNonZero(mask_high));
  EXPECT_EQ(cv::countNonZero(cells != at_high.cell_thresholds()), 0);  // the Apply's stay
}

TEST(ColourIndex, GreenIsBrightSoilIsDarkGreyIsNeutral) {
  // BGR: green leaf, brown soil, grey.
  cv::Mat bgr(1, 3, CV_8UC3);
  bgr.at<cv::Vec3b>(0, 0) = {40, 150, 60};
  bgr.at<cv::Vec3b>(0, 1) = {60, 90, 120};
  bgr.at<cv::Vec3b>(0, 2) = {100, 100, 100};
  for (ColourIndex index : {ColourIndex::kExG, ColourIndex::kExGR, ColourIndex::kCIVE}) {
    cv::Mat out;
    ComputeColourIndex(bgr, index, out);
    EXPECT_GT(out.at<uint8_t>(0, 0), out.at<uint8_t>(0, 1) + 20) << Name(index);
  }
  cv::Mat exg;
  ComputeColourIndex(bgr, ColourIndex::kExG, exg);
  // Leaf: r = .24, g = .6, b = .16 → ExG = 0.8 → 127.5 + 102 = 229.5.
  EXPECT_NEAR(exg.at<uint8_t>(0, 0), 229.5, 1.0);
  EXPECT_NEAR(exg.at<uint8_t>(0, 2), 127.5, 0.6);  // grey: ExG = 0
  EXPECT_EQ(ParseColourIndex("exgr"), ColourIndex::kExGR);
  EXPECT_FALSE(ParseColourIndex("ndvi").has_value());
}

// Every pixel of a random image (including black ones) against the
// formulas of colour_index.h in double precision.
TEST(ColourIndex, EveryPixelFollowsItsFormula) {
  cv::Mat bgr(37, 203, CV_8UC3);
  cv::RNG(9).fill(bgr, cv::RNG::UNIFORM, 0, 256);
  bgr(cv::Rect(0, 0, 5, 3)).setTo(cv::Scalar(0, 0, 0));
  for (ColourIndex index : {ColourIndex::kExG, ColourIndex::kExGR, ColourIndex::kCIVE}) {
    cv::Mat out;
    ComputeColourIndex(bgr, index, out);
    int wrong = 0;
    for (int v = 0; v < bgr.rows; ++v) {
      for (int u = 0; u < bgr.cols; ++u) {
        const cv::Vec3b p = bgr.at<cv::Vec3b>(v, u);
        const double b = p[0], g = p[1], r = p[2], sum = r + g + b;
        double expected = 127.0;
        if (index == ColourIndex::kCIVE) {
          expected = 127.5 - (0.441 * r - 0.811 * g + 0.385 * b + 18.78745);
        } else if (sum > 0.0) {
          const double exg = (2.0 * g - r - b) / sum, exr = (1.4 * r - g) / sum;
          expected = index == ColourIndex::kExG ? 127.5 + 127.5 * exg : 127.5 + 85.0 * (exg - exr);
        }
        expected = std::clamp(expected, 0.0, 255.0);
        wrong += std::abs(out.at<uint8_t>(v, u) - expected) > 0.5 + 1e-4;
      }
    }
    EXPECT_EQ(wrong, 0) << Name(index);
  }
}

}  // namespace
}  // namespace plantscale::vision
