#pragma once
// A learned crop/weed model on disk: MODEL.onnx and its card MODEL.json
// beside it (what the network takes and gives, what it was trained on, the
// data's licence and attribution, its validation figures, the command that
// made it). Written by `plantscale train-segmenter`, read by `segment
// --model`, `evaluate classes`, `detect-rows --model` and the vehicle's crop
// profile (`segmenter: {model: FILE}`).

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine/vision/learned_segmenter.h"

namespace plantscale::app {

inline constexpr const char* kModelCardFormat = "plantscale-segmenter";
inline constexpr int kModelCardVersion = 1;

struct LearnedModel {
  std::filesystem::path onnx_path;
  std::filesystem::path card_path;
  vision::LearnedModelSpec spec;
  std::vector<uint8_t> onnx;  // the graph's bytes
  nlohmann::json card;        // the whole card, as written
};

// MODEL.json for MODEL.onnx (the extension replaced).
std::filesystem::path CardPath(const std::filesystem::path& onnx_path);

// The spec the card states; throws DataError naming the key and reason.
vision::LearnedModelSpec SpecFromCard(const nlohmann::json& card);

// Reads MODEL.onnx and its card. Throws DataError (missing or unreadable
// file, a card that is not the model's, an invalid key), naming the file.
// The graph itself is checked when a LearnedSegmenter is made of it.
LearnedModel ReadLearnedModel(const std::filesystem::path& onnx_path);

// Reads the model and builds its segmenter; a graph OpenCV cannot run, or
// whose output does not fit its card, throws DataError naming the file.
vision::LearnedSegmenter LoadSegmenter(const LearnedModel& model);

// A label image: single-channel 8-bit PNG of ids 0 soil, 1 crop, 2 weed, of
// `size`. Throws DataError naming the reason (another size, colour, an id
// outside 0–2 with where it is).
cv::Mat ReadLabelImage(const std::filesystem::path& path, cv::Size size);

// A photograph and its label (LABELS/NAME.png for IMAGES/NAME.*).
struct LabelledPhoto {
  std::filesystem::path image;
  std::filesystem::path label;
};

// Every photograph of `images` with its label in `labels`, sorted by name.
// Throws DataError naming the folder (not one, no images) or the first
// photograph without a label.
std::vector<LabelledPhoto> ListLabelledPhotos(const std::filesystem::path& images,
                                              const std::filesystem::path& labels);

// Reads both, checked (ReadImage, ReadLabelImage); DataError names the file.
void ReadLabelledPhoto(const LabelledPhoto& photo, cv::Mat& image, cv::Mat& label);

// The confusion matrix (rows truth, columns prediction) of one image added
// to `counts` (3 × 3).
void AddConfusion(const cv::Mat& truth, const cv::Mat& predicted, std::vector<int64_t>& counts);

// Per-class IoU from a 3 × 3 confusion matrix (NaN for a class absent from
// both truth and prediction).
std::vector<double> ClassIou(const std::vector<int64_t>& counts);

}  // namespace plantscale::app
