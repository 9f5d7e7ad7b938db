#pragma once
// Frame sources of `plantscale run`: a V4L2 camera (a /dev/video* path or a
// device number, through OpenCV's videoio) or a folder of images (sorted by
// name, stamped at a fixed frame rate or with the times of a CSV), with wheel
// odometry from PLANTSCALE_ODOMETRY_IN (app/vehicle/odometry_input.h)
// attached to each frame: every sample received since the previous frame.
// A folder may take its odometry from a CSV instead: then each frame carries
// the samples after the previous frame's, up to the first at or after its
// capture (the odometry step that spans the capture reaches the vehicle
// before the frame does), as the simulator delivers them. The CSVs are the
// ones `simulate --out` writes (truth/frames.csv, truth/odometry.csv), so a
// folder written by simulate runs as `simulate --publish` does.

#include <filesystem>
#include <memory>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "app/vehicle/odometry_input.h"
#include "app/vehicle/runner.h"
#include "engine/pipeline/pipeline.h"

namespace plantscale::app {

struct CameraSourceOptions {
  std::string camera;                  // /dev/videoN, N, or a folder of images
  double folder_frame_rate_hz = 12.5;  // stamps of folder images without frame_times
  std::string frame_times;  // folder only: CSV of the images' capture times (ReadFrameTimes)
  std::string odometry;     // folder only: CSV of wheel odometry (ReadOdometryCsv), not LCM
};

// A folder image's capture, µs on the CSV's clock (from the start of the pass).
struct FrameTime {
  int64_t utime = 0;
  int frame_index = 0;
};

// The rows of a CSV with a header naming its columns: `utime` (µs,
// increasing) and optionally `frame` (the frame index; else the row's
// number), as simulate --out's truth/frames.csv. Throws ConfigError naming
// the file, the line and the reason for a missing column, a row with the
// wrong number of fields, a value that is not a number, times that do not
// increase, or no rows.
std::vector<FrameTime> ReadFrameTimes(const std::filesystem::path& csv);
// Wheel odometry samples of a CSV with columns `utime` (µs, increasing),
// `left_m_s` and `right_m_s` (the measured ground speeds of the wheels, m/s,
// finite), as simulate --out's truth/odometry.csv (its true_* columns are
// not read). Throws ConfigError as ReadFrameTimes.
std::vector<pipeline::OdometrySample> ReadOdometryCsv(const std::filesystem::path& csv);

class CameraFrameSource : public vehicle::FrameSource {
 public:
  // Throws std::runtime_error naming the camera when it cannot be opened or
  // the folder holds no images; ConfigError for bad CSVs (as above), frame
  // times whose count is not the folder's, or CSVs with a device.
  // `transport` is polled for odometry unless it comes from a CSV. Times of
  // the CSVs are shifted by `epoch_utime`.
  CameraFrameSource(const CameraSourceOptions& options, telemetry::Transport& transport,
                    int64_t epoch_utime);
  bool Next(vehicle::VehicleFrame& frame) override;
  int dropped_frames() const override { return dropped_; }
  std::string name() const override { return "run"; }
  std::vector<std::string> faults(int64_t now_utime) const override;

 private:
  bool ReadFolderImage(vehicle::VehicleFrame& frame);
  bool ReadDevice(vehicle::VehicleFrame& frame);
  // The CSV's samples up to the first at or after `utime`.
  void TakeOdometryUpTo(int64_t utime, std::vector<pipeline::OdometrySample>& out);

  CameraSourceOptions options_;
  telemetry::Transport& transport_;
  vehicle::OdometryInput odometry_;
  int64_t epoch_utime_;
  std::vector<std::filesystem::path> images_;  // folder mode
  std::vector<FrameTime> frame_times_;         // empty: at the frame rate
  std::vector<pipeline::OdometrySample> odometry_csv_;
  bool odometry_from_csv_ = false;
  size_t next_odometry_ = 0;
  cv::VideoCapture capture_;  // device mode
  size_t next_ = 0;
  int dropped_ = 0;
  std::string last_fault_;
};

}  // namespace plantscale::app
