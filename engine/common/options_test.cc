#include "engine/common/options.h"

#include <gtest/gtest.h>

#include <cmath>

namespace plantscale {
namespace {

TEST(Options, RangeChecksNameTheKeyAndValue) {
  OptionErrors errors;
  RequirePositive(errors, "height_m", -1.5);
  RequireInRange(errors, "tilt_rad", 2.0, 0.0, 1.5, false, true);
  RequireNonNegative(errors, "noise", std::nan(""));
  ASSERT_EQ(errors.size(), 3U);
  EXPECT_EQ(errors[0].key, "height_m");
  EXPECT_NE(errors[0].reason.find("-1.5"), std::string::npos);
  EXPECT_NE(errors[1].reason.find("(0, 1.5]"), std::string::npos);
  EXPECT_EQ(errors[2].key, "noise");
}

TEST(Options, ThrowListsEveryProblemWithPrefix) {
  OptionErrors errors;
  RequirePositive(errors, "height_m", 0.0);
  try {
    ThrowIfInvalid("camera preset x", Prefixed("camera", errors));
    FAIL() << "expected InvalidOptionsError";
  } catch (const InvalidOptionsError& e) {
    EXPECT_EQ(e.errors().at(0).key, "camera.height_m");
    EXPECT_NE(std::string(e.what()).find("camera preset x"), std::string::npos);
  }
}

TEST(Options, ValidValuesPass) {
  OptionErrors errors;
  RequirePositive(errors, "a", 1.0);
  RequireInRange(errors, "b", 1.5, 0.0, 1.5, false, true);
  EXPECT_NO_THROW(ThrowIfInvalid("ok", errors));
}

}  // namespace
}  // namespace plantscale
