#include "engine/vision/learned_segmenter.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdint>
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
  ClassMaps maps;
  Classify(image, maps);
  return maps;
}

void LearnedSegmenter::Classify(const cv::Mat& image, ClassMaps& maps) {
  FromLogits(Logits(ResizeForModel(image, spec_)), image.size(), maps, planes_);
}

ClassMaps LearnedSegmenter::FromLogits(const cv::Mat& logits, cv::Size size) {
  ClassMaps maps;
  cv::Mat planes[kPixelClassCount];
  FromLogits(logits, size, maps, planes);
  return maps;
}

void LearnedSegmenter::FromLogits(const cv::Mat& logits, cv::Size size, ClassMaps& maps,
                                  cv::Mat (&planes)[kPixelClassCount]) {
  if (logits.dims != 4 || logits.size[0] != 1 || logits.size[1] != kPixelClassCount) {
    throw DataError("logits must be 1×3×h×w");
  }
  const int h = logits.size[2], w = logits.size[3];
  for (int c = 0; c < kPixelClassCount; ++c) {
    const cv::Mat plane(h, w, CV_32F, const_cast<float*>(logits.ptr<float>(0, c)));
    if (plane.size() == size) {
      plane.copyTo(planes[c]);
    } else {
      cv::resize(plane, planes[c], size, 0, 0, cv::INTER_LINEAR);
    }
  }
  // In runs of rows (the planes are continuous), with OpenCV's vectorised exp
  // and divide on small buffers: the largest logit, the softmax of the chosen
  // class as 1 / Σ exp(l_k − max), and the first class reaching the largest
  // logit. Whole-plane temporaries instead (five planes of 5 MB at 1280×960)
  // cost 70× the time of 640×480 for 4× the pixels, in fresh pages rather than
  // arithmetic; for the same reason the planes and the maps are written into
  // buffers kept from the previous frame, unless someone else still holds the
  // maps (or they are a view into a larger image).
  for (cv::Mat* m : {&maps.classes, &maps.confidence}) {
    if ((m->u != nullptr && m->u->refcount > 1) || !m->isContinuous()) m->release();
  }
  maps.classes.create(size, CV_8UC1);
  maps.confidence.create(size, CV_32FC1);
  const int total = size.width * size.height;
  constexpr int kRun = 8192;  // pixels per run: the buffers stay in L1/L2
  cv::Mat shifted(kPixelClassCount, kRun, CV_32FC1), e, sum(1, kRun, CV_32FC1);
  float* best = sum.ptr<float>(0);  // holds the largest logit, then Σ exp
  const float* plane[kPixelClassCount];
  for (int c = 0; c < kPixelClassCount; ++c) plane[c] = planes[c].ptr<float>(0);
  std::uint8_t* classes = maps.classes.ptr<std::uint8_t>(0);
  float* out = maps.confidence.ptr<float>(0);
  for (int start = 0; start < total; start += kRun) {
    const int n = std::min(kRun, total - start);
    const float* l0 = plane[0] + start;
    const float* l1 = plane[1] + start;
    const float* l2 = plane[2] + start;
    std::uint8_t* cls = classes + start;
    for (int i = 0; i < n; ++i) {
      const float m = std::max(l0[i], std::max(l1[i], l2[i]));
      best[i] = m;
      cls[i] = l0[i] >= m ? 0 : (l1[i] >= m ? 1 : 2);
    }
    for (int c = 0; c < kPixelClassCount; ++c) {
      const float* l = plane[c] + start;
      float* d = shifted.ptr<float>(c);
      for (int i = 0; i < n; ++i) d[i] = l[i] - best[i];
    }
    const cv::Range run(0, n);
    cv::exp(shifted.colRange(run), e);
    const float* e0 = e.ptr<float>(0);
    const float* e1 = e.ptr<float>(1);
    const float* e2 = e.ptr<float>(2);
    for (int i = 0; i < n; ++i) best[i] = ((0.0f + e0[i]) + e1[i]) + e2[i];
    cv::Mat dst(1, n, CV_32FC1, out + start);
    cv::divide(1.0, sum.colRange(run), dst, CV_32F);
  }
}

}  // namespace plantscale::vision
