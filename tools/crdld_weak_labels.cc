// crdld_weak_labels: crop / weed / soil labels (0 soil, 1 crop, 2 weed, as
// train-segmenter takes them) for row photographs that are labelled only
// with their crop rows' centre lines, such as CRDLD (white lines about 8 px
// wide on black, at half the photograph's size). Weak labels: the plant mask
// is the one `detect-rows` finds without a model (photo segmentation), and a
// connected part of it is crop when it reaches a row line, weed when it does
// not. A model trained on them learns what the rows' plants look like, so
// that `detect-rows --model` finds rows in its crop class and not in the
// weeds between them (issue 57, item 6).
// usage: crdld_weak_labels IMAGES LINE_LABELS OUT_LABELS [--reach PX]
//   --reach: how far (photograph pixels) a part may lie from a line and still
//   reach it (default 4).
#include <filesystem>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "app/config/photo_segmentation.h"
#include "engine/vision/segmenter.h"

namespace fs = std::filesystem;
using namespace plantscale;

namespace {

// 255 on a row line, at the photograph's size.
cv::Mat LineMask(const fs::path& file, cv::Size size, int reach_px) {
  const cv::Mat label = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (label.empty()) throw std::runtime_error(file.string() + ": not an image");
  cv::Mat big, lines;
  cv::resize(label, big, size, 0, 0, cv::INTER_LINEAR);
  cv::threshold(big, lines, 127, 255, cv::THRESH_BINARY);
  if (reach_px > 0) {
    cv::dilate(lines, lines,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * reach_px + 1, 2 * reach_px + 1}));
  }
  return lines;
}

cv::Mat WeakLabel(const cv::Mat& image, const cv::Mat& lines) {
  const cv::Mat plant = app::PlantMaskOfPhoto(image);
  cv::Mat parts;
  const int n = cv::connectedComponents(plant, parts, 8, CV_32S);
  std::vector<uint8_t> on_line(static_cast<size_t>(n), 0);
  for (int y = 0; y < parts.rows; ++y) {
    const int* p = parts.ptr<int>(y);
    const uint8_t* l = lines.ptr<uint8_t>(y);
    for (int x = 0; x < parts.cols; ++x) {
      if (p[x] > 0 && l[x]) on_line[static_cast<size_t>(p[x])] = 1;
    }
  }
  cv::Mat label(plant.size(), CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < parts.rows; ++y) {
    const int* p = parts.ptr<int>(y);
    uint8_t* out = label.ptr<uint8_t>(y);
    for (int x = 0; x < parts.cols; ++x) {
      if (p[x] > 0) out[x] = on_line[static_cast<size_t>(p[x])] ? 1 : 2;
    }
  }
  return label;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: crdld_weak_labels IMAGES LINE_LABELS OUT_LABELS [--reach PX]\n";
    return 2;
  }
  const fs::path images = argv[1], line_labels = argv[2], out = argv[3];
  int reach_px = 4;
  for (int i = 4; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--reach" && i + 1 < argc) {
      reach_px = std::stoi(argv[++i]);
    } else {
      std::cerr << "crdld_weak_labels: unknown argument " << a << '\n';
      return 2;
    }
  }
  try {
    fs::create_directories(out);
    int written = 0;
    double crop = 0, weed = 0, total = 0;
    for (const auto& entry : fs::directory_iterator(images)) {
      const fs::path& file = entry.path();
      const cv::Mat image = cv::imread(file.string(), cv::IMREAD_COLOR);
      if (image.empty()) continue;
      fs::path line_file = line_labels / file.filename();
      if (!fs::exists(line_file)) line_file = line_labels / (file.stem().string() + ".png");
      if (!fs::exists(line_file)) throw std::runtime_error(file.string() + ": no line label in " + line_labels.string());
      const cv::Mat label = WeakLabel(image, LineMask(line_file, image.size(), reach_px));
      crop += cv::countNonZero(label == 1);
      weed += cv::countNonZero(label == 2);
      total += static_cast<double>(label.total());
      const fs::path dest = out / (file.stem().string() + ".png");
      if (!cv::imwrite(dest.string(), label)) throw std::runtime_error("cannot write " + dest.string());
      ++written;
    }
    std::cout << "crdld_weak_labels: " << written << " labels in " << out.string() << "; crop " << 100 * crop / total
              << " %, weed " << 100 * weed / total << " % of the pixels\n";
  } catch (const std::exception& e) {
    std::cerr << "crdld_weak_labels: " << e.what() << '\n';
    return 2;
  }
  return 0;
}
