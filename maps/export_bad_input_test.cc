// Bad input for exports: unknown EPSG, origin out of range, unwritable
// folder, a disk that fills. Each gives a typed error naming what and where,
// and no half-written file replaces a good one.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>

#include <fstream>

#include "maps/export.h"
#include "maps/map_errors.h"
#include "maps/test_maps.h"

namespace plantscale::maps {
namespace {

namespace fs = std::filesystem;
using testing::SyntheticMap;
using testing::TempDir;
using testing::TestAnchor;

ExportOptions Options(const GeoAnchorOptions& anchor) {
  ExportOptions o;
  o.anchor = anchor;
  return o;
}

size_t EntriesIn(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), {}));
}

std::string KeyOf(const ExportOptions& options) {
  try {
    ExportMap(SyntheticMap(), fs::temp_directory_path() / "plantscale_never_written", options);
  } catch (const InvalidOptionsError& e) {
    return e.errors().at(0).key + ": " + e.errors().at(0).reason;
  }
  return "no error";
}

TEST(ExportBadInput, UnknownEpsgNamesTheCodeAndWritesNothing) {
  EXPECT_EQ(KeyOf(Options(TestAnchor(0, 999999))).rfind("epsg: unknown EPSG code 999999", 0), 0u);
  EXPECT_FALSE(fs::exists(fs::temp_directory_path() / "plantscale_never_written"));
}

TEST(ExportBadInput, OriginOutsideTheValidRangeNamesTheKey) {
  GeoAnchorOptions a = TestAnchor();
  a.latitude_deg = -90.5;
  EXPECT_EQ(KeyOf(Options(a)), "anchor.latitude_deg: must be in [-90, 90] (got -90.5)");
  a = TestAnchor();
  a.longitude_deg = 181;
  EXPECT_EQ(KeyOf(Options(a)), "anchor.longitude_deg: must be in [-180, 180] (got 181)");
  ExportOptions none;  // no anchor but georeferenced formats
  EXPECT_EQ(KeyOf(none).rfind("anchor: georeferenced formats need an origin", 0), 0u);
  ExportOptions unknown = Options(TestAnchor());
  unknown.formats = {"gtiff", "shp"};
  EXPECT_EQ(KeyOf(unknown).rfind("formats: unknown format 'shp'", 0), 0u);
}

TEST(ExportBadInput, PngAndNativeMapNeedNoGeoreference) {
  TempDir dir;
  ExportOptions o;
  o.formats = {"png", "map"};
  EXPECT_EQ(ExportMap(SyntheticMap(), dir.path(), o).files.size(), 2u);
}

TEST(ExportBadInput, UnwritableFolderNamesThePath) {
  TempDir dir;
  std::ofstream(dir.path() / "plain_file") << "x";
  const fs::path out = dir.path() / "plain_file" / "maps";
  try {
    ExportMap(SyntheticMap(), out, Options(TestAnchor()));
    FAIL() << "expected MapIoError";
  } catch (const MapIoError& e) {
    EXPECT_NE(e.path().find("plain_file"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot create folder"), std::string::npos) << e.what();
  }
}

// Limits the size of any file this process writes (RLIMIT_FSIZE) with
// SIGXFSZ ignored, so writes past the limit fail with EFBIG like a full disk.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &old_);
    old_handler_ = signal(SIGXFSZ, SIG_IGN);
    rlimit limit = old_;
    limit.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_{};
  sighandler_t old_handler_{};
};

std::string Read(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

TEST(ExportBadInput, FullDiskFailsEachFormatAndKeepsThePreviousFiles) {
  TempDir dir;
  const CropMap map = SyntheticMap();
  const ExportResult good = ExportMap(map, dir.path(), Options(TestAnchor()));
  std::map<fs::path, std::string> before;
  for (const auto& e : fs::recursive_directory_iterator(dir.path())) {
    if (e.is_regular_file()) before[e.path()] = Read(e.path());
  }
  const rlim_t limit = 3000;  // bytes
  int failed = 0;
  for (const std::string& format : AllExportFormats()) {
    ExportOptions o = Options(TestAnchor());
    o.formats = {format};
    bool threw = false;
    {
      FileSizeLimit full(limit);
      try {
        ExportMap(map, dir.path(), o);
      } catch (const MapIoError& e) {
        threw = true;
        EXPECT_NE(std::string(e.what()).find(dir.path().string()), std::string::npos) << e.what();
      }
    }
    bool big = false;  // the format's output would not fit
    for (const auto& [path, bytes] : before) {
      const auto rel = fs::relative(path, dir.path()).string();
      const bool mine = rel.find(format == "isoxml" ? std::string("TASKDATA") : std::string(".")) !=
                        std::string::npos;
      big = big || (mine && bytes.size() > limit && good.files.size() > 0);
    }
    if (threw) ++failed;
    EXPECT_TRUE(threw || !big) << format << " wrote past a full disk without an error";
  }
  EXPECT_GE(failed, 5);  // all but the smallest outputs exceed 3 kB
  for (const auto& [path, bytes] : before) EXPECT_EQ(Read(path), bytes) << path;
  EXPECT_EQ(EntriesIn(dir.path()), 8u);  // no staging folder left behind
}

}  // namespace
}  // namespace plantscale::maps
