// Fuzz target: the image path of `plantscale segment` (app/config/photo_segmentation.h).
// Byte 0 picks the options (method auto/exg/nir/adaptive, colour index
// exg/exgr/cive, minimum blob area); the rest is the file. It is written
// as .png, or .jpg when it starts with a JPEG marker, read with ReadImage
// and, when readable, segmented with the options `segment` would use.
// Images are capped at 512 × 512 pixels (OPENCV_IO_MAX_IMAGE_PIXELS): the
// fuzzer looks for bad bytes, not large pictures. ReadImage and
// PhotoSegmenterOptions may refuse only with DataError, and OpenCV's
// decoders with cv::Exception (`segment` reports both per file and goes on);
// the segmenter must take every image ReadImage returns.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>

#include "app/config/photo_segmentation.h"
#include "engine/common/options.h"
#include "engine/vision/segmenter.h"
#include "tests/fuzz/fuzz_util.h"

namespace app = plantscale::app;

extern "C" int LLVMFuzzerInitialize(int*, char*** argv) {
  // OpenCV reads its limit once, as the library loads: start again with it.
  if (std::getenv("OPENCV_IO_MAX_IMAGE_PIXELS") == nullptr) {
    ::setenv("OPENCV_IO_MAX_IMAGE_PIXELS", "262144", 1);
    ::execv("/proc/self/exe", *argv);
    std::perror("segment_fuzz: re-exec with OPENCV_IO_MAX_IMAGE_PIXELS");
    std::abort();
  }
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  cv::setNumThreads(1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const kMethods[] = {"auto", "exg", "nir", "adaptive"};
  static const char* const kIndices[] = {"exg", "exgr", "cive"};
  app::SegmentPhotosRequest request;
  request.method = kMethods[data[0] % 4];
  request.index = kIndices[(data[0] / 4) % 3];
  request.min_area_px = (data[0] / 12) % 2 == 0 ? 0 : 1 + data[0] / 24;
  request.progress = false;
  const bool jpeg = size >= 3 && data[1] == 0xFF && data[2] == 0xD8;
  const auto path = plantscale::fuzz::WriteScratch(jpeg ? "fuzz.jpg" : "fuzz.png", data + 1, size - 1);
  try {
    const cv::Mat image = app::ReadImage(path);
    if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
      plantscale::fuzz::Fail("ReadImage returned an image the segmenter does not take");
    }
    cv::Mat input;
    const plantscale::vision::SegmenterOptions options =
        app::PhotoSegmenterOptions(request, image, input);
    plantscale::vision::Segmenter segmenter(options);
    const plantscale::vision::Segmentation& s = segmenter.Process(input);
    if (s.mask.size() != input.size()) plantscale::fuzz::Fail("mask size differs from the image");
  } catch (const plantscale::DataError&) {
    // the documented refusal
  } catch (const cv::Exception&) {
    // a decoder's refusal
  }
  return 0;
}
