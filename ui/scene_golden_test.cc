// Golden images of each scene piece, with pixel checks that mean something:
// predicted rows where the grid says, blobs and grid in the camera view where
// the camera model projects them, a red HUD on a lost link.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/geometry/grid_model.h"
#include "review/log_timeline.h"
#include "review/synthetic_run.h"
#include "review/test_util.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"
#include "ui/camera_view.h"
#include "ui/canvas.h"
#include "ui/golden.h"
#include "ui/hud.h"
#include "ui/map_layer.h"
#include "ui/map_view.h"
#include "ui/offset_trace.h"
#include "ui/palette.h"

#include <vtkPropCollection.h>
#include <vtkNew.h>

namespace plantscale::ui {
namespace {

using testing::MatchesGolden;
using review::testing::RunUpTo;

bool IsRowYellow(const cv::Vec3b& bgr) { return bgr[2] > 200 && bgr[1] > 170 && bgr[0] < 90; }

// Renders a map view of `model` with only `layers` visible.
cv::Mat RenderMap(const review::RunModel& model, std::initializer_list<MapLayerId> layers, int w = 400,
                  int h = 300, std::optional<FieldWindow> window = std::nullopt) {
  Canvas canvas(w, h);
  MapView view;
  view.AddTo(canvas.AddRenderer(0, 0, 1, 1, palette::kBackground));
  for (MapLayerId id : {MapLayerId::kMap, MapLayerId::kPlants, MapLayerId::kGrid, MapLayerId::kEllipses,
                        MapLayerId::kVehicle}) {
    view.SetVisible(id, std::find(layers.begin(), layers.end(), id) != layers.end());
  }
  view.SetWindow(window);
  view.Update(model);
  return canvas.Render();
}

// Issue 36: seeking back in a log left map tiles from later on screen. The
// map after seeking back to 10 s must be the map of a forward pass to 10 s.
TEST(MapLayer, SeekBackShowsTheMapAsItWasThen) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions run;
  run.length_m = 20.0;
  review::LogTimeline sought(review::SyntheticRun(run), "");
  vtkNew<vtkRenderer> renderer_sought, renderer_forward;
  MapLayer back, forward;
  back.AddTo(renderer_sought);
  forward.AddTo(renderer_forward);
  const FieldWindow whole{-5.0, 30.0, 0.0};
  sought.Seek(35.0);
  back.Update(sought.model(), whole);
  const int actors_at_35s = renderer_sought->GetViewProps()->GetNumberOfItems();
  sought.Seek(10.0);
  back.Update(sought.model(), whole);
  review::LogTimeline fresh(review::SyntheticRun(run), "");
  fresh.Seek(10.0);
  forward.Update(fresh.model(), whole);
  double b[4], f[4];
  ASSERT_TRUE(back.Bounds(b));
  ASSERT_TRUE(forward.Bounds(f));
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(b[i], f[i], 1e-9) << i;  // the same tiles, exactly
  EXPECT_LT(renderer_sought->GetViewProps()->GetNumberOfItems(), actors_at_35s);
  EXPECT_EQ(renderer_sought->GetViewProps()->GetNumberOfItems(), renderer_forward->GetViewProps()->GetNumberOfItems());
}

TEST(SceneGolden, MapLayerShowsCropWeedSoilTreated) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const review::LogTimeline run = RunUpTo({}, 12.0);
  const cv::Mat image = RenderMap(run.model(), {MapLayerId::kMap});
  EXPECT_TRUE(MatchesGolden(image, "map_layer"));
}

// The follow camera puts field x = 0 on the middle image row and shows
// 6 m across 400 px (66.7 px/m), field −x up: row n's line is at image row
// 150 + x_n · 66.7 where x_n = n r̄ − t_x / cos ψ ≈ n · 0.475 m + vehicle x.
TEST(SceneGolden, GridOverlayRowsAtExpectedImageRows) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const review::LogTimeline run = RunUpTo({}, 12.0);
  const cv::Mat image = RenderMap(run.model(), {MapLayerId::kGrid, MapLayerId::kVehicle});
  EXPECT_TRUE(MatchesGolden(image, "grid_overlay"));
  const auto& grid = *run.model().grid();
  const auto pose = *run.model().pose();
  const double ppm = 400.0 / 6.0;
  const int column = 200;  // 1.5 m ahead of the vehicle: inside the drawn lines
  for (int n = -1; n <= 1; ++n) {
    const auto line = GridRowLines(grid, pose, {})[static_cast<size_t>(n + 1)];
    const double x = 0.5 * (line.front().x() + line.back().x());
    const int expected = static_cast<int>(std::lround(150.0 + x * ppm));
    int found = -1000;
    for (int r = expected - 6; r <= expected + 6; ++r) {
      if (IsRowYellow(image.at<cv::Vec3b>(r, column)) && std::abs(r - expected) < std::abs(found - expected)) found = r;
    }
    EXPECT_NEAR(found, expected, 3) << "row " << n << " (tolerance 3 px = 4.5 cm)";
    EXPECT_NEAR(x, n * 0.475 + pose.x_m, 0.05) << "row " << n << " near its planted line";
  }
}

TEST(SceneGolden, EllipsesCloseUp) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const review::LogTimeline run = RunUpTo({}, 12.0);
  const double y = run.model().pose()->y_m;
  const cv::Mat image = RenderMap(run.model(), {MapLayerId::kEllipses, MapLayerId::kPlants, MapLayerId::kVehicle},
                                  400, 300, FieldWindow{y - 0.5, y + 2.5, 0.0});
  EXPECT_TRUE(MatchesGolden(image, "ellipses"));
}

TEST(SceneGolden, OffsetTraceChart) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const review::LogTimeline run = RunUpTo({}, 20.0);
  Canvas canvas(400, 300);
  OffsetTrace trace;
  trace.AddTo(canvas.AddRenderer(0, 0, 1, 1, {1, 1, 1}));
  trace.Update(run.model());
  EXPECT_TRUE(MatchesGolden(canvas.Render(), "offset_trace"));
}

// At 2.5 km along the bed the chart drew the ±2σ bands metres behind their
// lines (VTK's area and line plots took kilometre-scale distances apart):
// a sine offset of ±40 mm with a ±6 mm band over 2,450–2,470 m, the line
// must lie within its band in the columns where both are drawn.
TEST(SceneGolden, OffsetTraceLineWithinItsBandAtKilometres) {
  PLANTSCALE_REQUIRE_DISPLAY();
  namespace tm = telemetry;
  tm::Subscriber sub;
  review::RunModel model;
  model.Follow(sub);
  for (int i = 0; i <= 400; ++i) {
    const double d = 2450.0 + 0.05 * i;
    const int64_t utime = 1'000'000 + 80'000 * static_cast<int64_t>(i);
    plantscale_odometry_t odo{};
    odo.utime = utime;
    odo.distance_m = d;
    odo.valid = 1;
    const tm::Bytes o = tm::Encode(odo);
    sub.Feed(tm::channels::kOdometry, o.data(), o.size(), utime);
    tm::GridEstimate g;
    g.utime = utime;
    g.mode = tm::FilterMode::kTracking;
    g.state.offset_m = 0.04 * std::sin(2.0 * std::numbers::pi * d / 8.0);
    g.covariance(0, 0) = 0.003 * 0.003;
    g.state.bearing_rad = 0.02 * std::cos(2.0 * std::numbers::pi * d / 5.0);
    g.covariance(2, 2) = 0.001 * 0.001;
    const tm::Bytes b = tm::Encode(tm::ToLcm(g));
    sub.Feed(tm::channels::kGrid, b.data(), b.size(), utime);
  }
  Canvas canvas(400, 300);
  OffsetTrace trace;
  trace.AddTo(canvas.AddRenderer(0, 0, 1, 1, {1, 1, 1}));
  trace.Update(model);
  const cv::Mat image = canvas.Render();  // BGR
  int both = 0, within = 0;
  for (int x = 45; x < 250; ++x) {
    int line = -1, band_lo = image.rows, band_hi = -1;
    for (int y = 0; y < image.rows; ++y) {
      const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
      const bool solid = std::abs(p[2] - 30) < 25 && std::abs(p[1] - 110) < 25 && p[0] > 190;
      const bool light = p[2] > 150 && p[2] < 235 && p[1] > 180 && p[0] > 235;
      if (solid && line < 0) line = y;
      if (light) band_lo = std::min(band_lo, y), band_hi = std::max(band_hi, y);
    }
    if (line < 0 || band_hi < 0) continue;
    ++both;
    if (line >= band_lo - 2 && line <= band_hi + 2) ++within;
  }
  ASSERT_GT(both, 100);
  EXPECT_GT(within, 0.9 * both) << within << " of " << both << " columns";
}

TEST(SceneGolden, CameraViewGridAtProjectedColumns) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const review::LogTimeline run = RunUpTo({}, 12.0);
  Canvas canvas(320, 240);
  CameraView view;
  view.AddTo(canvas.AddRenderer(0, 0, 1, 1, palette::kBackground));
  view.Update(run.model());
  const cv::Mat image = canvas.Render();
  EXPECT_TRUE(MatchesGolden(image, "camera_view"));
  // Thumbnail 160×120 shown in 320×240: 2 screen px per thumbnail px, 0.5 per source px.
  const geometry::GridModel model(geometry::CameraModel({}), {});
  int checked = 0;
  for (const geometry::GridPlant& p : model.PlantsInView(run.model().grid()->state)) {
    const int u = static_cast<int>(std::lround(0.5 * p.image_px.x()));
    const int v = static_cast<int>(std::lround(0.5 * p.image_px.y()));
    if (u < 4 || v < 4 || u > 315 || v > 235) continue;
    bool yellow = false;
    for (int dv = -2; dv <= 2; ++dv) {
      for (int du = -2; du <= 2; ++du) yellow |= IsRowYellow(image.at<cv::Vec3b>(v + dv, u + du));
    }
    EXPECT_TRUE(yellow) << "grid plant (m " << p.m << ", n " << p.n << ") not drawn at (" << u << ", " << v << ")";
    ++checked;
  }
  EXPECT_GE(checked, 6);
}

cv::Mat RenderHud(const review::RunModel& model, int64_t now) {
  Canvas canvas(400, 60);
  Hud hud;
  hud.AddTo(canvas.AddRenderer(0, 0, 1, 1, palette::kHudOk));
  hud.Update(model, now);
  return canvas.Render();
}

TEST(SceneGolden, HudGreenWhileHeartbeatArrives) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const review::LogTimeline run = RunUpTo({}, 6.0);
  const cv::Mat image = RenderHud(run.model(), run.now_utime());
  EXPECT_TRUE(MatchesGolden(image, "hud_ok"));
  const cv::Vec3b corner = image.at<cv::Vec3b>(58, 398);
  EXPECT_NEAR(corner[1], 255 * palette::kHudOk.g, 2);
  EXPECT_LT(corner[2], 60);
}

TEST(SceneGolden, HudRedAtOnceOnLostLink) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions o;
  o.heartbeat_stops_at_s = 3.0;
  const review::LogTimeline run = RunUpTo(o, 6.0);
  const cv::Mat image = RenderHud(run.model(), run.now_utime());
  EXPECT_TRUE(MatchesGolden(image, "hud_lost"));
  const cv::Vec3b corner = image.at<cv::Vec3b>(58, 398);  // background, below the text
  EXPECT_GT(corner[2], 190);  // red ≥ 0.75
  EXPECT_LT(corner[1], 30);
  EXPECT_LT(corner[0], 30);
}

TEST(SceneGolden, NozzleBar) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const review::LogTimeline run = RunUpTo({}, 12.0);
  Canvas canvas(400, 60);
  NozzleBarView bar;
  bar.AddTo(canvas.AddRenderer(0, 0, 1, 1, {0.12, 0.12, 0.13}));
  bar.Update(run.model(), run.now_utime());
  EXPECT_TRUE(MatchesGolden(canvas.Render(), "nozzle_bar"));
}

}  // namespace
}  // namespace plantscale::ui
