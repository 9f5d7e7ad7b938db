// plantscale report on synthetic logs: the summary table's figures, the
// pictures, byte-identical output for the same log, golden page and map,
// a clear error without a display, and logs that are wrong.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "telemetry/log.h"
#include "ui/canvas.h"
#include "ui/golden.h"
#include "ui/report.h"
#include "ui/synthetic_run.h"

namespace plantscale::ui {
namespace {

namespace fs = std::filesystem;

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

fs::path Fresh(const std::string& name) {
  const fs::path dir = fs::path(testing::OutputDir()) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

ReportOptions SmallReport() {
  ReportOptions o;
  o.closeup_every_m = 5.0;
  o.map_width_px = 800;
  o.map_height_px = 160;
  o.trace_width_px = 600;
  o.trace_height_px = 260;
  return o;
}

TEST(Report, SummaryPicturesAndSameBytes) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const fs::path dir = Fresh("report_12m");
  SyntheticRunOptions run;
  run.length_m = 12.0;
  WriteSyntheticLog(dir / "run.lcmlog", run);
  const ReportResult a = WriteReport(dir / "run.lcmlog", dir / "a", SmallReport());
  const RunSummary& s = a.summary;
  EXPECT_NEAR(s.distance_m, 12.0, 0.05);
  EXPECT_EQ(s.offset_source, "tracker");
  // Zig-zag of 40 mm amplitude over 1.5 periods plus 8 mm filter noise:
  // RMS ≈ √(28.3² + 8²) ≈ 29 mm.
  EXPECT_NEAR(1e3 * s.rms_offset_m, 29.0, 5.0);
  EXPECT_GE(s.rms_offset_m, std::abs(s.mean_offset_m));
  // The synthetic tracker is truth plus N(0, 8 mm): over ~300 frames the RMS
  // error is 8 mm within 1 mm (3 standard errors of 0.33 mm).
  ASSERT_TRUE(s.rms_offset_error_m.has_value());
  EXPECT_NEAR(1e3 * *s.rms_offset_error_m, 8.0, 1.0);
  EXPECT_GT(s.crop_seen, 3 * 12 / 0.45 * 0.9);  // three rows of plants at 0.45 m
  EXPECT_GT(s.weeds_seen, 10);
  EXPECT_EQ(s.weeds_treated, s.weeds_seen);  // the synthetic sprayer hits every weed
  EXPECT_EQ(s.crop_treated, 0);
  ASSERT_TRUE(s.area_treated_m2.has_value());
  EXPECT_GT(*s.area_treated_m2, 0.0);
  EXPECT_TRUE(s.faults.empty());
  EXPECT_EQ(a.pictures.size(), 5u);  // map, trace, 2 close-ups (5, 10 m), 1 camera at the warning
  for (const std::string& p : a.pictures) EXPECT_TRUE(fs::exists(dir / "a" / p)) << p;
  const std::string html = Slurp(a.index);
  EXPECT_NE(html.find("<th>distance</th><td>12.00 m</td>"), std::string::npos);
  EXPECT_NE(html.find("camera frame dropped"), std::string::npos);

  const ReportResult b = WriteReport(dir / "run.lcmlog", dir / "b", SmallReport());
  for (const std::string& p : a.pictures) EXPECT_EQ(Slurp(dir / "a" / p), Slurp(dir / "b" / p)) << p;
  EXPECT_EQ(Slurp(a.index), Slurp(b.index));

  EXPECT_TRUE(testing::MatchesGolden(cv::imread((dir / "a" / "map.png").string()), "report_map"));
  const fs::path golden_html = fs::path(PLANTSCALE_UI_TESTDATA) / "report_index.html";
  const char* update = std::getenv("PLANTSCALE_UPDATE_GOLDEN");
  if (update && std::string(update) == "1") fs::copy_file(a.index, golden_html, fs::copy_options::overwrite_existing);
  EXPECT_EQ(html, Slurp(golden_html)) << "index.html differs from " << golden_html;
}

TEST(Report, ClearErrorWithoutDisplay) {
  const char* display = std::getenv("DISPLAY");
  const std::string saved = display ? display : "";
  unsetenv("DISPLAY");
  const fs::path dir = Fresh("report_no_display");
  SyntheticRunOptions run;
  run.length_m = 1.0;
  WriteSyntheticLog(dir / "run.lcmlog", run);
  try {
    WriteReport(dir / "run.lcmlog", dir / "out");
    ADD_FAILURE() << "no DisplayError";
  } catch (const DisplayError& e) {
    EXPECT_NE(std::string(e.what()).find("xvfb-run"), std::string::npos) << e.what();
  }
  if (!saved.empty()) setenv("DISPLAY", saved.c_str(), 1);
}

TEST(Report, LogFromAnotherProgramSaysSo) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const fs::path dir = Fresh("report_foreign");
  {
    telemetry::LogWriter log(dir / "other.lcmlog");
    const std::string bytes = "not a plantscale message";
    for (int i = 0; i < 20; ++i) log.Write("POSE", bytes.data(), bytes.size(), 1000 + i * 100000);
  }
  const ReportResult r = WriteReport(dir / "other.lcmlog", dir / "out", SmallReport());
  bool said = false;
  for (const std::string& p : r.problems) said |= p.find("no plantscale messages") != std::string::npos;
  EXPECT_TRUE(said);
  EXPECT_TRUE(fs::exists(r.index));
}

TEST(Report, NotAnLcmLogIsAProblemNotACrash) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const fs::path dir = Fresh("report_garbage");
  std::ofstream(dir / "garbage.lcmlog") << "this is a text file, not an LCM log\n";
  const ReportResult r = WriteReport(dir / "garbage.lcmlog", dir / "out", SmallReport());
  ASSERT_FALSE(r.problems.empty());
  EXPECT_NE(r.problems.front().find("log"), std::string::npos) << r.problems.front();
}

}  // namespace
}  // namespace plantscale::ui
