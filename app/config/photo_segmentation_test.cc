#include "app/config/photo_segmentation.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "engine/common/options.h"

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;

fs::path TempFile(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("plantscale_photo_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

void WriteBytes(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary) << bytes;
}

size_t OpenDescriptors() {
  return static_cast<size_t>(std::distance(fs::directory_iterator("/proc/self/fd"),
                                           fs::directory_iterator()));
}

std::string ErrorOf(const fs::path& p) {
  try {
    (void)ReadImage(p);
  } catch (const DataError& e) {
    return e.what();
  }
  return "";
}

// A Radiance HDR header with no FORMAT line, named .png (segment_fuzz's
// leak-hdr-bad-header-keeps-file-open): OpenCV's reader left the file open on
// each such file. Refused by its first bytes, before any decoder runs.
TEST(ReadImage, RefusesWhatIsNeitherPngNorJpegWithoutKeepingItOpen) {
  const fs::path p = TempFile("radiance.png");
  WriteBytes(p, std::string("#?RADIANCE\n-Y 2 +X 2\n") + std::string(32, '\x01'));
  const size_t before = OpenDescriptors();
  for (int i = 0; i < 20; ++i) {
    EXPECT_NE(ErrorOf(p).find("not a PNG or JPEG"), std::string::npos) << ErrorOf(p);
  }
  EXPECT_EQ(OpenDescriptors(), before);
  WriteBytes(p, std::string("BM\x3e\0\0\0", 6));  // a BMP header
  EXPECT_NE(ErrorOf(p).find("not a PNG or JPEG"), std::string::npos) << ErrorOf(p);
}

// The content decides, not the name: a PNG named .jpg reads; a JPEG cut
// short (no end-of-image marker) is refused under either name.
TEST(ReadImage, TakesTheFormatFromTheBytesNotTheName) {
  const cv::Mat image(6, 8, CV_8UC3, cv::Scalar(10, 200, 30));
  std::vector<uchar> png;
  std::vector<uchar> jpeg;
  ASSERT_TRUE(cv::imencode(".png", image, png));
  ASSERT_TRUE(cv::imencode(".jpg", image, jpeg));
  const fs::path as_jpg = TempFile("png.jpg");
  WriteBytes(as_jpg, std::string(png.begin(), png.end()));
  const cv::Mat read = ReadImage(as_jpg);
  EXPECT_EQ(read.size(), image.size());
  EXPECT_EQ(cv::norm(read, image, cv::NORM_INF), 0.0);
  const fs::path cut = TempFile("cut.png");
  WriteBytes(cut, std::string(jpeg.begin(), jpeg.end() - 10));
  EXPECT_NE(ErrorOf(cut).find("truncated JPEG"), std::string::npos) << ErrorOf(cut);
}

}  // namespace
}  // namespace plantscale::app
