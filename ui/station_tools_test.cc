// What the station draws for its keys and tools, asserted on pixels: the
// covariance ellipses appear and go with `l`, grow with `x`; the picked
// plant is ringed and the measured line drawn, and a seek clears both; the
// key list on `h`; zoom and pan; the legend and scale bar; review of a whole
// finished run; the far view of a long bed drawn in blocks; a log streamed
// from its file gives the model held in memory.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <tuple>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "review/synthetic_run.h"
#include "ui/golden.h"
#include "ui/map_annotations.h"
#include "ui/palette.h"
#include "ui/station_controller.h"

namespace plantscale::ui {
namespace {

namespace fs = std::filesystem;

// Pixels of `colour` (±12 per channel) in rows [r0, r1) of a BGR image.
int PixelsOf(const cv::Mat& image, Rgb colour, int r0 = 0, int r1 = -1) {
  const cv::Vec3b want(static_cast<uchar>(std::lround(colour.b * 255)), static_cast<uchar>(std::lround(colour.g * 255)),
                       static_cast<uchar>(std::lround(colour.r * 255)));
  int n = 0;
  for (int r = r0; r < (r1 < 0 ? image.rows : r1); ++r) {
    for (int c = 0; c < image.cols; ++c) {
      const cv::Vec3b p = image.at<cv::Vec3b>(r, c);
      n += std::abs(p[0] - want[0]) <= 12 && std::abs(p[1] - want[1]) <= 12 && std::abs(p[2] - want[2]) <= 12;
    }
  }
  return n;
}

fs::path Log(const std::string& name, const review::SyntheticRunOptions& o) {
  const fs::path p = fs::path(testing::OutputDir()) / (name + ".lcmlog");
  review::WriteSyntheticLog(p, o);
  return p;
}

class StationTools : public ::testing::Test {
 protected:
  void Open(std::unique_ptr<Source> source) {
    options_.width_px = 640, options_.height_px = 360;
    source_ = std::move(source);
    canvas_ = std::make_unique<Canvas>(options_.width_px, options_.height_px);
    scene_ = std::make_unique<StationScene>(*canvas_, options_);
    controller_ = std::make_unique<StationController>(*canvas_, *scene_, *source_, options_);
  }
  void SetUp() override {
    if (!DisplayAvailable()) GTEST_SKIP() << "no DISPLAY: VTK renders through GLX; run under xvfb-run -a";
    auto log = std::make_unique<LogSource>(Log("tools", {}), 1.0);
    log->Seek(12.0, /*relative=*/true);
    log->TogglePause();
    Open(std::move(log));
    controller_->Frame(0.0);
  }
  cv::Mat Draw() {
    controller_->Frame(0.0);
    return canvas_->Render();
  }
  // The map's rows of the image (its viewport spans 8 % to 54 % from the top).
  int MapPixels(const cv::Mat& image, Rgb colour) {
    return PixelsOf(image, colour, static_cast<int>(0.08 * image.rows) + 1, static_cast<int>(0.54 * image.rows));
  }
  void ClickAt(const Eigen::Vector2d& field) {
    const Eigen::Vector2d d = scene_->map().DisplayAtField(field);
    controller_->Click(static_cast<int>(std::lround(d.x())), static_cast<int>(std::lround(d.y())));
  }
  const review::PlantRecord& PlantInView() {
    const double y = source_->model().pose()->y_m;
    for (const auto& [id, r] : source_->model().plants()) {
      // The middle row: clear of the legend along the map's top.
      if (std::abs(r.plant.position_m.y() - (y + 1.0)) < 0.5 && std::abs(r.plant.position_m.x()) < 0.2 &&
          r.plant.kind == telemetry::PlantKind::kCrop) {
        return r;
      }
    }
    return source_->model().plants().begin()->second;
  }

  StationOptions options_;
  std::unique_ptr<Source> source_;
  std::unique_ptr<Canvas> canvas_;
  std::unique_ptr<StationScene> scene_;
  std::unique_ptr<StationController> controller_;
};

TEST_F(StationTools, EllipsesShowGoWithLAndGrowWithX) {
  const Rgb white = palette::kPlantEllipse;
  const int with = MapPixels(Draw(), white);
  controller_->Key("l");
  const int without = MapPixels(Draw(), white);
  // The legend's white swatch and scale bar stay; the ellipses (×20) are hundreds of pixels.
  EXPECT_GT(with, without + 300) << "with " << with << ", without " << without;
  controller_->Key("l");
  controller_->Key("x");  // ×20 → ×50
  EXPECT_EQ(scene_->map().ellipses().params().magnification, 50.0);
  const cv::Mat x50 = Draw();
  controller_->Key("x");  // → ×1: a 7 mm ellipse under its plant's marker
  const int x1 = MapPixels(Draw(), white);
  EXPECT_LT(x1, with / 2) << "x1 " << x1 << ", x20 " << with;
  EXPECT_GT(cv::norm(x50, Draw(), cv::NORM_L1), 0.0);
}

TEST_F(StationTools, PickIsRingedMeasureIsDrawnSeekClearsBoth) {
  const int legend = MapPixels(Draw(), palette::kPick);  // the legend's swatch only
  EXPECT_LE(legend, 121);
  const review::PlantRecord& plant = PlantInView();
  ClickAt(plant.plant.position_m);
  ASSERT_EQ(controller_->picked(), plant.plant.id) << controller_->tool_text();
  cv::Mat image = Draw();
  cv::imwrite(testing::OutputDir() + "/station_pick.png", image);
  // The ring is 24 px across, 3 px wide: about π·24·3 ≈ 200 pixels (legend swatch 100 more).
  const int ringed = MapPixels(image, palette::kPick);
  EXPECT_GT(ringed, legend + 150);
  // Whole cm² and mm in the record, no three-decimal numbers.
  EXPECT_EQ(controller_->tool_text().find(".000"), std::string::npos) << controller_->tool_text();
  controller_->Key("Right");  // seek 5 s on
  EXPECT_EQ(controller_->tool_text(), "");
  EXPECT_FALSE(controller_->picked().has_value());
  EXPECT_LE(MapPixels(Draw(), palette::kPick), legend + 5);

  controller_->Key("r");
  const Eigen::Vector2d a(0.3, source_->model().pose()->y_m - 0.5), b = a + Eigen::Vector2d(-0.6, 2.5);
  ClickAt(a);
  ClickAt(b);
  const std::string& text = controller_->tool_text();
  ASSERT_EQ(text.rfind("distance ", 0), 0u) << text;
  EXPECT_NEAR(std::stod(text.substr(9)), (b - a).norm(), 0.02) << text << " (a pixel is 9.4 mm)";
  image = Draw();
  cv::imwrite(testing::OutputDir() + "/station_measure.png", image);
  // The line's middle pixel is orange (3 px wide: within 2 px of it).
  const Eigen::Vector2d mid = scene_->map().DisplayAtField(0.5 * (a + b));
  int near = 0;
  for (int dr = -2; dr <= 2; ++dr) {
    for (int dc = -2; dc <= 2; ++dc) {
      const cv::Mat px = image(cv::Rect(static_cast<int>(mid.x()) + dc, image.rows - 1 - static_cast<int>(mid.y()) + dr, 1, 1));
      near += PixelsOf(px, palette::kPick);
    }
  }
  EXPECT_GT(near, 2);
  controller_->Key("Home");
  EXPECT_EQ(controller_->tool_text(), "");
  EXPECT_LE(MapPixels(Draw(), palette::kPick), legend + 5);
}

TEST_F(StationTools, HelpKeyShowsTheKeys) {
  const cv::Mat before = Draw();
  controller_->Key("h");
  EXPECT_TRUE(scene_->annotations().help_visible());
  const cv::Mat help = Draw();
  cv::imwrite(testing::OutputDir() + "/station_help.png", help);
  // The key list covers much of the map: many pixels change.
  cv::Mat diff;
  cv::absdiff(before, help, diff);
  cv::cvtColor(diff, diff, cv::COLOR_BGR2GRAY);
  EXPECT_GT(cv::countNonZero(diff > 40), 640 * 360 / 20);
  controller_->Key("question");
  EXPECT_FALSE(scene_->annotations().help_visible());
  EXPECT_NE(StationKeysHelp().find("Up/Down zoom"), std::string::npos);
}

TEST_F(StationTools, ZoomAndPan) {
  Draw();
  const double mpp = scene_->map().metres_per_pixel();
  controller_->Key("Up");
  Draw();
  EXPECT_NEAR(scene_->map().metres_per_pixel(), mpp / 1.5, 0.02 * mpp);
  EXPECT_TRUE(scene_->map().following());
  controller_->Key("bracketright");  // half a view ahead: following stops
  Draw();
  EXPECT_FALSE(scene_->map().following());
  const FieldWindow v = scene_->map().view();
  // The wheel zooms about the pointer: the field point under it stays put.
  const Eigen::Vector2d at(0.0, v.y0_m + 0.25 * (v.y1_m - v.y0_m));
  const Eigen::Vector2d px = scene_->map().DisplayAtField(at);
  controller_->Wheel(static_cast<int>(px.x()), static_cast<int>(px.y()), 2);
  Draw();
  EXPECT_NEAR(scene_->map().FieldAtDisplay(px.x(), px.y()).y(), at.y(), 2.0 * scene_->map().metres_per_pixel());
  EXPECT_NEAR(scene_->map().view().y1_m - scene_->map().view().y0_m, (v.y1_m - v.y0_m) / (1.25 * 1.25), 1e-6);
  // A drag of 100 px to the left moves the view ahead by 100 px of ground.
  const double step = scene_->map().metres_per_pixel() * 100.0, y0 = scene_->map().view().y0_m;
  controller_->DragStart(400, static_cast<int>(px.y()));
  controller_->DragTo(300, static_cast<int>(px.y()));
  controller_->DragEnd();
  Draw();
  EXPECT_NEAR(scene_->map().view().y0_m - y0, step, 0.02 * step);
  controller_->Key("f");  // free → following again
  Draw();
  EXPECT_TRUE(scene_->map().following());
}

// Without a pose covariance the vehicle's ellipse is the tracker's offset
// (across) and forward (along) covariance turned into the field frame.
TEST(VehicleEllipse, TrackerCovarianceTurnedByTheHeading) {
  review::RunModel model;
  telemetry::Pose pose{0.3, 5.0, 0.5 * M_PI, Eigen::Matrix3d::Zero()};
  EXPECT_FALSE(VehicleCovariance(model, pose).has_value());
  review::SyntheticRunOptions o;
  o.length_m = 2.0;
  review::LogTimeline run(review::SyntheticRun(o), "");
  run.Seek(3.0);
  ASSERT_TRUE(run.model().grid().has_value());
  const Eigen::Matrix2d c = run.model().grid()->covariance.topLeftCorner<2, 2>();
  const std::optional<Eigen::Matrix2d> turned = VehicleCovariance(run.model(), pose);
  ASSERT_TRUE(turned.has_value());
  // A quarter turn swaps the axes and flips the cross term.
  EXPECT_NEAR((*turned)(0, 0), c(1, 1), 1e-15);
  EXPECT_NEAR((*turned)(1, 1), c(0, 0), 1e-15);
  EXPECT_NEAR((*turned)(0, 1), -c(0, 1), 1e-15);
  pose.covariance(0, 0) = 4e-4, pose.covariance(1, 1) = 1e-4;
  EXPECT_NEAR((*VehicleCovariance(run.model(), pose))(0, 0), 4e-4, 1e-18) << "the pose's own comes first";
}

TEST(MapAnnotations, ScaleLengthsAreRound) {
  EXPECT_DOUBLE_EQ(RoundScaleLength(0.74), 0.5);
  EXPECT_DOUBLE_EQ(RoundScaleLength(1.9), 1.0);
  EXPECT_DOUBLE_EQ(RoundScaleLength(2.0), 2.0);
  EXPECT_DOUBLE_EQ(RoundScaleLength(480.0), 200.0);
  EXPECT_EQ(LengthText(0.5), "50 cm");
  EXPECT_EQ(LengthText(2000.0), "2 km");
}

// The review of a finished log: the whole bed framed, a click on the bottom
// bar goes to that metre, a plant's record by a click.
TEST(StationReview, WholeRunThenAnyMetre) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions o;
  o.length_m = 30.0;
  const review::ReviewRun run = review::LoadReviewRun(Log("review", o));
  ASSERT_FALSE(run.empty);
  EXPECT_TRUE(run.error.empty());
  StationOptions options;
  options.width_px = 640, options.height_px = 360;
  Canvas canvas(options.width_px, options.height_px);
  StationScene scene(canvas, options);
  ReviewSource source(run.model, "review.lcmlog");
  StationController controller(canvas, scene, source, options);
  controller.Frame(0.0);
  const FieldWindow whole = scene.map().view();
  EXPECT_LT(whole.y0_m, 0.6);
  EXPECT_GT(whole.y1_m, 29.0);
  const cv::Mat overview = canvas.Render();
  cv::imwrite(testing::OutputDir() + "/station_review.png", overview);
  EXPECT_GT(PixelsOf(overview, palette::kCrop, 30, 190), 200) << "the bed's crop cells are seen";
  // The bottom bar is the bed's weed strip (soil brown to weed red by weeds
  // per metre): many shades, not one bar colour; the view marked white.
  int soil = 0, weedy = 0, marked = 0;
  for (int c = 0; c < overview.cols; ++c) {
    const cv::Vec3b p = overview.at<cv::Vec3b>(overview.rows - 2, c);  // below the view's mark
    soil += PixelsOf(overview(cv::Rect(c, overview.rows - 2, 1, 1)), palette::kSoil);
    weedy += p[2] > p[1] + 100;  // red well above green: a column with weeds
    const cv::Vec3b m = overview.at<cv::Vec3b>(overview.rows - 6, c);  // the bar's middle row
    marked += m[0] > 240 && m[1] > 240 && m[2] > 240;
  }
  EXPECT_GT(soil, 50) << "columns without weeds";
  EXPECT_GT(weedy, 50) << "columns with weeds";
  EXPECT_GT(marked, 400) << "the whole bed is in view (the bar's words cover some of it)";
  controller.Click(320, 3);  // the middle of the bottom bar
  controller.Frame(0.0);
  const FieldWindow at = scene.map().view();
  EXPECT_NEAR(0.5 * (at.y0_m + at.y1_m), 0.5 * (whole.y0_m + whole.y1_m), 0.2);
  EXPECT_LT(at.y1_m - at.y0_m, 21.0);
  const review::PlantRecord& plant = std::next(run.model->plants().begin(), static_cast<long>(run.model->plants().size() / 2))->second;
  scene.map().SetWindow(FieldWindow{plant.plant.position_m.y() - 3, plant.plant.position_m.y() + 3, 0.0});
  controller.Frame(0.0);
  const Eigen::Vector2d px = scene.map().DisplayAtField(plant.plant.position_m);
  controller.Click(static_cast<int>(std::lround(px.x())), static_cast<int>(std::lround(px.y())));
  EXPECT_EQ(controller.picked(), plant.plant.id) << controller.tool_text();
  EXPECT_NE(controller.tool_text().find("sprayed"), std::string::npos);
}

// The whole run's bed map alone (plants, grid, ellipses and vehicle
// hidden), as the view of the whole run draws it.
cv::Mat RenderWholeRunMap(review::LogTimeline& run, Canvas& canvas, MapView& view) {
  view.AddTo(canvas.AddRenderer(0, 0, 1, 1, palette::kBackground));
  for (MapLayerId id : {MapLayerId::kPlants, MapLayerId::kGrid, MapLayerId::kEllipses, MapLayerId::kVehicle}) {
    view.SetVisible(id, false);
  }
  view.SetWindow(view.WholeRun(run.model()));
  view.Update(run.model());
  return canvas.Render();
}

// A long bed seen whole is drawn in 25 m blocks, not a tile actor each, and
// its weeds still show.
TEST(MapLayerLevels, FarViewDrawsBlocks) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions o;
  o.length_m = 200.0;
  review::LogTimeline run(review::SyntheticRun(o), "");
  run.Seek(run.duration_s());
  Canvas canvas(800, 200);
  MapView view;
  const cv::Mat far = RenderWholeRunMap(run, canvas, view);
  cv::imwrite(testing::OutputDir() + "/map_far.png", far);
  const int tiles = static_cast<int>(run.model().tiles().size());
  EXPECT_GT(tiles, 100);
  // The bed, 1.6 m across, is a few pixels high at 0.25 m a pixel: a weed
  // cell wins its block cell, so weed patches stay seen; the soil runs the
  // whole width.
  EXPECT_GT(PixelsOf(far, palette::kWeed), 50);
  EXPECT_GT(PixelsOf(far, palette::kSoil), 700);
  EXPECT_LE(view.map_layer().actors(), 10) << "200 m in 25 m blocks";
  view.SetWindow(FieldWindow{100.0, 106.0, 0.0});
  view.Update(run.model());
  const cv::Mat close = canvas.Render();
  EXPECT_GT(PixelsOf(close, palette::kCrop), 2000);
  // 6 m in view, drawn from 6 m before to 6 m after it: 18 m in chunks of
  // six 1.28 m tile rows (7.68 m), one image each.
  EXPECT_GE(view.map_layer().actors(), 3) << "chunks near the view";
  EXPECT_LE(view.map_layer().actors(), 4) << "chunks near the view";
}

// A view of kilometres draws the bed in 250 m blocks of 16 cm cells, a
// handful of images (VTK's cost is per image), weeds and soil still seen.
TEST(MapLayerLevels, KilometreViewDrawsCoarseBlocks) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions o;
  o.length_m = 700.0;
  o.speed_m_s = 4.0, o.frame_rate_hz = 4.0;  // fewer messages, the same bed
  review::LogTimeline run(review::SyntheticRun(o), "");
  run.Seek(run.duration_s());
  Canvas canvas(800, 200);
  MapView view;
  const cv::Mat far = RenderWholeRunMap(run, canvas, view);
  cv::imwrite(testing::OutputDir() + "/map_coarse.png", far);
  EXPECT_LE(view.map_layer().actors(), 3) << "700 m in 250 m blocks";
  // 0.9 m a pixel, the bed a line one or two pixels high: weeds in it, soil
  // most of its 800 pixels' length.
  EXPECT_GT(PixelsOf(far, palette::kWeed), 50);
  EXPECT_GT(PixelsOf(far, palette::kSoil), 400);
}

// The vehicle sends a tile row once its spray bar has passed it, and its
// bed frame drifts from the pose drawn: on the field preset the newest map
// row trails the vehicle by 1.0 m at 100 m and 3.1 m at 4.75 km, beyond the
// 1.5 m the view used to show behind it (no map cells at 2.6 km). Following
// the vehicle, at least 0.5 m of map stays in view over a whole tile row's
// cycle, and the vehicle stays in view.
TEST(MapViewFollow, DrawsTheMapThatTrailsTheVehicle) {
  PLANTSCALE_REQUIRE_DISPLAY();
  for (const double lag : {1.0, 2.0, 3.1}) {
    review::SyntheticRunOptions o;
    o.length_m = 30.0;
    o.map_lag_m = lag;
    review::LogTimeline run(review::SyntheticRun(o), "");
    run.Seek(50.0);  // 25 m at 0.5 m/s
    Canvas canvas(640, 200);
    MapView view;
    view.AddTo(canvas.AddRenderer(0, 0, 1, 1, palette::kBackground));
    for (MapLayerId id : {MapLayerId::kPlants, MapLayerId::kGrid, MapLayerId::kEllipses, MapLayerId::kVehicle}) {
      view.SetVisible(id, false);
    }
    int fewest = 1 << 30;
    for (int frame = 0; frame < 30; ++frame) {  // 1.5 m driven: more than a 1.28 m tile row
      run.Advance(0.1);
      view.Update(run.model());
      const cv::Mat image = canvas.Render();
      fewest = std::min(fewest, PixelsOf(image, palette::kSoil) + PixelsOf(image, palette::kCrop));
      const double y = run.model().pose()->y_m;
      EXPECT_GT(y, view.view().y0_m + 0.25) << lag;
      EXPECT_LT(y, view.view().y1_m - 0.25) << lag;
    }
    // 0.5 m of the 6 m view's 640 pixels, the bed's 1.6 m of 1.88 m across 200.
    EXPECT_GT(fewest, 0.5 / 6.0 * 640 * 0.85 * 200 * 0.8) << "lag " << lag << " m";
  }
}

TEST(LogTimelineStream, FileGivesTheModelOfMemory) {
  review::SyntheticRunOptions o;
  o.length_m = 8.0;
  const fs::path log = Log("stream", o);
  review::LogTimeline file = review::LogTimeline::Load(log);
  review::LogTimeline memory(review::SyntheticRun(o), "");
  EXPECT_DOUBLE_EQ(file.duration_s(), memory.duration_s());
  for (const double t : {6.0, 2.0, 14.0}) {  // on, back, on
    file.Seek(t), memory.Seek(t);
    EXPECT_EQ(file.model().messages(), memory.model().messages()) << t;
    EXPECT_EQ(file.model().plants().size(), memory.model().plants().size()) << t;
    EXPECT_EQ(file.model().tile_revision_sum(), memory.model().tile_revision_sum()) << t;
  }
}

}  // namespace
}  // namespace plantscale::ui
