#pragma once
// `plantscale segment`: plant masks and blob lists for photographs on disk
// (PNG/JPEG of any size, colour or near-infrared grey). The only part that
// reads and writes files; the segmentation itself is engine/vision.

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace plantscale::app {

struct SegmentPhotosRequest {
  std::vector<std::filesystem::path> inputs;  // files and folders
  std::filesystem::path out;
  std::string method = "auto";  // auto | exg | nir | adaptive
  std::string index = "exg";    // colour index for colour images: exg | exgr | cive
  int min_area_px = 0;          // 0: 1e-5 of the image's pixels, at least 4
  bool progress = true;
};

struct SegmentPhotosResult {
  int images = 0;
  int failed = 0;
  std::vector<std::string> errors;  // "FILE: reason"
};

// Images in `inputs` (folders are listed, sorted, non-recursively). A folder
// with no images and every unreadable file is an error of its own; the
// others are still processed.
std::vector<std::filesystem::path> CollectImages(const std::vector<std::filesystem::path>& inputs,
                                                 std::vector<std::string>& errors);

SegmentPhotosResult SegmentPhotos(const SegmentPhotosRequest& request, std::ostream& log);

}  // namespace plantscale::app
