#pragma once
// Golden-image comparison for the ui tests. Goldens live in ui/testdata/
// (small PNGs); PLANTSCALE_UPDATE_GOLDEN=1 rewrites them from the current
// renders (look at them before committing). Every render is also written to
// $PLANTSCALE_UI_TEST_OUT (default /tmp/plantscale_ui_test) for inspection.

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <string>

namespace plantscale::ui::testing {

// Passes when at most `max_bad_fraction` of the pixels differ from the
// golden by more than `tolerance` (0..255) in some channel.
::testing::AssertionResult MatchesGolden(const cv::Mat& image, const std::string& name,
                                         int tolerance = 10, double max_bad_fraction = 0.003);

// Skips the current test with a reason when no X display is available.
#define PLANTSCALE_REQUIRE_DISPLAY()                                                   \
  do {                                                                                 \
    if (!::plantscale::ui::DisplayAvailable()) {                                       \
      GTEST_SKIP() << "no DISPLAY: VTK renders through GLX; run under xvfb-run -a";    \
    }                                                                                  \
  } while (0)

std::string OutputDir();

}  // namespace plantscale::ui::testing
