#include "app/camera_source.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string_view>
#include <type_traits>

#include "app/config/config_loader.h"

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> SplitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  for (;;) {
    const size_t comma = line.find(',');
    fields.push_back(Trim(line.substr(0, comma)));
    if (comma == std::string_view::npos) return fields;
    line.remove_prefix(comma + 1);
  }
}

// A CSV with a header line naming its columns, read row by row; every
// problem is a ConfigError naming the file and the line.
class CsvReader {
 public:
  explicit CsvReader(const fs::path& file) : file_(file), in_(file) {
    if (!in_) {
      throw ConfigError(file_.string(), "(file)",
                        "cannot be read: " + std::string(std::strerror(errno)));
    }
    ++line_number_;
    if (!std::getline(in_, line_)) Fail("empty, expected a header line");
    for (std::string_view name : SplitFields(line_)) header_.emplace_back(name);
  }

  // The index of column `name`.
  size_t Column(const std::string& name) const {
    const auto it = std::find(header_.begin(), header_.end(), name);
    if (it == header_.end()) {
      throw ConfigError(file_.string(), "line 1", "no column '" + name + "' in the header");
    }
    return static_cast<size_t>(it - header_.begin());
  }
  bool HasColumn(const std::string& name) const {
    return std::find(header_.begin(), header_.end(), name) != header_.end();
  }

  // The next row that is not blank; false at the end of the file.
  bool Next() {
    while (std::getline(in_, line_)) {
      ++line_number_;
      if (Trim(line_).empty()) continue;
      fields_ = SplitFields(line_);
      if (fields_.size() != header_.size()) {
        Fail(std::to_string(fields_.size()) + " fields, the header has " +
             std::to_string(header_.size()));
      }
      return true;
    }
    return false;
  }

  template <typename T>
  T Get(size_t column) const {
    const std::string_view text = fields_[column];
    T value{};
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size() || text.empty()) {
      Fail(header_[column] + ": expected " + (std::is_integral_v<T> ? "an integer" : "a number") +
           ", got '" + std::string(text) + "'");
    }
    if constexpr (std::is_floating_point_v<T>) {
      if (!std::isfinite(value)) Fail(header_[column] + ": must be finite");
    }
    return value;
  }

  [[noreturn]] void Fail(const std::string& reason) const {
    throw ConfigError(file_.string(), "line " + std::to_string(line_number_), reason);
  }
  int line_number() const { return line_number_; }

 private:
  fs::path file_;
  std::ifstream in_;
  std::string line_;
  int line_number_ = 0;
  std::vector<std::string> header_;
  std::vector<std::string_view> fields_;  // of line_
};

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

std::vector<FrameTime> ReadFrameTimes(const fs::path& csv) {
  CsvReader reader(csv);
  const size_t utime = reader.Column("utime");
  const bool has_frame = reader.HasColumn("frame");
  const size_t frame = has_frame ? reader.Column("frame") : 0;
  std::vector<FrameTime> times;
  while (reader.Next()) {
    FrameTime t;
    t.utime = reader.Get<int64_t>(utime);
    t.frame_index = has_frame ? reader.Get<int>(frame) : static_cast<int>(times.size());
    if (!times.empty() && t.utime <= times.back().utime) {
      reader.Fail("utime " + std::to_string(t.utime) + " is not after the previous row's " +
                  std::to_string(times.back().utime));
    }
    times.push_back(t);
  }
  if (times.empty()) reader.Fail("no frames after the header");
  return times;
}

std::vector<pipeline::OdometrySample> ReadOdometryCsv(const fs::path& csv) {
  CsvReader reader(csv);
  const size_t utime = reader.Column("utime");
  const size_t left = reader.Column("left_m_s");
  const size_t right = reader.Column("right_m_s");
  std::vector<pipeline::OdometrySample> samples;
  while (reader.Next()) {
    pipeline::OdometrySample s;
    s.utime = reader.Get<int64_t>(utime);
    s.left_m_s = reader.Get<double>(left);
    s.right_m_s = reader.Get<double>(right);
    if (!samples.empty() && s.utime <= samples.back().utime) {
      reader.Fail("utime " + std::to_string(s.utime) + " is not after the previous row's " +
                  std::to_string(samples.back().utime));
    }
    samples.push_back(s);
  }
  if (samples.empty()) reader.Fail("no odometry samples after the header");
  return samples;
}

CameraFrameSource::CameraFrameSource(const CameraSourceOptions& options,
                                     telemetry::Transport& transport, int64_t epoch_utime)
    : options_(options), transport_(transport), epoch_utime_(epoch_utime) {
  const bool folder = fs::is_directory(options_.camera);
  if (!folder && (!options_.frame_times.empty() || !options_.odometry.empty())) {
    throw ConfigError("command line", options_.frame_times.empty() ? "--odometry" : "--frame-times",
                      "only with a folder of images (" + options_.camera + " is not a folder)");
  }
  if (options_.odometry.empty()) {
    odometry_.Attach(transport_);
  } else {
    odometry_csv_ = ReadOdometryCsv(options_.odometry);
    odometry_from_csv_ = true;
  }
  if (folder) {
    if (!(options_.folder_frame_rate_hz > 0.0)) {
      throw std::invalid_argument("--frame-rate: must be > 0");
    }
    images_ = ListImages(options_.camera);
    if (!options_.frame_times.empty()) {
      frame_times_ = ReadFrameTimes(options_.frame_times);
      if (frame_times_.size() != images_.size()) {
        throw ConfigError(
            options_.frame_times, "rows",
            std::to_string(frame_times_.size()) + " frame times for " +
                std::to_string(images_.size()) + " images in " + options_.camera +
                " (one row per image, in name order; simulate --out writes an image of "
                "every frame only with --every 1)");
      }
    }
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
    if (frame_times_.empty()) {
      frame.utime = epoch_utime_ + static_cast<int64_t>(1e6 * static_cast<double>(i) /
                                                        options_.folder_frame_rate_hz);
      frame.frame_index = static_cast<int>(i);
    } else {
      frame.utime = epoch_utime_ + frame_times_[i].utime;
      frame.frame_index = frame_times_[i].frame_index;
    }
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
  if (odometry_from_csv_) {
    frame.odometry.clear();
    if (ok) TakeOdometryUpTo(frame.utime, frame.odometry);
  } else {
    frame.odometry = odometry_.Take();
  }
  frame.truth = nullptr;
  return ok;
}

void CameraFrameSource::TakeOdometryUpTo(int64_t utime,
                                         std::vector<pipeline::OdometrySample>& out) {
  // As the simulator drives to a capture: step while the last step ended
  // before it, so the step spanning the capture comes with the frame.
  while (next_odometry_ < odometry_csv_.size() &&
         (next_odometry_ == 0 || epoch_utime_ + odometry_csv_[next_odometry_ - 1].utime < utime)) {
    pipeline::OdometrySample s = odometry_csv_[next_odometry_++];
    s.utime += epoch_utime_;
    out.push_back(s);
  }
}

std::vector<std::string> CameraFrameSource::faults(int64_t now_utime) const {
  // Folder frames carry folder time, not wall time: odometry age is only
  // meaningful against a live camera. Odometry from a CSV is the pipeline's
  // to judge (it closes the bar when the samples stop).
  std::vector<std::string> f;
  if (!odometry_from_csv_) {
    f = images_.empty() ? odometry_.Faults(now_utime) : odometry_.Faults(now_utime, 1e9);
  }
  if (!last_fault_.empty()) f.push_back(last_fault_);
  return f;
}

}  // namespace plantscale::app
