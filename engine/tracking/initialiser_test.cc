#include "engine/tracking/initialiser.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/tracking/test_scene.h"

namespace plantscale::tracking {
namespace {

TEST(Initialiser, HoughFindsTheRowsAmongWeeds) {
  testing::TestScene scene;
  scene.truth = {0.07, 0.21, -0.05, 0.475, 0.45};
  scene.weeds_per_frame = 15;
  const auto features = scene.Features();
  InitialiserOptions o;
  const auto fit = FitRowsOnGround(features, 0.475, 1, o);
  ASSERT_TRUE(fit);
  // Tolerances: a quarter of the thesis's Hough resolution (16 mm, 0.5°).
  EXPECT_NEAR(fit->offset_m, 0.07, 0.004);
  EXPECT_NEAR(fit->bearing_rad, -0.05, 0.002);
  EXPECT_GT(fit->support, 0.6);
  const auto phase = PlantLinePhaseOnGround(features, *fit, 0.475, 0.45, 1, o);
  ASSERT_TRUE(phase);
  EXPECT_NEAR(std::remainder(phase->forward_m - 0.21, 0.45), 0.0, 0.01);
  EXPECT_GT(phase->coherence, 0.8);
}

TEST(Initialiser, RefusesFeaturesWithoutRows) {
  testing::TestScene scene;
  scene.truth.offset_m = 5.0;  // no crop in view
  scene.weeds_per_frame = 30;
  InitialiserOptions o;
  GridInitialiser init(o, 0.475, 0.45, 1, 1.5);
  for (int frame = 0; frame < 5; ++frame) {
    const auto features = scene.Features();
    const InitialiserResult r = init.Offer(features, {0.05, 0.05});
    EXPECT_FALSE(r.state) << "frame " << frame;
    EXPECT_FALSE(r.reason.empty());
  }
}

TEST(Initialiser, ConfirmsOnTheThirdAgreeingFrame) {
  testing::TestScene scene;
  scene.truth = {-0.04, 0.3, 0.03, 0.475, 0.45};
  GridInitialiser init(InitialiserOptions{}, 0.475, 0.45, 1, 1.5);
  const WheelIncrement u{0.056, 0.056};
  InitialiserResult first = init.Offer(scene.Features(), {});
  EXPECT_FALSE(first.state);
  EXPECT_NE(first.reason.find("waiting"), std::string::npos);
  scene.Drive(u);
  EXPECT_FALSE(init.Offer(scene.Features(), u).state);
  scene.Drive(u);
  const InitialiserResult second = init.Offer(scene.Features(), u);
  ASSERT_TRUE(second.state);
  EXPECT_NEAR(second.state->offset_m, scene.truth.offset_m, 0.005);
  EXPECT_NEAR(second.state->bearing_rad, scene.truth.bearing_rad, 0.003);
  EXPECT_NEAR(std::remainder(second.state->forward_m - scene.truth.forward_m, 0.45), 0.0, 0.01);
}

}  // namespace
}  // namespace plantscale::tracking
