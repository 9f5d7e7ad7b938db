#include "engine/vision/pixel_classes.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"
#include "engine/geometry/test_cameras.h"
#include "engine/sim/simulator.h"
#include "engine/vision/segmenter.h"

namespace plantscale::vision {
namespace {

// A crop disc and a weed disc overlapping it: one blob of the plain mask,
// two once the mask is cut along the classes.
TEST(ClassCut, SeparatesAWeedTouchingACrop) {
  cv::Mat classes(120, 160, CV_8UC1, cv::Scalar(0));
  cv::circle(classes, {60, 60}, 30, cv::Scalar(1), cv::FILLED);
  cv::circle(classes, {98, 60}, 12, cv::Scalar(2), cv::FILLED);  // overlaps the crop by 4 px
  const cv::Mat mask = classes != 0;
  BlobExtractor e;
  ASSERT_EQ(e.Extract(mask).size(), 1u);
  cv::Mat cut;
  ClassCut(classes, cut);
  cv::Mat parts = mask.clone();
  parts.setTo(0, cut);
  const std::span<const Blob> blobs = e.Extract(parts);
  ASSERT_EQ(blobs.size(), 2u);
  // The cut takes the weed's pixels next to the crop only: the crop keeps
  // all of its own.
  EXPECT_EQ(cv::countNonZero(cut & (classes == 1)), 0);
  EXPECT_EQ(blobs[0].area_px, cv::countNonZero(classes == 1));
  const int weed = cv::countNonZero(classes == 2);
  EXPECT_GT(blobs[1].area_px, weed - 30);  // a 1-px arc of the 12-px disc
  EXPECT_LT(blobs[1].area_px, weed);
  // A crop's rim against soil is not cut.
  cv::Mat lone(120, 160, CV_8UC1, cv::Scalar(0));
  cv::circle(lone, {60, 60}, 30, cv::Scalar(1), cv::FILLED);
  ClassCut(lone, cut);
  EXPECT_EQ(cv::countNonZero(cut), 0);
  EXPECT_THROW(ClassCut(cv::Mat(), cut), DataError);
}

// Plant matter the model calls soil between a crop and a weed (the
// threshold's rim, the segmenter's growth) is cut halfway, however wide.
TEST(ClassCut, CutsASoilBridgeHalfway) {
  for (const int gap : {2, 5, 12}) {
    cv::Mat classes(60, 100, CV_8UC1, cv::Scalar(0));
    classes(cv::Rect(10, 20, 20, 20)).setTo(1);
    classes(cv::Rect(30 + gap, 20, 20, 20)).setTo(2);
    cv::Mat mask(60, 100, CV_8UC1, cv::Scalar(0));
    mask(cv::Rect(10, 20, 40 + gap, 20)).setTo(255);  // plant across the gap
    cv::Mat cut;
    ClassCut(classes, cut);
    mask.setTo(0, cut);
    BlobExtractor e;
    const std::span<const Blob> blobs = e.Extract(mask);
    ASSERT_EQ(blobs.size(), 2u) << "gap " << gap;
    // The crop keeps its pixels and the nearer half of the gap (a tie goes
    // to the crop), the cut is one column, the weed the rest.
    EXPECT_EQ(blobs[0].area_px, 20 * (20 + (gap + 1) / 2)) << "gap " << gap;
    EXPECT_EQ(cv::countNonZero(cut(cv::Rect(10, 20, 40 + gap, 20))), 20) << "gap " << gap;
  }
  // No weed in the frame: nothing is cut.
  cv::Mat lone(60, 100, CV_8UC1, cv::Scalar(0));
  lone(cv::Rect(10, 20, 20, 20)).setTo(1);
  cv::Mat cut;
  ClassCut(lone, cut);
  EXPECT_EQ(cv::countNonZero(cut), 0);
}

// The cut from the two-pass sweep is the cut from OpenCV's exact L1 distance
// transforms, pixel for pixel, on scattered crops and weeds of every size
// (frames of a simulated field's shape and odd sizes, borders included).
TEST(ClassCut, SweepMatchesOpenCvsDistanceTransform) {
  cv::RNG rng(7);
  int with_a_cut = 0;
  for (const cv::Size size : {cv::Size(640, 480), cv::Size(97, 31), cv::Size(1, 50), cv::Size(50, 1)}) {
    for (int trial = 0; trial < 4; ++trial) {
      cv::Mat classes(size, CV_8UC1, cv::Scalar(0));
      for (int k = 0; k < 60; ++k) {
        const cv::Point c(rng.uniform(0, size.width), rng.uniform(0, size.height));
        cv::circle(classes, c, rng.uniform(0, 30), cv::Scalar(k % 4 == 0 ? 2 : 1), cv::FILLED);
      }
      cv::Mat cut;
      ClassCut(classes, cut);
      cv::Mat expected = cv::Mat::zeros(size, CV_8UC1);
      const cv::Mat crop = classes == 1, weed = classes == 2;
      if (cv::countNonZero(crop) > 0 && cv::countNonZero(weed) > 0) {
        cv::Mat to_crop, to_weed, crop_side, near_crop;
        cv::distanceTransform(~crop, to_crop, cv::DIST_L1, 3, CV_32F);
        cv::distanceTransform(~weed, to_weed, cv::DIST_L1, 3, CV_32F);
        cv::compare(to_crop, to_weed, crop_side, cv::CMP_LE);
        cv::dilate(crop_side, near_crop, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
        cv::bitwise_and(near_crop, ~crop_side, expected);
      }
      EXPECT_EQ(cv::countNonZero(cut != expected), 0) << size << " trial " << trial;
      with_a_cut += cv::countNonZero(expected) > 0;
    }
  }
  EXPECT_GE(with_a_cut, 8);  // of 16: a one-pixel-wide frame mostly holds one class
}

TEST(BlobExtractor, LearnedClassIsTheMajorityAndConfidenceItsMeanProbability) {
  cv::Mat mask(20, 20, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(2, 2, 10, 10)).setTo(255);  // 100 px
  cv::Mat classes(20, 20, CV_8UC1, cv::Scalar(1));
  classes(cv::Rect(2, 2, 10, 3)).setTo(2);   // 30 px weed
  cv::Mat confidence(20, 20, CV_32FC1, cv::Scalar(0.9f));
  confidence(cv::Rect(2, 2, 10, 3)).setTo(0.6f);
  BlobExtractor e;
  e.Extract(mask);
  e.SetClasses(classes, confidence);
  const std::span<const Blob> blobs = e.Extract(mask);  // a new extraction forgets them
  EXPECT_EQ(blobs[0].learned_class, -1);
  e.SetClasses(classes, confidence);
  const Blob& b = blobs[0];
  EXPECT_EQ(b.learned_class, 1);
  // 70 crop pixels at 0.9 over 100 pixels.
  EXPECT_NEAR(b.learned_confidence, 0.63, 1e-6);
  EXPECT_THROW(e.SetClasses(classes(cv::Rect(0, 0, 10, 10)), confidence(cv::Rect(0, 0, 10, 10))),
               DataError);
  EXPECT_THROW(e.SetClasses(classes, cv::Mat(20, 20, CV_8UC1)), DataError);
}

// On a simulated frame with its own labels as the classes (a perfect
// model), no blob holds crop and weed: each blob's plant pixels are
// (nearly) all of its learned class, where the plain segmentation joins
// weeds to crops.
TEST(Segmenter, ClassesSplitBlobsOnASimulatedFrame) {
  sim::SimulatorOptions o;
  o.camera = geometry::testing::ThesisCamera();
  o.field.crop_radius_m = 0.14;
  o.field.weed_density_per_m2 = 30.0;  // weeds against crops in every frame
  o.seed = 7;
  sim::Simulator simulator(o);
  sim::SimFrame frame;
  for (int i = 0; i < 20; ++i) PLANTSCALE_CHECK(simulator.Next(frame), "simulator ended");
  const cv::Mat& labels = frame.rendered.labels;
  ClassMaps oracle;
  oracle.classes = labels.clone();
  oracle.confidence = cv::Mat(labels.size(), CV_32FC1, cv::Scalar(1.0f));
  // Pixels of a blob whose label differs from the blob's majority label.
  const auto mixed = [&](const Segmentation& s, const cv::Mat& mask) {
    cv::Mat components;
    const int n = cv::connectedComponents(mask, components, 8, CV_32S);
    std::vector<std::array<int, 3>> count(static_cast<size_t>(n), {0, 0, 0});
    for (int v = 0; v < mask.rows; ++v) {
      for (int u = 0; u < mask.cols; ++u) {
        const int k = components.at<int>(v, u);
        if (k > 0) ++count[static_cast<size_t>(k)][labels.at<uint8_t>(v, u)];
      }
    }
    int minority = 0;
    for (int k = 1; k < n; ++k) {
      const auto& c = count[static_cast<size_t>(k)];
      minority += std::min(c[1], c[2]);  // crop in a weed blob or weed in a crop blob
    }
    EXPECT_EQ(static_cast<size_t>(n - 1), s.blobs.size());
    return minority;
  };
  Segmenter plain({});
  const Segmentation& p = plain.Process(frame.rendered.image, simulator.camera());
  const int joined = mixed(p, p.mask);
  Segmenter cut({});
  const Segmentation& c = cut.Process(frame.rendered.image, simulator.camera(), oracle);
  const int left = mixed(c, c.mask);
  // Measured on this frame: 4,672 crop or weed pixels in a blob of the
  // other before, none after.
  EXPECT_GT(joined, 300);
  EXPECT_EQ(left, 0);
  int crop_blobs = 0, weed_blobs = 0;
  for (const Blob& b : c.blobs) {
    EXPECT_GE(b.learned_class, 0);
    if (b.learned_class == 1) ++crop_blobs;
    if (b.learned_class == 2) ++weed_blobs;
    if (b.learned_class != 0) {
      EXPECT_GT(b.learned_confidence, 0.5);
    }
  }
  EXPECT_GT(crop_blobs, 3);
  EXPECT_GT(weed_blobs, 3);
  for (const Blob& b : c.track_blobs) EXPECT_GE(b.learned_class, 0);
  EXPECT_THROW(cut.Process(frame.rendered.image, simulator.camera(),
                           ClassMaps{labels(cv::Rect(0, 0, 10, 10)).clone(), cv::Mat()}),
               DataError);
}

}  // namespace
}  // namespace plantscale::vision
