#include "app/sim_output.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "app/config/config_loader.h"

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("plantscale_out_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  return dir;
}

SimulateRequest ShortRun(const fs::path& out) {
  SimulateRequest r;
  r.options = LoadSimulatorPreset("testbed", DefaultConfigDir());
  r.options.length_m = 1.0;
  r.out = out;
  r.image_every = 2;
  r.progress = false;
  return r;
}

int CountLines(const fs::path& file) {
  std::ifstream in(file);
  int n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

TEST(SimOutput, WritesFramesLabelsAndTruth) {
  const fs::path out = TempDir("writes");
  std::ostringstream progress;
  const SimulateSummary s = RunSimulation(ShortRun(out), progress);
  // 1 m at 0.3 m/s and 12.5 frames/s: 41 or 42 frames (timing jitter).
  EXPECT_NEAR(s.frames, 1.0 / 0.3 * 12.5, 1.5);
  EXPECT_EQ(s.images_written, (s.frames + 1) / 2);
  EXPECT_EQ(CountLines(out / "truth" / "frames.csv"), s.frames + 1);
  EXPECT_GT(CountLines(out / "truth" / "visible_plants.csv"), s.frames * 5);
  // Odometry at 50 Hz: four samples per frame.
  EXPECT_NEAR(CountLines(out / "truth" / "odometry.csv") - 1, 4 * s.frames, 4);
  const cv::Mat frame = cv::imread((out / "frames" / "000000.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat labels = cv::imread((out / "labels" / "000000.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat instances =
      cv::imread((out / "instances" / "000000.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(frame.empty());
  EXPECT_EQ(frame.cols, 640);
  EXPECT_EQ(frame.rows, 480);
  EXPECT_EQ(labels.type(), CV_8UC1);
  EXPECT_EQ(instances.type(), CV_16UC1);
  double max_label = 0.0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  EXPECT_LE(max_label, 2.0);
  EXPECT_GT(cv::countNonZero(labels), 1000);
  EXPECT_TRUE(fs::exists(out / "run.json"));
  EXPECT_FALSE(fs::exists(out / "frames" / "000001.png"));  // every 2nd frame only
  fs::remove_all(out);
}

TEST(SimOutput, SameSeedSameBytes) {
  const fs::path a = TempDir("same_a");
  const fs::path b = TempDir("same_b");
  std::ostringstream progress;
  RunSimulation(ShortRun(a), progress);
  RunSimulation(ShortRun(b), progress);
  for (const char* file : {"frames/000004.png", "labels/000004.png", "truth/frames.csv",
                           "truth/visible_plants.csv", "truth/odometry.csv"}) {
    std::ifstream fa(a / file, std::ios::binary);
    std::ifstream fb(b / file, std::ios::binary);
    const std::string da((std::istreambuf_iterator<char>(fa)), {});
    const std::string db((std::istreambuf_iterator<char>(fb)), {});
    EXPECT_FALSE(da.empty()) << file;
    EXPECT_EQ(da, db) << file;
  }
  fs::remove_all(a);
  fs::remove_all(b);
}

// What `run` reads back is what the simulator rendered: 8-bit PNGs,
// lossless, named by frame index, one per frame with --every 1; the frame
// times and measured odometry round-trip exactly through the CSVs.
TEST(SimOutput, FramesAndOdometryReadBackExactly) {
  const fs::path out = TempDir("exact");
  SimulateRequest request = ShortRun(out);
  request.image_every = 1;
  std::ostringstream progress;
  const SimulateSummary s = RunSimulation(request, progress);
  sim::Simulator simulator(request.options);
  sim::SimFrame frame;
  std::vector<sim::OdometrySample> odometry;
  int frames = 0;
  std::ifstream times(out / "truth" / "frames.csv");
  std::string line;
  std::getline(times, line);  // header
  while (simulator.Next(frame)) {
    SCOPED_TRACE("frame " + std::to_string(frame.truth.index));
    EXPECT_EQ(frame.truth.index, frames);
    std::ostringstream name;
    name << std::setw(6) << std::setfill('0') << frame.truth.index << ".png";
    const cv::Mat png = cv::imread((out / "frames" / name.str()).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(png.type(), CV_8UC1);
    ASSERT_EQ(png.size(), frame.rendered.image.size());
    EXPECT_EQ(cv::countNonZero(png != frame.rendered.image), 0);
    ASSERT_TRUE(std::getline(times, line));
    EXPECT_EQ(line.substr(0, line.find(',', line.find(',') + 1)),
              std::to_string(frame.truth.index) + "," + std::to_string(frame.truth.utime));
    odometry.insert(odometry.end(), frame.odometry.begin(), frame.odometry.end());
    ++frames;
  }
  EXPECT_EQ(frames, s.frames);
  std::ifstream csv(out / "truth" / "odometry.csv");
  std::getline(csv, line);
  for (const sim::OdometrySample& o : odometry) {
    ASSERT_TRUE(std::getline(csv, line));
    std::istringstream fields(line);
    std::string utime, left, right;
    std::getline(fields, utime, ',');
    std::getline(fields, left, ',');
    std::getline(fields, right, ',');
    EXPECT_EQ(std::stoll(utime), o.utime);
    EXPECT_EQ(std::stod(left), o.left_m_s) << line;
    EXPECT_EQ(std::stod(right), o.right_m_s) << line;
  }
  fs::remove_all(out);
}

TEST(SimOutput, ReplacesAnOldOutputOnlyWhenComplete) {
  const fs::path out = TempDir("replace");
  fs::create_directories(out);
  std::ofstream(out / "old.txt") << "previous run";
  std::ostringstream progress;
  SimulateRequest bad = ShortRun(out);
  bad.options.camera.height_m = -1.0;  // invalid: nothing may be touched
  EXPECT_THROW(RunSimulation(bad, progress), InvalidOptionsError);
  EXPECT_TRUE(fs::exists(out / "old.txt"));
  RunSimulation(ShortRun(out), progress);
  EXPECT_FALSE(fs::exists(out / "old.txt"));
  EXPECT_TRUE(fs::exists(out / "run.json"));
  // No staging folders left beside it.
  for (const auto& e : fs::directory_iterator(out.parent_path())) {
    EXPECT_EQ(e.path().filename().string().find("." + out.filename().string() + ".partial"),
              std::string::npos);
  }
  fs::remove_all(out);
}

TEST(SimOutput, UnwritableFolderIsAClearError) {
  if (::geteuid() == 0) {
    // root ignores permissions: use a path below a regular file instead.
    const fs::path file = TempDir("blocker");
    std::ofstream(file) << "x";
    std::ostringstream progress;
    try {
      RunSimulation(ShortRun(file / "out"), progress);
      FAIL() << "expected an error";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("cannot create folder"), std::string::npos) << e.what();
    }
    fs::remove_all(file);
    return;
  }
  const fs::path dir = TempDir("readonly");
  fs::create_directories(dir);
  ::chmod(dir.c_str(), 0500);
  std::ostringstream progress;
  EXPECT_THROW(RunSimulation(ShortRun(dir / "out"), progress), std::runtime_error);
  ::chmod(dir.c_str(), 0700);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace plantscale::app
