#pragma once
// `plantscale segment`: plant masks and blob lists for photographs on disk
// (PNG/JPEG of any size, colour or near-infrared grey). The only part that
// reads and writes files; the segmentation itself is engine/vision.

#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <iosfwd>
#include <string>
#include <vector>

#include "engine/vision/segmenter.h"

namespace plantscale::app {

struct SegmentPhotosRequest {
  std::vector<std::filesystem::path> inputs;  // files and folders
  std::filesystem::path out;
  std::string method = "auto";  // auto | exg | nir | adaptive
  std::string index = "exg";    // colour index for colour images: exg | exgr | cive
  int min_area_px = 0;          // 0: 1e-5 of the image's pixels, at least 4
  bool progress = true;
  // A learned crop/weed model (MODEL.onnx with MODEL.json beside it): then
  // NAME_classes.png (0 soil, 1 crop, 2 weed) and NAME_overlay.png instead
  // of the mask and blobs.
  std::filesystem::path model;
};

// A photograph's crop and weed pixel fractions (segment --model).
struct PhotoClassFractions {
  std::string name;
  int width_px = 0, height_px = 0;
  double crop = 0.0, weed = 0.0;
};

// What a batch of photographs came to (segment, detect-rows).
struct ImageBatchResult {
  int images = 0;
  int failed = 0;
  std::vector<std::string> errors;  // "FILE: reason"
  std::vector<PhotoClassFractions> fractions;  // segment --model: one per photograph segmented
};
using SegmentPhotosResult = ImageBatchResult;

// Images in `inputs` (folders are listed, sorted, non-recursively). A folder
// with no images and every unreadable file is an error of its own; the
// others are still processed.
std::vector<std::filesystem::path> CollectImages(const std::vector<std::filesystem::path>& inputs,
                                                 std::vector<std::string>& errors);

// Runs `one` on every image of `inputs` into `out` (created), with a
// progress bar labelled `label`: each image done is counted, each that
// throws is recorded as "FILE: reason" and the batch goes on.
void ForEachImage(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& out,
                  const std::string& label, bool progress, std::ostream& log, ImageBatchResult& result,
                  const std::function<void(const std::filesystem::path&)>& one);

// A PNG/JPEG as 8-bit grey or BGR; throws DataError naming what is wrong
// (empty, neither PNG nor JPEG by its first bytes, truncated, corrupt,
// unsupported depth or channels).
cv::Mat ReadImage(const std::filesystem::path& path);

// A colour image whose three channels are equal is a grey (NIR) image
// (or a label of ids) saved as colour.
bool IsGreyInColour(const cv::Mat& bgr);

// The segmenter options `plantscale segment` uses on this photograph, and in
// `input` the image to give it (a colour file with equal channels becomes
// grey). Throws DataError when the method does not suit the image.
vision::SegmenterOptions PhotoSegmenterOptions(const SegmentPhotosRequest& request,
                                               const cv::Mat& image, cv::Mat& input);

// The plant mask `plantscale segment` writes for this photograph (255:
// plant), with the request's method (the default: excess green on colour,
// the grey method on NIR). Throws DataError as PhotoSegmenterOptions.
cv::Mat PlantMaskOfPhoto(const cv::Mat& image, const SegmentPhotosRequest& request = {});

// Throws DataError when request.model cannot be loaded (before any image).
SegmentPhotosResult SegmentPhotos(const SegmentPhotosRequest& request, std::ostream& log);

// The photograph with crop pixels tinted green and weed pixels red.
cv::Mat ClassOverlay(const cv::Mat& image, const cv::Mat& classes);

}  // namespace plantscale::app
