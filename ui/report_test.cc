// plantscale report on synthetic logs: the summary's and the agronomic
// summary's figures (gaps against plants left out of the synthetic bed), the
// pictures, byte-identical output for the same log, golden page and bed
// strip, a report without a display, and logs that are wrong (another
// program's, not LCM, empty, cut mid-event).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "review/synthetic_run.h"
#include "telemetry/log.h"
#include "ui/canvas.h"
#include "ui/golden.h"
#include "ui/report.h"

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
  o.pictures.strip_width_px = 800;
  o.pictures.trace_width_px = 600;
  o.pictures.trace_height_px = 260;
  return o;
}

// Pictures in the page and on disk, every one a readable PNG.
void ExpectPictures(const ReportResult& r, const fs::path& dir) {
  for (const std::string& p : r.pictures) {
    const cv::Mat img = cv::imread((dir / p).string());
    EXPECT_FALSE(img.empty()) << p;
    EXPECT_NE(Slurp(r.index).find("src=\"" + p + "\""), std::string::npos) << p;
  }
}

TEST(Report, SummaryPicturesAndSameBytes) {
  const fs::path dir = Fresh("report_12m");
  review::SyntheticRunOptions run;
  run.length_m = 12.0;
  review::WriteSyntheticLog(dir / "run.lcmlog", run);
  const ReportResult a = WriteReport(dir / "run.lcmlog", dir / "a", SmallReport());
  const review::RunSummary& s = a.summary;
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
  EXPECT_EQ(s.weeds_left, s.weeds_seen - s.weeds_treated - s.weeds_not_reached);
  EXPECT_EQ(s.crop_treated, 0);
  ASSERT_TRUE(s.area_treated_m2.has_value());
  EXPECT_GT(*s.area_treated_m2, 0.0);
  EXPECT_TRUE(s.faults.empty());

  // The agronomy of the synthetic bed: three full rows at 0.45 m, crops of
  // 0.01 m² (leaf-tip radius √(0.01 / (π 0.832)) = 61.8 mm), weeds of
  // 0.002 m² (disc radius 25.2 mm), 2 weeds per metre over 1.4 m.
  const review::AgronomySummary& g = a.agronomy;
  ASSERT_EQ(g.rows.size(), 3u);
  EXPECT_EQ(g.rows.front().row, -1);
  EXPECT_EQ(g.rows.back().row, 1);
  EXPECT_EQ(g.gaps, 0);
  EXPECT_EQ(g.missing, 0);
  // Each observation carries N(0, 1 cm) per axis: the median of ~27
  // neighbour spacings (sd 1.4 cm) within 8 mm (≈ 2.4 standard errors), and
  // plants per metre, n plants over (n − 1)·l̄ + l̄, within 1 %.
  for (const review::RowAgronomy& r : g.rows) {
    EXPECT_NEAR(r.plant_spacing_m, 0.45, 0.008);
    EXPECT_NEAR(r.plants_per_m, 1.0 / 0.45, 0.01 / 0.45);
  }
  EXPECT_NEAR(1e3 * g.crop_size.median_m, 61.8, 0.1);
  EXPECT_NEAR(1e3 * g.crop_size.q1_m, 61.8, 0.1);
  EXPECT_NEAR(1e3 * g.weed_size.median_m, 25.2, 0.1);
  EXPECT_NEAR(g.weeds_per_m2, 2.0 / 1.4, 0.35);  // ±25 %: ~30 weeds, Poisson-like spread in the stand
  ASSERT_TRUE(g.product_l.has_value());
  EXPECT_NEAR(*g.product_l, *s.area_treated_m2 * 1e-4 * 200.0, 1e-12);  // 200 L/ha by default
  // Broadcast: the rows' band over the stand at the same rate.
  ASSERT_TRUE(g.broadcast_product_l.has_value() && g.product_saved_fraction.has_value());
  EXPECT_NEAR(*g.broadcast_product_l, g.surveyed_area_m2 * 1e-4 * 200.0, 1e-12);
  EXPECT_NEAR(*g.product_saved_fraction, 1.0 - *s.area_treated_m2 / g.surveyed_area_m2, 1e-12);
  EXPECT_GT(*g.product_saved_fraction, 0.0);
  EXPECT_LT(*g.product_saved_fraction, 1.0);
  EXPECT_GT(g.duration_s, 12.0 / 0.5 - 1.0);  // 0.5 m/s

  ExpectPictures(a, dir / "a");
  for (const char* f : {"overview.png", "bed_1.png", "offset_trace.png", "plant_size.png", "closeup_1.png"}) {
    EXPECT_TRUE(fs::exists(dir / "a" / f)) << f;
  }
  EXPECT_TRUE(fs::exists(dir / "a" / "summary.csv"));
  EXPECT_TRUE(fs::exists(dir / "a" / "summary.json"));
  const std::string html = Slurp(a.index);
  EXPECT_NE(html.find("<th>distance</th><td>12.00 m</td>"), std::string::npos);
  EXPECT_NE(html.find("camera frame dropped"), std::string::npos);
  EXPECT_NE(html.find("magnified ×20"), std::string::npos);
  const std::string csv = Slurp(dir / "a" / "summary.csv");
  EXPECT_NE(csv.find("\nall,"), std::string::npos) << csv;
  EXPECT_NE(Slurp(dir / "a" / "summary.json").find("\"plants_per_m\""), std::string::npos);

  const ReportResult b = WriteReport(dir / "run.lcmlog", dir / "b", SmallReport());
  for (const std::string& p : a.pictures) EXPECT_EQ(Slurp(dir / "a" / p), Slurp(dir / "b" / p)) << p;
  EXPECT_EQ(Slurp(a.index), Slurp(b.index));

  EXPECT_TRUE(testing::MatchesGolden(cv::imread((dir / "a" / "bed_1.png").string()), "report_bed"));
  if (!DisplayAvailable()) return;  // the page names the camera pictures only with a display
  const fs::path golden_html = fs::path(PLANTSCALE_UI_TESTDATA) / "report_index.html";
  const char* update = std::getenv("PLANTSCALE_UPDATE_GOLDEN");
  if (update && std::string(update) == "1") fs::copy_file(a.index, golden_html, fs::copy_options::overwrite_existing);
  EXPECT_EQ(html, Slurp(golden_html)) << "index.html differs from " << golden_html;
}

TEST(Agronomy, GapsAgainstMissingPlants) {
  const fs::path dir = Fresh("report_gaps");
  review::SyntheticRunOptions run;
  run.length_m = 20.0;
  // Row 0: one plant missing at line 5 and three at lines 10–12; row 1: one at line 20.
  run.missing_crops = {{0, 5}, {0, 10}, {0, 11}, {0, 12}, {1, 20}};
  review::WriteSyntheticLog(dir / "run.lcmlog", run);
  ReportOptions o = SmallReport();
  o.agronomy.rate_l_ha = 150.0;
  const ReportResult r = WriteReport(dir / "run.lcmlog", dir / "out", o);
  const review::AgronomySummary& g = r.agronomy;
  ASSERT_EQ(g.rows.size(), 3u);
  EXPECT_EQ(g.gaps, 3);
  EXPECT_EQ(g.missing, 5);
  EXPECT_EQ(g.longest_gap, 3);
  EXPECT_EQ(g.rows[0].gaps, 0);
  EXPECT_EQ(g.rows[1].gaps, 2);
  EXPECT_EQ(g.rows[1].longest_gap, 3);
  EXPECT_NEAR(g.rows[1].longest_gap_at_m, 0.5 + 9 * 0.45, 0.04);  // the plant before the gap, ±4 sd of its noise
  EXPECT_EQ(g.rows[2].missing, 1);
  EXPECT_EQ(g.rows[1].crop + 4, g.rows[0].crop);
  ASSERT_TRUE(g.product_l.has_value());
  EXPECT_NEAR(*g.product_l, *g.area_treated_m2 * 1e-4 * 150.0, 1e-12);
  // The heat map: the cells of row 0 hold the plants of the row.
  int row0 = 0;
  for (const review::HeatCell& c : g.cells) row0 += c.row == 0 ? c.crop : 0;
  EXPECT_EQ(row0, g.rows[1].crop);
}

TEST(Agronomy, SizeQuartiles) {
  const review::SizeStats s = review::SizeStatsOf({0.05, 0.01, 0.03, 0.02, 0.04}, 0.01, 4);
  EXPECT_EQ(s.count, 5);
  EXPECT_NEAR(s.median_m, 0.03, 1e-12);
  EXPECT_NEAR(s.q1_m, 0.02, 1e-12);
  EXPECT_NEAR(s.q3_m, 0.04, 1e-12);
  EXPECT_EQ(s.histogram, (std::vector<int>{0, 1, 1, 3}));  // the last bin open-ended
  EXPECT_NEAR(review::LeafTipRadius(M_PI * 0.832 * 0.1 * 0.1, 0.832), 0.1, 1e-12);
}

// A plant record of `kind` at (x, y) of ground area `area_m2`, its id the
// next free one.
void AddRecord(std::map<int64_t, review::PlantRecord>& plants, telemetry::PlantKind kind, double x, double y,
               double area_m2) {
  const auto id = static_cast<int64_t>(plants.size());
  review::PlantRecord& r = plants[id];
  r.plant.id = id;
  r.plant.kind = kind;
  r.plant.position_m = {x, y};
  r.plant.size_m2 = area_m2;
}

// The plant figures of `plants` on rows 0.5 m apart, crop-sized weed
// records at `far_view_fraction` of the crops' radius (0: none), smaller
// ones near a gap's place at `gap_crop_fraction` (0: none).
review::AgronomySummary FiguresOnRowsHalfAMetreApart(const std::map<int64_t, review::PlantRecord>& plants, double far_view_fraction,
                                             double gap_crop_fraction = review::AgronomyOptions{}.gap_crop_fraction) {
  review::AgronomySummary a;
  a.row_spacing_m = 0.5;
  review::AgronomyOptions o;
  o.far_view_fraction = far_view_fraction;
  o.gap_crop_fraction = gap_crop_fraction;
  review::AddPlantFigures(a, plants, o);
  return a;
}

TEST(Agronomy, FarViewsOfCropsAndTheGroundSeen) {
  // Two rows 0.5 m apart, a crop of leaf-tip radius 0.1 m every 0.5 m over
  // 10 m, and weeds: a crop-sized record 0.1 m from its crop (a far view of
  // it), one as large between the rows (a weed: no crop within half a
  // spacing), one small under a canopy and four clear.
  std::map<int64_t, review::PlantRecord> plants;
  const double crop_m2 = M_PI * 0.832 * 0.1 * 0.1, big_m2 = M_PI * 0.08 * 0.08, small_m2 = M_PI * 0.01 * 0.01;
  for (int i = 0; i <= 20; ++i) {
    AddRecord(plants, telemetry::PlantKind::kCrop, 0.0, 0.5 * i, crop_m2);
    AddRecord(plants, telemetry::PlantKind::kCrop, 0.5, 0.5 * i, crop_m2);
  }
  AddRecord(plants, telemetry::PlantKind::kWeed, 0.0, 2.1, big_m2);
  AddRecord(plants, telemetry::PlantKind::kWeed, 0.25, 5.25, big_m2);
  AddRecord(plants, telemetry::PlantKind::kWeed, 0.5, 3.05, small_m2);
  for (int i = 1; i <= 4; ++i) AddRecord(plants, telemetry::PlantKind::kWeed, 0.25, i + 0.3, small_m2);
  const review::AgronomySummary a = FiguresOnRowsHalfAMetreApart(plants, review::AgronomyOptions{}.far_view_fraction);
  EXPECT_NEAR(a.surveyed_area_m2, 1.0 * 10.0, 1e-9);
  EXPECT_NEAR(a.crop_size.median_m, 0.1, 1e-9);
  EXPECT_EQ(a.far_views_of_crops, 1);
  EXPECT_EQ(a.weeds, 6);
  EXPECT_NEAR(a.weeds_per_m2, 0.6, 1e-9);
  // Unseen: 42 discs of 0.75 × 0.1 m; seen: the 5 weeds outside them.
  const double unseen_m2 = 42 * M_PI * 0.075 * 0.075;
  EXPECT_NEAR(a.unseen_canopy_m2, unseen_m2, 1e-9);
  EXPECT_NEAR(a.weeds_per_m2_seen, 5.0 / (10.0 - unseen_m2), 1e-9);
  // Off: every weed record counts.
  const review::AgronomySummary all = FiguresOnRowsHalfAMetreApart(plants, 0.0);
  EXPECT_EQ(all.far_views_of_crops, 0);
  EXPECT_EQ(all.weeds, 7);
}

TEST(Agronomy, ACropRecordedAsAWeedFillsItsGap) {
  // One row, a crop of leaf-tip radius 0.1 m every 0.5 m over 10 m, with
  // three gaps of one plant (y = 2, 5, 8) and one of two (3.5 and 4). In
  // the gap at 2 a crop-sized weed record stands 4 cm off the place (the
  // crop recorded as a weed); in the gap at 5 a small weed (a weed in a
  // gap); in the gap at 3.5–4 a crop-sized record at 4: the gap is one
  // plant shorter, at 3.5 alone.
  std::map<int64_t, review::PlantRecord> plants;
  const double crop_m2 = M_PI * 0.832 * 0.1 * 0.1, big_m2 = M_PI * 0.08 * 0.08, small_m2 = M_PI * 0.02 * 0.02;
  for (int i = 0; i <= 20; ++i) {
    const double y = 0.5 * i;
    if (y == 2.0 || y == 3.5 || y == 4.0 || y == 5.0 || y == 8.0) continue;
    AddRecord(plants, telemetry::PlantKind::kCrop, 0.0, y, crop_m2);
  }
  AddRecord(plants, telemetry::PlantKind::kWeed, 0.03, 2.03, big_m2);
  AddRecord(plants, telemetry::PlantKind::kWeed, 0.0, 5.0, small_m2);
  AddRecord(plants, telemetry::PlantKind::kWeed, -0.02, 4.04, big_m2);
  const review::AgronomySummary a = FiguresOnRowsHalfAMetreApart(plants, review::AgronomyOptions{}.far_view_fraction);
  ASSERT_EQ(a.rows.size(), 1u);
  EXPECT_EQ(a.crops_recorded_as_weeds, 2);
  EXPECT_EQ(a.weed_records_taken_as_crops.size(), 2u);  // the bed picture draws the two as crops' rings
  EXPECT_EQ(a.gaps, 3);     // 3.5, 5, 8
  EXPECT_EQ(a.missing, 3);
  EXPECT_EQ(a.longest_gap, 1);
  EXPECT_EQ(a.weeds, 1);    // the small one; the two crop-sized records are crops
  // Off (every weed record a weed): the gaps as the crop records leave them.
  const review::AgronomySummary all = FiguresOnRowsHalfAMetreApart(plants, 0.0, 0.0);
  EXPECT_EQ(all.crops_recorded_as_weeds, 0);
  EXPECT_EQ(all.gaps, 4);
  EXPECT_EQ(all.missing, 5);
  EXPECT_EQ(all.longest_gap, 2);
  EXPECT_NEAR(all.rows[0].longest_gap_at_m, 3.0, 1e-9);  // the plant before the gap
  EXPECT_EQ(all.weeds, 3);
}

TEST(Agronomy, ASmallCropBesideItsPlaceFillsItsGap) {
  // One row, a crop of leaf-tip radius 0.1 m every 0.5 m over 10 m, gaps of
  // one plant at y = 2, 5 and 8. Weed records of 0.04 m (0.4 of the crops'
  // radius, below the crop-sized 0.55): at 2, 5 cm off the place (within
  // 0.15 spacings: the small crop recorded as a weed); at 5, 12 cm off
  // (0.24 spacings: a weed in the gap); at 8, one of 0.03 m on the place
  // (0.3 of the crops' radius: a weed).
  std::map<int64_t, review::PlantRecord> plants;
  const double crop_m2 = M_PI * 0.832 * 0.1 * 0.1;
  for (int i = 0; i <= 20; ++i) {
    const double y = 0.5 * i;
    if (y == 2.0 || y == 5.0 || y == 8.0) continue;
    AddRecord(plants, telemetry::PlantKind::kCrop, 0.0, y, crop_m2);
  }
  AddRecord(plants, telemetry::PlantKind::kWeed, 0.03, 2.04, M_PI * 0.04 * 0.04);
  AddRecord(plants, telemetry::PlantKind::kWeed, 0.0, 5.12, M_PI * 0.04 * 0.04);
  AddRecord(plants, telemetry::PlantKind::kWeed, 0.0, 8.0, M_PI * 0.03 * 0.03);
  const review::AgronomySummary a = FiguresOnRowsHalfAMetreApart(plants, review::AgronomyOptions{}.far_view_fraction);
  ASSERT_EQ(a.rows.size(), 1u);
  EXPECT_EQ(a.crops_recorded_as_weeds, 1);
  EXPECT_EQ(a.gaps, 2);  // 5, 8
  EXPECT_EQ(a.missing, 2);
  EXPECT_EQ(a.weeds, 2);
  // Only crop-sized records fill a gap: all three are weeds.
  const review::AgronomySummary crop_sized_only = FiguresOnRowsHalfAMetreApart(plants, review::AgronomyOptions{}.far_view_fraction, 0.0);
  EXPECT_EQ(crop_sized_only.crops_recorded_as_weeds, 0);
  EXPECT_EQ(crop_sized_only.missing, 3);
  EXPECT_EQ(crop_sized_only.weeds, 3);
}

TEST(Report, NoDisplayStillReports) {
  const char* display = std::getenv("DISPLAY");
  const std::string saved = display ? display : "";
  unsetenv("DISPLAY");
  const fs::path dir = Fresh("report_no_display");
  review::SyntheticRunOptions run;
  run.length_m = 6.0;
  review::WriteSyntheticLog(dir / "run.lcmlog", run);
  const ReportResult r = WriteReport(dir / "run.lcmlog", dir / "out", SmallReport());
  if (!saved.empty()) setenv("DISPLAY", saved.c_str(), 1);
  EXPECT_TRUE(fs::exists(r.index));
  EXPECT_GE(r.pictures.size(), 4u);
  bool said = false;
  for (const std::string& p : r.problems) said |= p.find("no X display") != std::string::npos;
  EXPECT_TRUE(said) << "the camera views at events need a display, and the page should say they are missing";
  ExpectPictures(r, dir / "out");
}

TEST(Report, LogFromAnotherProgramSaysSo) {
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
  EXPECT_NE(Slurp(r.index).find("Problem: no plantscale messages"), std::string::npos);
}

TEST(Report, NotAnLcmLogIsAProblemNotACrash) {
  const fs::path dir = Fresh("report_garbage");
  std::ofstream(dir / "garbage.lcmlog") << "this is a text file, not an LCM log\n";
  const ReportResult r = WriteReport(dir / "garbage.lcmlog", dir / "out", SmallReport());
  ASSERT_FALSE(r.problems.empty());
  EXPECT_NE(r.problems.front().find("log"), std::string::npos) << r.problems.front();
  EXPECT_NE(Slurp(r.index).find("Problem: log:"), std::string::npos);
}

TEST(Report, EmptyLogIsAProblemNotACrash) {
  const fs::path dir = Fresh("report_empty");
  std::ofstream(dir / "empty.lcmlog").flush();
  const ReportResult r = WriteReport(dir / "empty.lcmlog", dir / "out", SmallReport());
  bool said = false;
  for (const std::string& p : r.problems) said |= p.find("no events") != std::string::npos;
  EXPECT_TRUE(said);
  EXPECT_NE(Slurp(r.index).find("Problem: log: no events"), std::string::npos);
  ExpectPictures(r, dir / "out");
}

TEST(Report, LogCutMidEventReportsWhatCameBefore) {
  const fs::path dir = Fresh("report_cut");
  review::SyntheticRunOptions run;
  run.length_m = 10.0;
  review::WriteSyntheticLog(dir / "run.lcmlog", run);
  const std::string bytes = Slurp(dir / "run.lcmlog");
  // Cut in the middle of the file: inside an event, almost surely.
  std::ofstream(dir / "cut.lcmlog", std::ios::binary) << bytes.substr(0, bytes.size() / 2 + 7);
  const ReportResult r = WriteReport(dir / "cut.lcmlog", dir / "out", SmallReport());
  ASSERT_FALSE(r.problems.empty());
  EXPECT_NE(r.problems.front().find("log:"), std::string::npos) << r.problems.front();
  // About half the run was read: 5 m ± 1 m, and its plants are summarised.
  EXPECT_NEAR(r.summary.distance_m, 5.0, 1.0);
  EXPECT_GT(r.agronomy.crop, 3 * 4 / 0.45 * 0.8);
  ExpectPictures(r, dir / "out");
}

}  // namespace
}  // namespace plantscale::ui
