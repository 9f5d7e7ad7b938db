#include "app/config/learned_model.h"

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "app/config/photo_segmentation.h"

namespace plantscale::app {
namespace fs = std::filesystem;

fs::path CardPath(const fs::path& onnx_path) {
  fs::path card = onnx_path;
  card.replace_extension(".json");
  return card;
}

namespace {

int IntKey(const nlohmann::json& j, const char* key, const std::string& where) {
  if (!j.contains(key) || !j.at(key).is_number_integer()) {
    throw DataError(where + ": '" + key + "' must be an integer");
  }
  return j.at(key).get<int>();
}

}  // namespace

vision::LearnedModelSpec SpecFromCard(const nlohmann::json& card) {
  if (!card.is_object() || card.value("format", "") != kModelCardFormat) {
    throw DataError(std::string("not a plantscale model card ('format' is not '") + kModelCardFormat + "')");
  }
  if (card.value("version", 0) != kModelCardVersion) {
    throw DataError("model card version " + card.value("version", nlohmann::json()).dump() +
                    " (this plantscale reads version " + std::to_string(kModelCardVersion) + ")");
  }
  if (!card.contains("input") || !card.at("input").is_object()) {
    throw DataError("the card has no 'input' object");
  }
  const nlohmann::json& in = card.at("input");
  vision::LearnedModelSpec s;
  s.input_width_px = IntKey(in, "width_px", "input");
  s.input_height_px = IntKey(in, "height_px", "input");
  const std::string kind = in.value("image", "");
  if (kind != "colour" && kind != "grey") {
    throw DataError("input.image must be 'colour' or 'grey' (got '" + kind + "')");
  }
  s.channels = kind == "colour" ? 3 : 1;
  if (!card.contains("classes") || !card.at("classes").is_array()) {
    throw DataError("the card has no 'classes' list");
  }
  s.classes = static_cast<int>(card.at("classes").size());
  s.output_stride = IntKey(card, "output_stride", "card");
  const OptionErrors errors = s.Validate();
  if (!errors.empty()) throw DataError(errors.front().key + " " + errors.front().reason);
  const std::vector<std::string> expected{"soil", "crop", "weed"};
  if (card.at("classes") != nlohmann::json(expected)) {
    throw DataError("classes must be [\"soil\", \"crop\", \"weed\"] (got " + card.at("classes").dump() + ")");
  }
  return s;
}

LearnedModel ReadLearnedModel(const fs::path& onnx_path) {
  LearnedModel m;
  m.onnx_path = onnx_path;
  m.card_path = CardPath(onnx_path);
  std::ifstream in(onnx_path, std::ios::binary);
  if (!in) throw DataError(onnx_path.string() + ": cannot read the model");
  m.onnx.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (m.onnx.empty()) throw DataError(onnx_path.string() + ": empty model file (0 bytes)");
  std::ifstream card_in(m.card_path);
  if (!card_in) {
    throw DataError(m.card_path.string() + ": cannot read the model's card (MODEL.json beside MODEL.onnx)");
  }
  try {
    m.card = nlohmann::json::parse(card_in);
    m.spec = SpecFromCard(m.card);
  } catch (const nlohmann::json::exception& e) {
    throw DataError(m.card_path.string() + ": not JSON: " + e.what());
  } catch (const DataError& e) {
    throw DataError(m.card_path.string() + ": " + e.what());
  }
  return m;
}

vision::LearnedSegmenter LoadSegmenter(const LearnedModel& model) {
  try {
    return vision::LearnedSegmenter(model.onnx, model.spec);
  } catch (const DataError& e) {
    throw DataError(model.onnx_path.string() + ": " + e.what());
  }
}

cv::Mat ReadLabelImage(const fs::path& path, cv::Size size) {
  cv::Mat label = ReadImage(path);
  // A label saved as colour: its ids in every channel.
  if (label.channels() == 3 && IsGreyInColour(label)) cv::extractChannel(label, label, 0);
  if (label.channels() != 1) {
    throw DataError("a label must be single-channel (ids 0 soil, 1 crop, 2 weed); this one has " +
                    std::to_string(label.channels()) + " channels");
  }
  if (label.size() != size) {
    throw DataError("label is " + std::to_string(label.cols) + "×" + std::to_string(label.rows) +
                    ", its photograph " + std::to_string(size.width) + "×" + std::to_string(size.height));
  }
  double max_id = 0;
  cv::Point where;
  cv::minMaxLoc(label, nullptr, &max_id, nullptr, &where);
  if (max_id > 2) {
    throw DataError("label id " + std::to_string(static_cast<int>(max_id)) + " at (" +
                    std::to_string(where.x) + ", " + std::to_string(where.y) +
                    ") is outside 0–2 (0 soil, 1 crop, 2 weed)");
  }
  return label;
}

std::vector<LabelledPhoto> ListLabelledPhotos(const fs::path& images, const fs::path& labels) {
  std::error_code ec;
  if (!fs::is_directory(images, ec)) throw DataError(images.string() + ": not a folder");
  if (!fs::is_directory(labels, ec)) throw DataError(labels.string() + ": not a folder");
  std::vector<std::string> errors;
  const std::vector<fs::path> files = CollectImages({images}, errors);
  if (!errors.empty()) throw DataError(errors.front());
  std::vector<LabelledPhoto> photos;
  for (const fs::path& file : files) {
    const fs::path label = labels / (file.stem().string() + ".png");
    if (!fs::exists(label, ec)) throw DataError(file.string() + ": no label (expected " + label.string() + ")");
    photos.push_back({file, label});
  }
  return photos;
}

void ReadLabelledPhoto(const LabelledPhoto& photo, cv::Mat& image, cv::Mat& label) {
  try {
    image = ReadImage(photo.image);
  } catch (const DataError& e) {
    throw DataError(photo.image.string() + ": " + e.what());
  }
  try {
    label = ReadLabelImage(photo.label, image.size());
  } catch (const DataError& e) {
    throw DataError(photo.label.string() + ": " + e.what());
  }
}

void AddConfusion(const cv::Mat& truth, const cv::Mat& predicted, std::vector<int64_t>& counts) {
  counts.resize(vision::kPixelClassCount * vision::kPixelClassCount, 0);
  for (int y = 0; y < truth.rows; ++y) {
    const uint8_t* t = truth.ptr<uint8_t>(y);
    const uint8_t* p = predicted.ptr<uint8_t>(y);
    for (int x = 0; x < truth.cols; ++x) {
      ++counts[static_cast<size_t>(t[x] * vision::kPixelClassCount + p[x])];
    }
  }
}

std::vector<double> ClassIou(const std::vector<int64_t>& counts) {
  const int n = vision::kPixelClassCount;
  std::vector<double> iou(static_cast<size_t>(n));
  for (int c = 0; c < n; ++c) {
    int64_t row = 0, col = 0;
    for (int k = 0; k < n; ++k) {
      row += counts[static_cast<size_t>(c * n + k)];
      col += counts[static_cast<size_t>(k * n + c)];
    }
    const int64_t tp = counts[static_cast<size_t>(c * n + c)];
    const int64_t uni = row + col - tp;
    iou[static_cast<size_t>(c)] =
        uni > 0 ? static_cast<double>(tp) / static_cast<double>(uni) : std::numeric_limits<double>::quiet_NaN();
  }
  return iou;
}

}  // namespace plantscale::app
