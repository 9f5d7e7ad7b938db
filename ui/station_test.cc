// The station composed: a golden of the whole window, and the station loop
// kept running (off-screen) on logs that are wrong, saying what is wrong.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "review/test_util.h"
#include "telemetry/command_auth.h"
#include "telemetry/log.h"
#include "ui/golden.h"
#include "ui/palette.h"
#include "ui/station.h"
#include "ui/station_sources.h"

namespace plantscale::ui {
namespace {

namespace fs = std::filesystem;

TEST(Station, ComposedWindowGolden) {
  PLANTSCALE_REQUIRE_DISPLAY();
  const review::LogTimeline run = review::testing::RunUpTo({}, 12.0);
  StationOptions o;
  o.width_px = 640, o.height_px = 360;
  Canvas canvas(o.width_px, o.height_px);
  StationScene scene(canvas, o);
  scene.Update(run.model(), run.now_utime(), 12.0 / 20.0);
  const cv::Mat image = canvas.Render();
  EXPECT_TRUE(testing::MatchesGolden(image, "station"));
  // The HUD strip (top 8 %) is the link-ok green.
  const cv::Vec3b hud = image.at<cv::Vec3b>(26, 636);
  EXPECT_NEAR(hud[1], 255 * palette::kHudOk.g, 2);
}

// Redrawing only the viewports that changed gives the pixels of a full
// redraw: frames of the log (map, camera, HUD and timeline change at their
// own rates, most frames bring nothing new) and then a lost link, where only
// the HUD changes (to red).
TEST(Station, PartialRedrawMatchesFullRedraw) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions run;
  run.length_m = 6.0;
  StationOptions o;
  o.width_px = 640, o.height_px = 360;
  review::LogTimeline partial_run = review::testing::RunUpTo(run, 5.0), full_run = review::testing::RunUpTo(run, 5.0);
  Canvas partial(o.width_px, o.height_px), full(o.width_px, o.height_px);
  full.SetPartialRedraw(false);
  StationScene partial_scene(partial, o), full_scene(full, o);
  cv::Mat last;
  for (int frame = 0; frame < 16; ++frame) {
    const bool lost = frame == 15;  // 5 s after the last message: the heartbeat is lost
    for (review::LogTimeline* t : {&partial_run, &full_run}) t->Advance(1.0 / 60.0);
    const int64_t now = partial_run.now_utime() + (lost ? 5'000'000 : 0);
    const double fraction = partial_run.position_s() / partial_run.duration_s();
    partial_scene.Update(partial_run.model(), now, fraction);
    full_scene.Update(full_run.model(), now, fraction);
    last = partial.Render();
    EXPECT_EQ(cv::norm(last, full.Render(), cv::NORM_INF), 0.0) << "frame " << frame;
  }
  const cv::Vec3b hud = last.at<cv::Vec3b>(5, 636);  // BGR
  EXPECT_NEAR(hud[2], 255 * palette::kHudLost.r, 2);
  EXPECT_NEAR(hud[1], 255 * palette::kHudLost.g, 2);
}

StationResult RunOn(const fs::path& log, double seconds = 1.0) {
  StationOptions o;
  o.log = log;
  o.offscreen = true;
  o.max_seconds = seconds;
  o.speed = 8.0;
  o.width_px = 640, o.height_px = 360;
  return RunStation(o);
}

bool Says(const StationResult& r, const std::string& what) {
  for (const std::string& p : r.problems) {
    if (p.find(what) != std::string::npos) return true;
  }
  return false;
}

fs::path LogWith(const std::string& name, const review::SyntheticRunOptions& o) {
  const fs::path p = fs::path(testing::OutputDir()) / (name + ".lcmlog");
  review::WriteSyntheticLog(p, o);
  return p;
}

TEST(Station, KeepsRunningOnAGoodLog) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions o;
  o.length_m = 3.0;
  const StationResult r = RunOn(LogWith("station_good", o), 3.0);
  // It ran for its three seconds and drew, and found nothing wrong. The
  // frame count depends on the machine's load (beside the other tests on
  // two cores it once drew 8 where 10 were required; in a clean clone's
  // first run, VTK's start-up under load took most of one second and it
  // drew 1; with two simulator evaluations beside the suite it drew 2
  // where 3 were required), so only drawing at all is required: the frame
  // rate is the benchmarks' and the review test's.
  EXPECT_GE(r.seconds, 2.9);
  EXPECT_GE(r.frames, 1);
  EXPECT_TRUE(r.problems.empty()) << r.problems.front();
}

TEST(Station, ScreenshotIsTheWindowAsItClosed) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions run;
  run.length_m = 3.0;
  StationOptions o;
  o.log = LogWith("station_screenshot", run);
  o.offscreen = true;
  o.max_seconds = 1.5;  // 12 s of log at speed 8: past its end, where replay time stops
  o.speed = 8.0;
  o.width_px = 640, o.height_px = 360;
  o.screenshot = fs::path(testing::OutputDir()) / "station_screenshot.png";
  fs::remove(o.screenshot);
  const StationResult r = RunStation(o);
  EXPECT_TRUE(r.problems.empty()) << r.problems.front();
  // The log ends with the vehicle's run_finished: replayed to its end the
  // station says the run finished (the heartbeat never ages there).
  EXPECT_NE(r.link.find("run finished after"), std::string::npos) << r.link;
  const cv::Mat image = cv::imread(o.screenshot.string());
  ASSERT_FALSE(image.empty()) << o.screenshot;
  EXPECT_EQ(image.cols, 640);
  EXPECT_EQ(image.rows, 360);
  const cv::Vec3b hud = image.at<cv::Vec3b>(5, 636);  // BGR, at the log's last message
  EXPECT_NEAR(hud[0], 255 * palette::kHudFinished.b, 2);
  EXPECT_NEAR(hud[1], 255 * palette::kHudFinished.g, 2);
  EXPECT_NEAR(hud[2], 255 * palette::kHudFinished.r, 2);
}

// Live, the heartbeat stops when the vehicle ends its run: after its
// run_finished event the HUD turns slate, not the lost link's red.
TEST(Station, HudIsSlateOnceTheRunFinished) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions run;
  run.length_m = 3.0;
  review::LogTimeline timeline = review::testing::RunUpTo(run, 6.0);
  timeline.Seek(timeline.duration_s());
  StationOptions o;
  o.width_px = 640, o.height_px = 360;
  Canvas canvas(o.width_px, o.height_px);
  StationScene scene(canvas, o);
  scene.Update(timeline.model(), timeline.now_utime() + 5'000'000, 1.0);
  const cv::Mat image = canvas.Render();
  const cv::Vec3b hud = image.at<cv::Vec3b>(26, 636);  // BGR, clear of the text
  EXPECT_NEAR(hud[0], 255 * palette::kHudFinished.b, 2);
  EXPECT_NEAR(hud[1], 255 * palette::kHudFinished.g, 2);
  EXPECT_NEAR(hud[2], 255 * palette::kHudFinished.r, 2);
  cv::imwrite((fs::path(testing::OutputDir()) / "station_finished.png").string(), image);
}

TEST(Station, SaysWhatIsWrongWithBadLogs) {
  PLANTSCALE_REQUIRE_DISPLAY();
  review::SyntheticRunOptions nan;
  nan.length_m = 2.0;
  nan.nan_grid_at_s = 0.5;
  EXPECT_TRUE(Says(RunOn(LogWith("station_nan", nan)), "PLANTSCALE_GRID"));

  review::SyntheticRunOptions restart;
  restart.length_m = 4.0;
  restart.restart_at_s = 2.0;
  EXPECT_TRUE(Says(RunOn(LogWith("station_restart", restart)), "restarted"));

  const fs::path empty = fs::path(testing::OutputDir()) / "station_empty.lcmlog";
  { telemetry::LogWriter w(empty); }
  EXPECT_TRUE(Says(RunOn(empty), "NO MESSAGES"));

  const fs::path foreign = fs::path(testing::OutputDir()) / "station_foreign.lcmlog";
  {
    telemetry::LogWriter w(foreign);
    for (int i = 0; i < 5; ++i) w.Write("OTHER", "abc", 3, 1000 + i * 1000);
  }
  EXPECT_TRUE(Says(RunOn(foreign), "no plantscale messages"));
}

}  // namespace
}  // namespace plantscale::ui

namespace plantscale::ui {
namespace {

// A live station's command keys publish on PLANTSCALE_COMMAND (here over
// memq://, which the live source's own subscriber also hears); a log
// source says commands need a live vehicle. No display needed.
// The last command the live source's own subscriber heard, once it is `command`.
std::optional<plantscale_command_t> Heard(const LiveSource& live, int8_t command) {
  std::optional<plantscale_command_t> got;
  for (int i = 0; i < 100 && !(got && got->command == command); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    got = live.subscriber().Snapshot().command;
  }
  return got;
}

TEST(StationSources, LiveSourceSendsCommandsALogSourceDoesNot) {
  const int64_t start = telemetry::WallUtime();
  LiveSource live("memq://");  // no key: unsigned, which a vehicle refuses by default
  EXPECT_EQ(live.SendCommand(plantscale_command_t::COMMAND_PAUSE, 0), "sent unsigned (no --command-key): pause");
  EXPECT_EQ(live.SendCommand(plantscale_command_t::COMMAND_SET_MODE, plantscale_command_t::MODE_SPRAY_WEED),
            "sent unsigned (no --command-key): spray the weeds");
  const std::optional<plantscale_command_t> got = Heard(live, plantscale_command_t::COMMAND_SET_MODE);
  ASSERT_TRUE(got.has_value());
  EXPECT_GE(got->seq, start);  // the wall clock: seqs increase across station restarts
  EXPECT_EQ(got->command, int8_t{plantscale_command_t::COMMAND_SET_MODE});
  EXPECT_EQ(got->mode, int8_t{plantscale_command_t::MODE_SPRAY_WEED});
  EXPECT_EQ(got->origin.rfind("station@", 0), 0u) << got->origin;
  EXPECT_EQ(got->mac_size, 0);

  review::SyntheticRunOptions o;
  o.length_m = 2.0;
  const std::filesystem::path log = std::filesystem::temp_directory_path() / ("plantscale_cmd_" + std::to_string(::getpid()) + ".lcmlog");
  review::WriteSyntheticLog(log, o);
  LogSource replay(log, 1.0);
  EXPECT_NE(replay.SendCommand(plantscale_command_t::COMMAND_PAUSE, 0).find("need a live station"), std::string::npos);
  std::filesystem::remove(log);
}

// With --command-key the station signs: what it sends verifies with the
// key (fresh, seqs increasing), and not with another.
TEST(StationSources, LiveSourceSignsCommandsWithItsKey) {
  telemetry::CommandKey key, other;
  key.bytes.fill(3);
  other.bytes.fill(4);
  LiveSource live("memq://", key);
  telemetry::CommandReplayState state, other_state;
  int64_t last_seq = 0;
  for (const int8_t command : {int8_t{plantscale_command_t::COMMAND_PAUSE}, int8_t{plantscale_command_t::COMMAND_START}}) {
    EXPECT_EQ(live.SendCommand(command, 0).rfind("sent to the vehicle: ", 0), 0u);
    const std::optional<plantscale_command_t> got = Heard(live, command);
    ASSERT_TRUE(got.has_value());
    EXPECT_EQ(got->mac_size, int16_t{plantscale_command_t::MAC_SIZE});
    EXPECT_GT(got->seq, last_seq);
    last_seq = got->seq;
    const telemetry::CommandCheck check = telemetry::Verify(*got, key, telemetry::WallUtime(), state);
    EXPECT_TRUE(check.accepted()) << check.reason;
    EXPECT_EQ(telemetry::Verify(*got, other, telemetry::WallUtime(), other_state).verdict,
              telemetry::CommandVerdict::kForged);
  }
}

}  // namespace
}  // namespace plantscale::ui
