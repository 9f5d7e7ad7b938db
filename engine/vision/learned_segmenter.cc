#include "engine/vision/learned_segmenter.h"

#include <opencv2/imgproc.hpp>
#include <string>

namespace plantscale::vision {

OptionErrors LearnedModelSpec::Validate() const {
  OptionErrors e;
  for (const auto& [key, value] : {std::pair{"input_width_px", input_width_px},
                                   std::pair{"input_height_px", input_height_px}}) {
    if (value < 16 || value > 4096 || value % 16 != 0) {
      e.push_back({key, "must be a multiple of 16 in 16..4096 (got " + std::to_string(value) + ")"});
    }
  }
  if (channels != 1 && channels != 3) {
    e.push_back({"channels", "must be 1 (grey) or 3 (colour) (got " + std::to_string(channels) + ")"});
  }
  if (classes != kPixelClassCount) {
    e.push_back({"classes", "must be 3: soil, crop, weed (got " + std::to_string(classes) + ")"});
  }
  if (output_stride != 1 && output_stride != 2 && output_stride != 4) {
    e.push_back({"output_stride", "must be 1, 2 or 4 (got " + std::to_string(output_stride) + ")"});
  }
  return e;
}

cv::Mat ResizeForModel(const cv::Mat& image, const LearnedModelSpec& spec) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    throw DataError("the model takes an 8-bit grey or colour image");
  }
  cv::Mat input = image;
  if (spec.channels == 1 && image.channels() == 3) {
    cv::cvtColor(image, input, cv::COLOR_BGR2GRAY);
  } else if (spec.channels == 3 && image.channels() == 1) {
    throw DataError("the model takes colour photographs and this one is grey");
  }
  const cv::Size size(spec.input_width_px, spec.input_height_px);
  if (input.size() == size) return input.clone();
  const bool shrinking = input.cols >= size.width && input.rows >= size.height;
  cv::Mat resized;
  cv::resize(input, resized, size, 0, 0, shrinking ? cv::INTER_AREA : cv::INTER_LINEAR);
  return resized;
}

LearnedSegmenter::LearnedSegmenter(std::span<const uint8_t> onnx, const LearnedModelSpec& spec)
    : spec_(spec) {
  ThrowIfInvalid("learned model", spec.Validate());
  if (onnx.empty()) throw DataError("the model is empty (0 bytes)");
  try {
    net_ = cv::dnn::readNetFromONNX(reinterpret_cast<const char*>(onnx.data()), onnx.size());
  } catch (const cv::Exception& e) {
    throw DataError(std::string("not an ONNX model OpenCV can read: ") + e.err);
  }
  if (net_.empty()) throw DataError("not an ONNX model OpenCV can read (no layers)");
  net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  // One pass on a blank input checks the graph's output against the spec.
  const cv::Mat blank(spec.input_height_px, spec.input_width_px, spec.channels == 1 ? CV_8UC1 : CV_8UC3,
                      cv::Scalar::all(0));
  cv::Mat out;
  try {
    out = Logits(blank);
  } catch (const cv::Exception& e) {
    throw DataError(std::string("the model does not run on a ") + std::to_string(spec.channels) +
                    "-channel " + std::to_string(spec.input_width_px) + "×" +
                    std::to_string(spec.input_height_px) + " input: " + e.err);
  }
  const int h = spec.input_height_px / spec.output_stride, w = spec.input_width_px / spec.output_stride;
  if (out.dims != 4 || out.size[0] != 1 || out.size[1] != spec.classes || out.size[2] != h ||
      out.size[3] != w) {
    std::string shape;
    for (int i = 0; i < out.dims; ++i) shape += (i ? "×" : "") + std::to_string(out.size[i]);
    throw DataError("the model's output is " + shape + "; its card says 1×" +
                    std::to_string(spec.classes) + "×" + std::to_string(h) + "×" + std::to_string(w) +
                    " (classes, 1/" + std::to_string(spec.output_stride) + " of the input)");
  }
}

cv::Mat LearnedSegmenter::Logits(const cv::Mat& model_input) {
  if (model_input.cols != spec_.input_width_px || model_input.rows != spec_.input_height_px ||
      model_input.channels() != spec_.channels) {
    throw DataError("the model's input must be " + std::to_string(spec_.input_width_px) + "×" +
                    std::to_string(spec_.input_height_px) + " with " + std::to_string(spec_.channels) +
                    " channel(s) (ResizeForModel)");
  }
  // 8-bit values as floats, N×C×H×W, channels in the image's order (BGR).
  const cv::Mat blob = cv::dnn::blobFromImage(model_input, 1.0, cv::Size(), cv::Scalar(), false, false,
                                              CV_32F);
  net_.setInput(blob);
  return net_.forward().clone();
}

ClassMaps LearnedSegmenter::Classify(const cv::Mat& image) {
  return FromLogits(Logits(ResizeForModel(image, spec_)), image.size());
}

ClassMaps LearnedSegmenter::FromLogits(const cv::Mat& logits, cv::Size size) {
  if (logits.dims != 4 || logits.size[0] != 1 || logits.size[1] != kPixelClassCount) {
    throw DataError("logits must be 1×3×h×w");
  }
  const int h = logits.size[2], w = logits.size[3];
  cv::Mat planes[kPixelClassCount];
  for (int c = 0; c < kPixelClassCount; ++c) {
    const cv::Mat plane(h, w, CV_32F, const_cast<float*>(logits.ptr<float>(0, c)));
    if (plane.size() == size) {
      planes[c] = plane.clone();
    } else {
      cv::resize(plane, planes[c], size, 0, 0, cv::INTER_LINEAR);
    }
  }
  // Whole-plane operations (OpenCV vectorises them): the largest logit, the
  // softmax of the chosen class as 1 / Σ exp(l_k − max), and the first class
  // reaching the largest logit.
  cv::Mat best = cv::max(planes[0], cv::max(planes[1], planes[2]));
  cv::Mat sum(size, CV_32FC1, cv::Scalar(0)), e;
  for (const cv::Mat& plane : planes) {
    cv::exp(plane - best, e);
    sum += e;
  }
  ClassMaps maps;
  cv::divide(1.0, sum, maps.confidence, CV_32F);
  maps.classes = cv::Mat(size, CV_8UC1, cv::Scalar(2));
  maps.classes.setTo(1, planes[1] >= best);
  maps.classes.setTo(0, planes[0] >= best);
  return maps;
}

}  // namespace plantscale::vision
