// The station's keys and clicks, driven without the event loop: clicking a
// plant shows its record, the measure tool gives the ground distance between
// two clicks, `g` hides the predicted grid, space pauses, q quits.
#include "ui/station_controller.h"

#include <gtest/gtest.h>

#include "review/synthetic_run.h"
#include "ui/golden.h"

namespace plantscale::ui {
namespace {

namespace fs = std::filesystem;

int YellowPixels(const cv::Mat& image) {
  int n = 0;
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) {
      const cv::Vec3b p = image.at<cv::Vec3b>(r, c);
      n += p[2] > 200 && p[1] > 170 && p[0] < 90;
    }
  }
  return n;
}

class StationControllerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!DisplayAvailable()) GTEST_SKIP() << "no DISPLAY: VTK renders through GLX; run under xvfb-run -a";
    const fs::path log = fs::path(testing::OutputDir()) / "controller.lcmlog";
    review::WriteSyntheticLog(log, {});
    options_.width_px = 640, options_.height_px = 360;
    source_ = std::make_unique<LogSource>(log, 1.0);
    source_->Seek(12.0, /*relative=*/true);
    canvas_ = std::make_unique<Canvas>(options_.width_px, options_.height_px);
    scene_ = std::make_unique<StationScene>(*canvas_, options_);
    controller_ = std::make_unique<StationController>(*canvas_, *scene_, *source_, options_);
    source_->TogglePause();  // hold the log still while we click
    controller_->Frame(0.0);
  }
  void ClickAt(const Eigen::Vector2d& field) {
    const Eigen::Vector2d d = scene_->map().DisplayAtField(field);
    controller_->Click(static_cast<int>(std::lround(d.x())), static_cast<int>(std::lround(d.y())));
  }

  StationOptions options_;
  std::unique_ptr<LogSource> source_;
  std::unique_ptr<Canvas> canvas_;
  std::unique_ptr<StationScene> scene_;
  std::unique_ptr<StationController> controller_;
};

TEST_F(StationControllerTest, ClickOnAPlantShowsItsRecord) {
  const auto& plants = source_->model().plants();
  ASSERT_FALSE(plants.empty());
  const review::PlantRecord& weed = [&]() -> const review::PlantRecord& {
    for (const auto& [id, r] : plants) {
      if (r.plant.kind == telemetry::PlantKind::kWeed) return r;
    }
    return plants.begin()->second;
  }();
  ClickAt(weed.plant.position_m);
  EXPECT_NE(controller_->tool_text().find("plant " + std::to_string(weed.plant.id) + ": weed"), std::string::npos)
      << controller_->tool_text();
  EXPECT_NE(controller_->tool_text().find("sprayed (outside crop region)"), std::string::npos);
  // A point in view between the rows more than 0.2 m from every plant.
  std::optional<Eigen::Vector2d> empty;
  for (double y = source_->model().pose()->y_m; !empty && y < source_->model().pose()->y_m + 3.0; y += 0.02) {
    const Eigen::Vector2d p(0.24, y);
    double nearest = 1e9;
    for (const auto& [id, r] : plants) nearest = std::min(nearest, (r.plant.position_m - p).norm());
    if (nearest > 0.2) empty = p;
  }
  ASSERT_TRUE(empty.has_value());
  ClickAt(*empty);
  EXPECT_NE(controller_->tool_text().find("no plant"), std::string::npos);
}

TEST_F(StationControllerTest, MeasureToolGivesGroundDistance) {
  controller_->Key("r");
  const Eigen::Vector2d a = source_->model().pose()->y_m * Eigen::Vector2d(0, 1) + Eigen::Vector2d(0.2, 0.0);
  const Eigen::Vector2d b = a + Eigen::Vector2d(-0.3, 1.2);  // 1.237 m away
  ClickAt(a);
  ClickAt(b);
  const std::string& text = controller_->tool_text();
  ASSERT_NE(text.find("distance "), std::string::npos) << text;
  const double d = std::stod(text.substr(text.find("distance ") + 9));
  EXPECT_NEAR(d, (b - a).norm(), 0.02) << "one pixel is 6 m / 640 px = 9.4 mm";
}

TEST_F(StationControllerTest, KeysToggleGridPauseAndQuit) {
  const int with_grid = YellowPixels(canvas_->Render());
  EXPECT_GT(with_grid, 500);
  controller_->Key("g");
  controller_->Frame(0.0);
  EXPECT_LT(YellowPixels(canvas_->Render()), with_grid / 2) << "rows hidden (the camera view keeps its own grid)";
  EXPECT_NE(source_->Status().find("PAUSED"), std::string::npos);
  controller_->Key("space");
  EXPECT_EQ(source_->Status().find("PAUSED"), std::string::npos);
  EXPECT_FALSE(controller_->Key("m"));
  EXPECT_TRUE(controller_->Key("q"));
}

TEST_F(StationControllerTest, ScriptedKeysArePressedWhenDueAndQuitCloses) {
  StationOptions o = options_;
  o.press = {{0.0, "g"}, {0.0, "C"}, {100.0, "q"}};  // --press g@0 --press C@0 --press q@100
  StationController scripted(*canvas_, *scene_, *source_, o);
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(scene_->map().Visible(MapLayerId::kGrid));
  scripted.PressDue(start);
  EXPECT_FALSE(scene_->map().Visible(MapLayerId::kGrid));
  ASSERT_EQ(scripted.command_replies().size(), 1u);
  EXPECT_NE(scripted.command_replies()[0].find("need a live station"), std::string::npos);
  EXPECT_FALSE(scripted.ShouldClose(start));  // q is due at 100 s
  scripted.PressDue(start - std::chrono::seconds(101));
  EXPECT_TRUE(scripted.ShouldClose(start));
}

}  // namespace
}  // namespace plantscale::ui
