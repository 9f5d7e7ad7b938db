#include "app/config/photo_segmentation.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <ostream>

#include "app/config/learned_model.h"
#include "app/config/progress.h"
#include "engine/common/options.h"
#include "engine/vision/segmenter.h"
#include "maps/staged_output.h"

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

std::string LowerExtension(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}
bool IsJpeg(const fs::path& p) { return LowerExtension(p) == ".jpg" || LowerExtension(p) == ".jpeg"; }
bool IsImageFile(const fs::path& p) { return IsJpeg(p) || LowerExtension(p) == ".png"; }

// libjpeg decodes a truncated file into a grey-filled image with only a
// warning; a complete JPEG ends with the EOI marker FF D9.
bool JpegComplete(const fs::path& p) {
  std::ifstream in(p, std::ios::binary | std::ios::ate);
  const std::streamoff size = in.tellg();
  if (size < 4) return false;
  in.seekg(size - 2);
  char tail[2] = {0, 0};
  in.read(tail, 2);
  return static_cast<unsigned char>(tail[0]) == 0xFF && static_cast<unsigned char>(tail[1]) == 0xD9;
}

enum class ImageFormat { kPng, kJpeg, kOther };

// What the file's first bytes say it is (the signatures OpenCV's PNG and JPEG
// decoders take), whatever its name says. Only these two reach cv::imread: it
// would take any format OpenCV knows, and its Radiance HDR reader leaves the
// file open on a bad header (one descriptor lost per such file).
ImageFormat SniffFormat(const fs::path& p) {
  static constexpr unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  unsigned char head[8] = {};
  std::ifstream in(p, std::ios::binary);
  in.read(reinterpret_cast<char*>(head), sizeof head);
  const std::streamsize n = in.gcount();
  if (n == 8 && std::equal(head, head + 8, kPng)) return ImageFormat::kPng;
  if (n >= 3 && head[0] == 0xFF && head[1] == 0xD8 && head[2] == 0xFF) return ImageFormat::kJpeg;
  return ImageFormat::kOther;
}

}  // namespace

cv::Mat ReadImage(const fs::path& p) {
  std::error_code ec;
  const auto size = fs::file_size(p, ec);
  if (ec) throw DataError("cannot read: " + ec.message());
  if (size == 0) throw DataError("empty file (0 bytes)");
  const ImageFormat format = SniffFormat(p);
  if (format == ImageFormat::kOther) throw DataError("not a PNG or JPEG image (neither signature)");
  if (format == ImageFormat::kJpeg && !JpegComplete(p)) {
    throw DataError("truncated JPEG (no end-of-image marker)");
  }
  cv::Mat image = cv::imread(p.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw DataError("not a readable PNG/JPEG image (corrupt or truncated)");
  if (image.depth() == CV_16U) image.convertTo(image, CV_8U, 1.0 / 257.0);
  if (image.depth() != CV_8U) throw DataError("unsupported pixel depth (need 8 or 16 bit)");
  switch (image.channels()) {
    case 1: case 3: return image;
    case 4: cv::cvtColor(image, image, cv::COLOR_BGRA2BGR); return image;
    case 2: cv::cvtColor(image, image, cv::COLOR_GRAY2BGR); return image;  // never from imread
    default: throw DataError("unsupported channel count " + std::to_string(image.channels()));
  }
}

bool IsGreyInColour(const cv::Mat& bgr) {
  cv::Mat ch[3];
  cv::split(bgr, ch);
  return cv::countNonZero(ch[0] != ch[1]) == 0 && cv::countNonZero(ch[1] != ch[2]) == 0;
}

vision::SegmenterOptions PhotoSegmenterOptions(const SegmentPhotosRequest& r,
                                               const cv::Mat& image, cv::Mat& input) {
  vision::SegmenterOptions o;
  o.colour_index = *vision::ParseColourIndex(r.index);
  const bool colour = image.channels() == 3 && !IsGreyInColour(image);
  input = image;
  if (image.channels() == 3 && !colour) cv::cvtColor(image, input, cv::COLOR_BGR2GRAY);
  // Photographs of unknown scale: light smoothing only (sensor noise, JPEG
  // blocks); the 2 px of the product default were set on 640×480 frames.
  o.smoothing_px = 1.0;
  // Soil seen between a real plant's leaves is soil: a photograph's mask
  // keeps its holes, notches and what lies between its lobes (the
  // simulator's are shaded leaf, holes.h).
  o.fill_holes_max_fraction = 0.0;
  o.close_notches_px = 0;
  o.hull_gain = 0.0;
  o.soil_growth.z = 0.0;  // as the hull growth: soil beside a real plant is soil
  std::string method = r.method == "auto" ? (colour ? "exg" : "nir") : r.method;
  if (method == "nir" && colour) {
    throw DataError("--method nir needs a near-infrared (single-channel) image; this one is "
                    "colour: use --method exg");
  }
  if (method == "exg") {
    if (!colour) throw DataError("--method exg needs a colour image; this one is grey: use nir");
    // Colour indices are differences, not ratios, so the soil-relative gain
    // of the local threshold does not apply; Otsu on the index is the
    // standard (Meyer & Neto 2008) and needs no tuning per photograph.
    o.method = vision::ThresholdMethod::kOtsu;
    o.otsu_floor = 127.5 + 127.5 * 0.05;  // ExG >= 0.05: visibly greener than grey
    if (o.colour_index == vision::ColourIndex::kExGR) {
      o.method = vision::ThresholdMethod::kFixed;  // ExGR's own zero (Meyer & Neto 2008)
      o.fixed_threshold = 128.0;
    }
  } else if (method == "adaptive") {
    o.method = vision::ThresholdMethod::kAdaptive;
    o.smoothing_px = 0.0;  // the thesis's method as published
  } else {
    o.method = vision::ThresholdMethod::kLocal;
  }
  const double pixels = static_cast<double>(image.total());
  o.blobs.min_area_px = r.min_area_px > 0 ? r.min_area_px
                                          : std::max(4, static_cast<int>(std::ceil(1e-5 * pixels)));
  return o;
}

namespace {

void WriteBlobs(const fs::path& path, std::span<const vision::Blob> blobs) {
  maps::WriteStaged(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp);
    out << "id,centroid_u,centroid_v,area_px,bbox_u,bbox_v,bbox_width,bbox_height\n";
    out.precision(2);
    out << std::fixed;
    for (const vision::Blob& b : blobs) {
      out << b.id << ',' << b.centroid_px.x() << ',' << b.centroid_px.y() << ',' << b.area_px
          << ',' << b.bbox_px.x << ',' << b.bbox_px.y << ',' << b.bbox_px.width << ','
          << b.bbox_px.height << '\n';
    }
    if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
  });
}

void SegmentOne(const SegmentPhotosRequest& r, const fs::path& file) {
  const cv::Mat image = ReadImage(file);
  cv::Mat input;
  vision::Segmenter segmenter(PhotoSegmenterOptions(r, image, input));
  const vision::Segmentation& s = segmenter.Process(input);
  const std::string stem = file.stem().string();
  const fs::path mask = r.out / (stem + "_mask.png");
  maps::WriteStaged(mask, [&](const fs::path& tmp) {
    if (!cv::imwrite(tmp.string(), s.mask)) throw std::runtime_error("cannot write " + mask.string());
  });
  WriteBlobs(r.out / (stem + "_blobs.csv"), s.blobs);
}

}  // namespace

cv::Mat PlantMaskOfPhoto(const cv::Mat& image, const SegmentPhotosRequest& request) {
  cv::Mat input;
  vision::Segmenter segmenter(PhotoSegmenterOptions(request, image, input));
  return segmenter.Process(input).mask;  // shares the buffer the segmenter leaves
}

std::vector<fs::path> CollectImages(const std::vector<fs::path>& inputs,
                                    std::vector<std::string>& errors) {
  std::vector<fs::path> files;
  for (const fs::path& in : inputs) {
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      std::vector<fs::path> found;
      for (const auto& e : fs::directory_iterator(in, ec)) {
        if (e.is_regular_file() && IsImageFile(e.path())) found.push_back(e.path());
      }
      if (ec) errors.push_back(in.string() + ": cannot list folder: " + ec.message());
      else if (found.empty()) errors.push_back(in.string() + ": no PNG or JPEG images in folder");
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else if (fs::exists(in, ec)) {
      files.push_back(in);
    } else {
      errors.push_back(in.string() + ": no such file or folder");
    }
  }
  return files;
}

void ForEachImage(const std::vector<fs::path>& inputs, const fs::path& out, const std::string& label,
                  bool progress, std::ostream& log, ImageBatchResult& result,
                  const std::function<void(const fs::path&)>& one) {
  const std::vector<fs::path> files = CollectImages(inputs, result.errors);
  result.failed = static_cast<int>(result.errors.size());
  fs::create_directories(out);
  ProgressBar bar(log, label, static_cast<int>(files.size()), progress);
  int done = 0;
  for (const fs::path& file : files) {
    try {
      one(file);
      ++result.images;
    } catch (const std::exception& e) {
      result.errors.push_back(file.string() + ": " + e.what());
      ++result.failed;
    }
    bar.Update(++done);
  }
  bar.Finish();
}

cv::Mat ClassOverlay(const cv::Mat& image, const cv::Mat& classes) {
  cv::Mat bgr;
  if (image.channels() == 1) cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  else bgr = image.clone();
  const cv::Vec3b tint[3] = {{0, 0, 0}, {40, 220, 40}, {40, 40, 255}};
  for (int y = 0; y < bgr.rows; ++y) {
    cv::Vec3b* p = bgr.ptr<cv::Vec3b>(y);
    const uint8_t* c = classes.ptr<uint8_t>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      if (c[x] == 0) continue;
      for (int k = 0; k < 3; ++k) p[x][k] = static_cast<uint8_t>((p[x][k] + tint[c[x]][k]) / 2);
    }
  }
  return bgr;
}

namespace {

void WritePng(const fs::path& path, const cv::Mat& image) {
  maps::WriteStaged(path, [&](const fs::path& tmp) {
    if (!cv::imwrite(tmp.string(), image)) throw std::runtime_error("cannot write " + path.string());
  });
}

PhotoClassFractions ClassifyOne(vision::LearnedSegmenter& model, const fs::path& out, const fs::path& file) {
  const cv::Mat image = ReadImage(file);
  const vision::ClassMaps maps = model.Classify(image);
  const std::string stem = file.stem().string();
  WritePng(out / (stem + "_classes.png"), maps.classes);
  WritePng(out / (stem + "_overlay.png"), ClassOverlay(image, maps.classes));
  const double n = static_cast<double>(maps.classes.total());
  return {file.filename().string(), image.cols, image.rows,
          cv::countNonZero(maps.classes == 1) / n, cv::countNonZero(maps.classes == 2) / n};
}

}  // namespace

SegmentPhotosResult SegmentPhotos(const SegmentPhotosRequest& request, std::ostream& log) {
  SegmentPhotosResult result;
  if (!request.model.empty()) {
    vision::LearnedSegmenter model = LoadSegmenter(ReadLearnedModel(request.model));
    ForEachImage(request.inputs, request.out, "segment", request.progress, log, result,
                 [&](const fs::path& file) { result.fractions.push_back(ClassifyOne(model, request.out, file)); });
    return result;
  }
  ForEachImage(request.inputs, request.out, "segment", request.progress, log, result,
               [&request](const fs::path& file) { SegmentOne(request, file); });
  return result;
}

}  // namespace plantscale::app
