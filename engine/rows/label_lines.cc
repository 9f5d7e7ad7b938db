#include "engine/rows/label_lines.h"

namespace plantscale::rows {

std::vector<double> LabelLineCentres(const uint8_t* row, int cols, double scale) {
  std::vector<double> centres;
  for (int x = 0; x < cols;) {
    if (row[x] < 128) {
      ++x;
      continue;
    }
    const int start = x;
    while (x < cols && row[x] >= 128) ++x;
    centres.push_back(0.5 * (start + x) * scale);
  }
  return centres;
}

}  // namespace plantscale::rows
