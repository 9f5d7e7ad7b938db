#pragma once
// Frame sources of `plantscale run`: a V4L2 camera (a /dev/video* path or a
// device number, through OpenCV's videoio) or a folder of images (sorted by
// name, stamped at a fixed frame rate), with wheel odometry from
// PLANTSCALE_ODOMETRY_IN (app/vehicle/odometry_input.h) attached to each
// frame: every sample received since the previous frame.

#include <filesystem>
#include <memory>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "app/vehicle/odometry_input.h"
#include "app/vehicle/runner.h"

namespace plantscale::app {

struct CameraSourceOptions {
  std::string camera;                  // /dev/videoN, N, or a folder of images
  double folder_frame_rate_hz = 12.5;  // stamps of folder images
};

class CameraFrameSource : public vehicle::FrameSource {
 public:
  // Throws std::runtime_error naming the camera when it cannot be opened or
  // the folder holds no images. `transport` is polled for odometry.
  CameraFrameSource(const CameraSourceOptions& options, telemetry::Transport& transport,
                    int64_t epoch_utime);
  bool Next(vehicle::VehicleFrame& frame) override;
  int dropped_frames() const override { return dropped_; }
  std::string name() const override { return "run"; }
  std::vector<std::string> faults(int64_t now_utime) const override;

 private:
  bool ReadFolderImage(vehicle::VehicleFrame& frame);
  bool ReadDevice(vehicle::VehicleFrame& frame);

  CameraSourceOptions options_;
  telemetry::Transport& transport_;
  vehicle::OdometryInput odometry_;
  int64_t epoch_utime_;
  std::vector<std::filesystem::path> images_;  // folder mode
  cv::VideoCapture capture_;                   // device mode
  size_t next_ = 0;
  int dropped_ = 0;
  std::string last_fault_;
};

}  // namespace plantscale::app
