#include "app/camera_source.h"

#include <algorithm>
#include <cctype>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

bool IsImage(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" ||
         ext == ".tiff" || ext == ".pgm";
}

std::vector<fs::path> ListImages(const fs::path& dir) {
  std::vector<fs::path> images;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file() && IsImage(e.path())) images.push_back(e.path());
  }
  std::sort(images.begin(), images.end());
  if (images.empty())
    throw std::runtime_error(dir.string() + ": no images (png, jpg, bmp, tif, pgm)");
  return images;
}

bool AllDigits(const std::string& s) {
  return !s.empty() &&
         std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

}  // namespace

CameraFrameSource::CameraFrameSource(const CameraSourceOptions& options,
                                     telemetry::Transport& transport, int64_t epoch_utime)
    : options_(options), transport_(transport), epoch_utime_(epoch_utime) {
  odometry_.Attach(transport_);
  if (fs::is_directory(options_.camera)) {
    if (!(options_.folder_frame_rate_hz > 0.0)) {
      throw std::invalid_argument("--frame-rate: must be > 0");
    }
    images_ = ListImages(options_.camera);
    return;
  }
  const bool opened = AllDigits(options_.camera)
                          ? capture_.open(std::stoi(options_.camera), cv::CAP_V4L2)
                          : capture_.open(options_.camera, cv::CAP_V4L2);
  if (!opened) {
    throw std::runtime_error(options_.camera +
                             ": cannot open the camera (not a V4L2 device or a folder of images)");
  }
}

bool CameraFrameSource::ReadFolderImage(vehicle::VehicleFrame& frame) {
  while (next_ < images_.size()) {
    const size_t i = next_++;
    frame.utime = epoch_utime_ + static_cast<int64_t>(1e6 * static_cast<double>(i) /
                                                      options_.folder_frame_rate_hz);
    frame.frame_index = static_cast<int>(i);
    frame.image = cv::imread(images_[i].string(), cv::IMREAD_UNCHANGED);
    if (!frame.image.empty()) return true;
    ++dropped_;
    last_fault_ = "camera: cannot read " + images_[i].string();
  }
  return false;
}

bool CameraFrameSource::ReadDevice(vehicle::VehicleFrame& frame) {
  if (!capture_.read(frame.image) || frame.image.empty()) {
    last_fault_ = "camera: " + options_.camera + " stopped delivering frames";
    return false;
  }
  frame.utime = telemetry::WallUtime();
  frame.frame_index = static_cast<int>(next_++);
  return true;
}

bool CameraFrameSource::Next(vehicle::VehicleFrame& frame) {
  const bool ok = images_.empty() ? ReadDevice(frame) : ReadFolderImage(frame);
  while (transport_.Handle(0)) {
  }
  frame.odometry = odometry_.Take();
  frame.truth = nullptr;
  return ok;
}

std::vector<std::string> CameraFrameSource::faults(int64_t now_utime) const {
  // Folder frames carry folder time, not wall time: odometry age is only
  // meaningful against a live camera.
  std::vector<std::string> f =
      images_.empty() ? odometry_.Faults(now_utime) : odometry_.Faults(now_utime, 1e9);
  if (!last_fault_.empty()) f.push_back(last_fault_);
  return f;
}

}  // namespace plantscale::app
