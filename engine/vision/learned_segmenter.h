#pragma once
// Crop, weed and soil per pixel from a learned model: a small fully
// convolutional network (an ONNX graph of Conv, BatchNormalization, Relu,
// Resize and Concat) run through OpenCV's dnn module on the CPU. The model is
// the grower's, trained on their own labelled photographs by
// `plantscale train-segmenter` (app/training/); nothing Python runs here.
//
// The network takes the photograph resized to its input size (ResizeForModel:
// training resized its photographs with the same function) as 8-bit values in
// floats, N×C×H×W, and normalises them itself; it returns class logits at
// 1/output_stride of its input. Classify upsamples the logits bilinearly to
// the photograph's size and takes, per pixel, the most likely class and its
// softmax probability (the confidence the classifier fuses with the grid's
// position prior).
//
// Pure: the model arrives as bytes (the app reads the file and its card).

#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <span>

#include "engine/common/options.h"
#include "engine/vision/pixel_classes.h"

namespace plantscale::vision {

// What a model takes and gives; from its card (MODEL.json).
struct LearnedModelSpec {
  int input_width_px = 512;   // photographs are resized to this (a multiple of 16)
  int input_height_px = 384;
  int channels = 3;           // 3: colour (B, G, R); 1: grey (near-infrared)
  int classes = kPixelClassCount;
  int output_stride = 2;      // the logits are 1/output_stride of the input

  OptionErrors Validate() const;
};

// The photograph as the model takes it: grey or BGR as the spec says (a
// colour photograph for a grey model is converted; a grey photograph for a
// colour model is refused with a DataError), resized to the input size
// (area averaging when shrinking, bilinear when enlarging).
cv::Mat ResizeForModel(const cv::Mat& image, const LearnedModelSpec& spec);

class LearnedSegmenter {
 public:
  // Throws DataError when the bytes are not an ONNX graph OpenCV can run, or
  // when the graph's output does not fit the spec (class count, stride);
  // InvalidOptionsError when the spec itself is invalid.
  LearnedSegmenter(std::span<const uint8_t> onnx, const LearnedModelSpec& spec);

  const LearnedModelSpec& spec() const { return spec_; }

  // The raw logits (1 × classes × H/stride × W/stride, CV_32F) for an image
  // already at the model's input size and channels (ResizeForModel's output).
  cv::Mat Logits(const cv::Mat& model_input);

  // Classes and confidence at the photograph's size (8-bit grey or BGR, any size).
  ClassMaps Classify(const cv::Mat& image);
  // The same into `maps`, reusing its buffers when no one else holds them (a
  // fresh 5 MB plane per frame costs more in page faults than the arithmetic).
  void Classify(const cv::Mat& image, ClassMaps& maps);

  // Classes and confidence at the given size from logits (1 × C × h × w).
  static ClassMaps FromLogits(const cv::Mat& logits, cv::Size size);
  // The same into `maps` and the upsampled logits into `planes`, reusing
  // their buffers (what Classify(image, maps) does frame after frame).
  static void FromLogits(const cv::Mat& logits, cv::Size size, ClassMaps& maps,
                         cv::Mat (&planes)[kPixelClassCount]);

 private:

  LearnedModelSpec spec_;
  cv::dnn::Net net_;
  cv::Mat planes_[kPixelClassCount];  // the upsampled logits, kept between frames
};

}  // namespace plantscale::vision
