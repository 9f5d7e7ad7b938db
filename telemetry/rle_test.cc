#include "telemetry/rle.h"

#include <gtest/gtest.h>

#include "engine/common/options.h"

namespace plantscale::telemetry {
namespace {

TEST(Rle, RoundTripsRunsLongerThan255) {
  std::vector<uint8_t> cells(604, 1);
  cells[600] = 2;
  cells[601] = 3;
  cells[602] = 3;
  cells[603] = 0;
  const std::vector<uint8_t> encoded = RleEncode(cells);
  // 600 = 255 + 255 + 90: three pairs, then 2, 3×2, 0: three more.
  EXPECT_EQ(encoded.size(), 12u);
  EXPECT_EQ(RleDecode(encoded, cells.size()), cells);
  EXPECT_TRUE(RleEncode({}).empty());
}

TEST(Rle, MalformedDataThrows) {
  EXPECT_THROW(RleDecode({3}, 3), DataError);           // odd length
  EXPECT_THROW(RleDecode({0, 1}, 0), DataError);        // zero count
  EXPECT_THROW(RleDecode({3, 1}, 4), DataError);        // too few cells
  EXPECT_THROW(RleDecode({3, 1, 2, 1}, 4), DataError);  // too many cells
}

}  // namespace
}  // namespace plantscale::telemetry
