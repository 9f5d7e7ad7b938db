#include "app/sim_output.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "app/config_loader.h"

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
