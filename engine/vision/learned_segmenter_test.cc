#include "engine/vision/learned_segmenter.h"

#include <gtest/gtest.h>

#include <cmath>

namespace plantscale::vision {
namespace {

// Logits 1 × 3 × h × w with class k's plane filled by fill(k, y, x).
template <typename Fill>
cv::Mat MakeLogits(int h, int w, Fill fill) {
  const int sizes[] = {1, 3, h, w};
  cv::Mat logits(4, sizes, CV_32F);
  for (int k = 0; k < 3; ++k) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) logits.ptr<float>(0, k)[y * w + x] = fill(k, y, x);
    }
  }
  return logits;
}

TEST(LearnedSegmenter, ClassesAreTheArgmaxAndConfidenceTheSoftmax) {
  // Left half crop (logit 2 against 0), right half weed (logit 1 against 0).
  const cv::Mat logits = MakeLogits(4, 8, [](int k, int, int x) {
    if (x < 4) return k == 1 ? 2.0f : 0.0f;
    return k == 2 ? 1.0f : 0.0f;
  });
  const ClassMaps m = LearnedSegmenter::FromLogits(logits, cv::Size(8, 4));
  EXPECT_EQ(m.classes.at<uint8_t>(1, 0), 1);
  EXPECT_EQ(m.classes.at<uint8_t>(2, 7), 2);
  const double crop_p = std::exp(2.0) / (std::exp(2.0) + 2.0);
  const double weed_p = std::exp(1.0) / (std::exp(1.0) + 2.0);
  EXPECT_NEAR(m.confidence.at<float>(1, 0), crop_p, 1e-6);
  EXPECT_NEAR(m.confidence.at<float>(2, 7), weed_p, 1e-6);
}

TEST(LearnedSegmenter, LogitsAreUpsampledToThePhotograph) {
  // A soil/crop boundary at logit-column 5 of 10 lands at pixel 20 of 40.
  const cv::Mat logits = MakeLogits(3, 10, [](int k, int, int x) {
    const float crop = x < 5 ? 3.0f : -3.0f;
    return k == 1 ? crop : (k == 0 ? -crop : -10.0f);
  });
  const ClassMaps m = LearnedSegmenter::FromLogits(logits, cv::Size(40, 12));
  ASSERT_EQ(m.classes.size(), cv::Size(40, 12));
  EXPECT_EQ(m.classes.at<uint8_t>(6, 18), 1);
  EXPECT_EQ(m.classes.at<uint8_t>(6, 21), 0);
  EXPECT_EQ(cv::countNonZero(m.classes.row(6) == 1), 20);
}

TEST(LearnedSegmenter, ResizesAsTheSpecSays) {
  LearnedModelSpec spec;
  spec.input_width_px = 64;
  spec.input_height_px = 48;
  spec.channels = 1;
  const cv::Mat colour(96, 128, CV_8UC3, cv::Scalar(10, 200, 30));
  const cv::Mat in = ResizeForModel(colour, spec);
  EXPECT_EQ(in.size(), cv::Size(64, 48));
  EXPECT_EQ(in.channels(), 1);
  // BT.601 luma of (B 10, G 200, R 30).
  EXPECT_NEAR(in.at<uint8_t>(10, 10), 0.114 * 10 + 0.587 * 200 + 0.299 * 30, 1.0);
  spec.channels = 3;
  const cv::Mat grey(48, 64, CV_8UC1, cv::Scalar(90));
  EXPECT_THROW(ResizeForModel(grey, spec), DataError);
}

// Bytes that are no ONNX graph are refused in app/learned_model_test.cc
// (OpenCV's importer, outside the sanitized unit tests).
TEST(LearnedSegmenter, RefusesBadSpecsAndAnEmptyModel) {
  LearnedModelSpec spec;
  spec.input_width_px = 100;  // not a multiple of 16
  spec.classes = 2;
  const OptionErrors errors = spec.Validate();
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0].key, "input_width_px");
  EXPECT_EQ(errors[1].key, "classes");
  EXPECT_THROW(LearnedSegmenter({}, LearnedModelSpec{}), DataError);
  EXPECT_THROW(LearnedSegmenter({}, spec), InvalidOptionsError);
}

}  // namespace
}  // namespace plantscale::vision
