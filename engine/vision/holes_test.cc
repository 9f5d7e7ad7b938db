#include "engine/vision/holes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "engine/common/rng.h"
#include "engine/vision/segmenter.h"

namespace plantscale::vision {
namespace {

TEST(Holes, SoilEnclosedByPlantIsFilledAndNothingElse) {
  cv::Mat mask(40, 50, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(10, 10, 12, 10)).setTo(255);
  mask(cv::Rect(13, 13, 5, 4)).setTo(0);  // a 20-pixel hole
  const cv::Mat before = mask.clone();
  HoleFiller filler;
  EXPECT_EQ(filler.Fill(mask, 1000), 20);
  EXPECT_EQ(cv::countNonZero(mask), cv::countNonZero(before) + 20);
  EXPECT_TRUE(cv::countNonZero(mask(cv::Rect(10, 10, 12, 10)) == 0) == 0);
  // Soil outside the plant stays soil.
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(30, 0, 20, 40))), 0);
}

TEST(Holes, ABayOpenToTheSoilOrTheImageBorderIsNoHole) {
  cv::Mat mask(30, 30, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(5, 5, 10, 10)).setTo(255);
  mask(cv::Rect(8, 8, 4, 7)).setTo(0);  // a C shape: the gap reaches row 14, the bottom edge
  // Plant enclosing soil against the image's left border: that soil reaches
  // the border, so it may be soil beyond the frame.
  mask(cv::Rect(0, 20, 6, 6)).setTo(255);
  mask(cv::Rect(0, 22, 3, 2)).setTo(0);
  const cv::Mat before = mask.clone();
  HoleFiller filler;
  EXPECT_EQ(filler.Fill(mask, 1000), 0);
  EXPECT_EQ(cv::countNonZero(mask != before), 0);
}

TEST(Holes, SoilTouchingTheOutsideOnlyAtACornerIsAHole) {
  // An 8-connected diamond ring of single pixels: its inside meets the
  // outside only diagonally, and soil is 4-connected (the blob is one
  // 8-connected piece around it).
  cv::Mat mask(11, 11, CV_8UC1, cv::Scalar(0));
  for (int k = 0; k <= 3; ++k) {
    mask.at<uint8_t>(2 + k, 5 - k) = 255;
    mask.at<uint8_t>(2 + k, 5 + k) = 255;
    mask.at<uint8_t>(8 - k, 5 - k) = 255;
    mask.at<uint8_t>(8 - k, 5 + k) = 255;
  }
  HoleFiller filler;
  // Inside the diamond: rows 3..7 hold 1, 3, 5, 3, 1 pixels.
  EXPECT_EQ(filler.Fill(mask, 1000), 13);
  EXPECT_EQ(mask.at<uint8_t>(5, 5), 255);
}

TEST(Holes, HolesLargerThanTheLimitStay) {
  cv::Mat mask(40, 40, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(2, 2, 30, 30)).setTo(255);
  mask(cv::Rect(5, 5, 10, 10)).setTo(0);   // 100 pixels
  mask(cv::Rect(20, 20, 3, 3)).setTo(0);   // 9 pixels
  HoleFiller filler;
  EXPECT_EQ(filler.Fill(mask, 99), 9);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(5, 5, 10, 10))), 0);
  EXPECT_EQ(filler.Fill(mask, 100), 100);
  EXPECT_EQ(filler.Fill(mask, 0), 0);
}

// Against a reference: 4-connected soil components (OpenCV) that touch no
// border and are within the limit, on random masks of every density and
// widths that are and are not multiples of 64.
TEST(Holes, MatchesConnectedComponentsOfTheSoilOnRandomMasks) {
  Rng rng(7);
  HoleFiller filler;
  for (int trial = 0; trial < 60; ++trial) {
    const int w = 20 + trial * 7 % 150, h = 10 + trial * 5 % 60;
    const double density = 0.3 + 0.4 * (trial % 5) / 4.0;
    cv::Mat mask(h, w, CV_8UC1);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) mask.at<uint8_t>(v, u) = rng.Uniform() < density ? 255 : 0;
    }
    const int limit = trial % 3 == 0 ? 3 : 100000;
    cv::Mat soil = mask == 0, labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(soil, labels, stats, centroids, 4, CV_32S);
    cv::Mat expected = mask.clone();
    int expected_filled = 0;
    for (int k = 1; k < n; ++k) {
      const int x = stats.at<int>(k, cv::CC_STAT_LEFT), y = stats.at<int>(k, cv::CC_STAT_TOP);
      const int bw = stats.at<int>(k, cv::CC_STAT_WIDTH), bh = stats.at<int>(k, cv::CC_STAT_HEIGHT);
      const int area = stats.at<int>(k, cv::CC_STAT_AREA);
      if (x == 0 || y == 0 || x + bw == w || y + bh == h || area > limit) continue;
      expected.setTo(255, labels == k);
      expected_filled += area;
    }
    EXPECT_EQ(filler.Fill(mask, limit), expected_filled) << "trial " << trial;
    EXPECT_EQ(cv::countNonZero(mask != expected), 0) << "trial " << trial;
  }
}

TEST(Holes, SegmenterFillsAShadedPatchInsideAPlantButNotTheThesisBaseline) {
  // A bright plant on dark soil with a shaded patch in the middle, darker
  // than the plant threshold: 113 pixels, under 0.5 % of the 240×320 image
  // (384).
  cv::Mat image(240, 320, CV_8UC1, cv::Scalar(40));
  cv::circle(image, {80, 60}, 25, cv::Scalar(200), cv::FILLED);
  cv::circle(image, {80, 60}, 6, cv::Scalar(60), cv::FILLED);
  SegmenterOptions ours;
  ours.smoothing_px = 0.0;
  ours.soil_growth.z = 0.0;  // below: the hole filling alone
  Segmenter segmenter(ours);
  const Segmentation& seg = segmenter.Process(image);
  ASSERT_EQ(seg.blobs.size(), 1u);
  EXPECT_EQ(seg.mask.at<uint8_t>(60, 80), 255);
  EXPECT_EQ(seg.blobs[0].area_px, cv::countNonZero(image > 100) + 113);  // the disc of r = 6
  SegmenterOptions thesis = ThesisSegmenterOptions();
  thesis.smoothing_px = 0.0;
  Segmenter baseline(thesis);
  EXPECT_EQ(baseline.Process(image).mask.at<uint8_t>(60, 80), 0);
  // The same patch in a 120×160 image is over 0.5 % of it (96): kept.
  Segmenter small(ours);
  EXPECT_EQ(small.Process(image(cv::Rect(0, 0, 160, 120))).mask.at<uint8_t>(60, 80), 0);
  // Soil growth (soil_growth.h) takes it there: at 60 it stands far above
  // the flat soil at 40 around the plant, and the blob reaches it.
  ours.soil_growth.z = 3.0;
  Segmenter grown(ours);
  const cv::Mat grown_mask = grown.Process(image(cv::Rect(0, 0, 160, 120))).mask;
  EXPECT_EQ(cv::countNonZero(grown_mask(cv::Rect(74, 54, 13, 13)) == 0), 0);
}

cv::Mat Disk(int r) {
  cv::Mat k(2 * r + 1, 2 * r + 1, CV_8UC1, cv::Scalar(0));
  for (int dv = -r; dv <= r; ++dv) {
    const int h = NotchCloser::DiskHalfWidth(r, dv);
    k.row(dv + r).colRange(r - h, r + h + 1).setTo(1);
  }
  return k;
}

TEST(Notches, ANotchNarrowerThanTheDiskIsClosedAndTwoBlobsAreNotJoined) {
  cv::Mat mask(60, 80, CV_8UC1, cv::Scalar(0));
  cv::circle(mask, {30, 30}, 15, cv::Scalar(255), cv::FILLED);
  mask(cv::Rect(28, 15, 5, 10)).setTo(0);  // a notch 5 px wide, 10 deep, from the top
  cv::Mat before = mask.clone();
  NotchCloser closer;
  const int added = closer.Close(mask, 4);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(28, 19, 5, 6))), 30);  // the notch below its mouth
  EXPECT_EQ(added, cv::countNonZero(mask) - cv::countNonZero(before));
  EXPECT_EQ(cv::countNonZero(before & ~mask), 0);  // nothing removed
  // Two discs 3 px apart: closing would bridge them, so neither changes.
  cv::Mat pair(60, 80, CV_8UC1, cv::Scalar(0));
  cv::rectangle(pair, cv::Rect(10, 20, 20, 20), cv::Scalar(255), cv::FILLED);
  cv::rectangle(pair, cv::Rect(33, 20, 20, 20), cv::Scalar(255), cv::FILLED);
  before = pair.clone();
  EXPECT_EQ(closer.Close(pair, 4), 0);
  EXPECT_EQ(cv::countNonZero(pair != before), 0);
}

// One blob at a time, the result is OpenCV's closing with the same disk
// (borders as soil), OR the mask.
TEST(Notches, MatchesOpenCvClosingOfASingleBlob) {
  Rng rng(11);
  NotchCloser closer;
  for (int trial = 0; trial < 30; ++trial) {
    const int w = 40 + trial * 13 % 140, h = 30 + trial * 7 % 50, r = 1 + trial % 5;
    cv::Mat mask(h, w, CV_8UC1, cv::Scalar(0));
    // A random star-shaped blob: one connected piece with notches.
    const cv::Point c(w / 2, h / 2);
    std::vector<cv::Point> poly;
    for (int k = 0; k < 24; ++k) {
      const double a = 2.0 * M_PI * k / 24.0, rad = (0.15 + 0.3 * rng.Uniform()) * std::min(w, h);
      poly.emplace_back(c.x + static_cast<int>(rad * std::cos(a)), c.y + static_cast<int>(rad * std::sin(a)));
    }
    cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(255));
    cv::Mat expected;
    cv::morphologyEx(mask, expected, cv::MORPH_CLOSE, Disk(r), cv::Point(-1, -1), 1,
                     cv::BORDER_CONSTANT, cv::Scalar(0));
    expected |= mask;
    const int before = cv::countNonZero(mask);
    const int added = closer.Close(mask, r);
    EXPECT_EQ(cv::countNonZero(mask != expected), 0) << "trial " << trial << " r " << r;
    EXPECT_EQ(added, cv::countNonZero(mask) - before) << "trial " << trial;
  }
}

// A plant whose right lobe is shaded: the lobe is in the low mask only.
// Inside the lit part's hull it is added; the low mask's pixels outside
// every hull (a glint) stay soil.
TEST(HullGrower, AddsTheLowMaskInsideTheBlobsHullOnly) {
  cv::Mat mask(60, 80, CV_8UC1, cv::Scalar(0)), low(60, 80, CV_8UC1, cv::Scalar(0));
  // Lit: an L of two arms; its hull is the triangle they span.
  mask(cv::Rect(10, 10, 6, 30)).setTo(255);
  mask(cv::Rect(10, 34, 30, 6)).setTo(255);
  // Shaded: the triangle between the arms, and a glint far away.
  cv::rectangle(low, cv::Rect(16, 12, 14, 22), cv::Scalar(255), cv::FILLED);
  cv::rectangle(low, cv::Rect(60, 5, 6, 6), cv::Scalar(255), cv::FILLED);
  low |= mask;
  const cv::Mat before = mask.clone();
  HullGrower grower;
  const int added = grower.Grow(mask, low, 30);
  EXPECT_EQ(added, cv::countNonZero(mask) - cv::countNonZero(before));
  EXPECT_EQ(cv::countNonZero(before & ~mask), 0);  // nothing removed
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(60, 5, 6, 6))), 0);  // the glint
  // The shaded block's part inside the hull (below the diagonal from
  // (15, 10) to (39, 34), u − v = 5, by more than a pixel) is added, the
  // part above it is not.
  int inside = 0, outside = 0, inside_added = 0, outside_added = 0;
  for (int v = 12; v < 34; ++v) {
    for (int u = 16; u < 30; ++u) {
      const int side = u - v - 5;
      const bool set = mask.at<uint8_t>(v, u) != 0;
      if (side < -1) inside += 1, inside_added += set;
      if (side > 1) outside += 1, outside_added += set;
    }
  }
  ASSERT_GT(inside, 20);
  ASSERT_GT(outside, 5);
  EXPECT_EQ(inside_added, inside);
  EXPECT_EQ(outside_added, 0);
  // Blobs under the area limit get no hull.
  cv::Mat small = before.clone();
  EXPECT_EQ(grower.Grow(small, low, 1000), 0);
}

// Two plants whose grown regions would touch stay as they were; a third,
// alone, grows.
TEST(HullGrower, GrowthJoiningTwoBlobsIsNotKept) {
  cv::Mat mask(50, 120, CV_8UC1, cv::Scalar(0)), low(50, 120, CV_8UC1, cv::Scalar(0));
  for (const int x : {10, 40, 80}) {
    // A U-shaped plant (open upwards) with shaded matter between its arms.
    mask(cv::Rect(x, 10, 4, 25)).setTo(255);
    mask(cv::Rect(x + 20, 10, 4, 25)).setTo(255);
    mask(cv::Rect(x, 31, 24, 4)).setTo(255);
    low(cv::Rect(x + 4, 10, 16, 21)).setTo(255);
  }
  // The second plant's leaves reach left above and below the first plant
  // (not touching it), so its hull takes in column 34, beside the first's
  // right arm (columns 30–33); shaded leaf there would join the two.
  mask(cv::Rect(40, 4, 4, 6)).setTo(255);
  mask(cv::Rect(34, 4, 6, 3)).setTo(255);
  mask(cv::Rect(40, 35, 4, 6)).setTo(255);
  mask(cv::Rect(34, 38, 6, 3)).setTo(255);
  low(cv::Rect(34, 15, 6, 6)).setTo(255);
  const cv::Mat before = mask.clone();
  HullGrower grower;
  const int added = grower.Grow(mask, low, 30);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(0, 0, 70, 50)) != before(cv::Rect(0, 0, 70, 50))), 0);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(84, 10, 16, 21))), 16 * 21);  // the third grew
  EXPECT_EQ(added, 16 * 21);
}

// The spans HullGrower fills are the blob's convex hull: on random
// star-shaped blobs with a low mask that is everywhere, every pixel whose
// centre lies inside cv::convexHull's polygon (or on it) is added, and none
// more than half a pixel outside it along u (within 0.5 px of the polygon).
TEST(HullGrower, SpansAreTheBlobsConvexHull) {
  Rng rng(23);
  HullGrower grower;
  for (int trial = 0; trial < 20; ++trial) {
    const int w = 90 + trial, h = 70 + trial % 7;
    cv::Mat mask(h, w, CV_8UC1, cv::Scalar(0));
    std::vector<cv::Point> star;
    for (int k = 0; k < 9; ++k) {
      const double a = 2.0 * M_PI * k / 9.0, r = rng.Uniform(8.0, 30.0);
      star.emplace_back(static_cast<int>(w / 2 + r * std::cos(a)), static_cast<int>(h / 2 + r * std::sin(a)));
    }
    cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{star}, cv::Scalar(255));
    const cv::Mat low(h, w, CV_8UC1, cv::Scalar(255));
    std::vector<cv::Point> pixels, hull;
    cv::findNonZero(mask, pixels);
    cv::convexHull(pixels, hull);
    grower.Grow(mask, low, 30);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const double d = cv::pointPolygonTest(hull, cv::Point2f(u, v), true);
        const bool set = mask.at<uint8_t>(v, u) != 0;
        if (d >= 0.0) {
          EXPECT_TRUE(set) << "trial " << trial << " inside at " << u << "," << v;
        }
        if (d < -0.5) {
          EXPECT_FALSE(set) << "trial " << trial << " outside at " << u << "," << v << " by " << -d;
        }
      }
    }
  }
}

TEST(RowBits, SetBitsSetsExactlyTheRange) {
  for (const auto& [begin, end] : std::vector<std::pair<int, int>>{{0, 1}, {3, 64}, {0, 128}, {63, 65}, {10, 10}, {70, 190}, {127, 128}}) {
    std::vector<uint64_t> words(3, 0);
    detail::SetBits(words.data(), begin, end);
    for (int u = 0; u < 192; ++u) {
      const bool set = (words[static_cast<size_t>(u / 64)] >> (u % 64)) & 1;
      EXPECT_EQ(set, u >= begin && u < end) << begin << ".." << end << " at " << u;
    }
  }
}

}  // namespace
}  // namespace plantscale::vision
