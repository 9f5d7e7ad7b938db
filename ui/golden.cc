#include "ui/golden.h"

#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "ui/canvas.h"

namespace plantscale::ui::testing {

std::string OutputDir() {
  const char* dir = std::getenv("PLANTSCALE_UI_TEST_OUT");
  const std::string out = dir && dir[0] ? dir : "/tmp/plantscale_ui_test";
  std::filesystem::create_directories(out);
  return out;
}

::testing::AssertionResult MatchesGolden(const cv::Mat& image, const std::string& name, int tolerance,
                                         double max_bad_fraction) {
  WritePng(image, std::filesystem::path(OutputDir()) / (name + ".png"));
  const std::filesystem::path golden = std::filesystem::path(PLANTSCALE_UI_TESTDATA) / (name + ".png");
  const char* update = std::getenv("PLANTSCALE_UPDATE_GOLDEN");
  if (update && std::string(update) == "1") {
    WritePng(image, golden);
    return ::testing::AssertionSuccess() << "golden " << golden << " rewritten";
  }
  const cv::Mat expected = cv::imread(golden.string(), cv::IMREAD_COLOR);
  if (expected.empty()) {
    return ::testing::AssertionFailure() << "no golden " << golden
                                         << " (PLANTSCALE_UPDATE_GOLDEN=1 writes it)";
  }
  if (expected.size() != image.size()) {
    return ::testing::AssertionFailure() << "size " << image.cols << "x" << image.rows << " vs golden "
                                         << expected.cols << "x" << expected.rows;
  }
  cv::Mat diff;
  cv::absdiff(image, expected, diff);
  std::vector<cv::Mat> channels;
  cv::split(diff, channels);
  const cv::Mat worst = cv::max(channels[0], cv::max(channels[1], channels[2]));
  const int bad = cv::countNonZero(worst > tolerance);
  const double fraction = static_cast<double>(bad) / static_cast<double>(image.total());
  if (fraction <= max_bad_fraction) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << name << ": " << bad << " pixels (" << 100.0 * fraction
                                       << " %) differ by more than " << tolerance << " from " << golden
                                       << "; allowed " << 100.0 * max_bad_fraction << " %";
}

}  // namespace plantscale::ui::testing
