#include "telemetry/rle.h"

#include <string>

#include "engine/common/options.h"

namespace plantscale::telemetry {

std::vector<uint8_t> RleEncode(const std::vector<uint8_t>& cells) {
  std::vector<uint8_t> out;
  for (size_t i = 0; i < cells.size();) {
    size_t run = 1;
    while (i + run < cells.size() && run < 255 && cells[i + run] == cells[i]) ++run;
    out.push_back(static_cast<uint8_t>(run));
    out.push_back(cells[i]);
    i += run;
  }
  return out;
}

std::vector<uint8_t> RleDecode(const std::vector<uint8_t>& encoded, size_t expected_cells) {
  if (encoded.size() % 2 != 0) {
    throw DataError("map tile: run-length data has odd length " + std::to_string(encoded.size()));
  }
  std::vector<uint8_t> cells;
  cells.reserve(expected_cells);
  for (size_t i = 0; i < encoded.size(); i += 2) {
    if (encoded[i] == 0) throw DataError("map tile: zero run length at byte " + std::to_string(i));
    if (cells.size() + encoded[i] > expected_cells) break;  // reported below
    cells.insert(cells.end(), encoded[i], encoded[i + 1]);
  }
  size_t expanded = 0;
  for (size_t i = 0; i < encoded.size(); i += 2) expanded += encoded[i];
  if (expanded != expected_cells) {
    throw DataError("map tile: run-length data does not expand to " +
                    std::to_string(expected_cells) + " cells");
  }
  return cells;
}

}  // namespace plantscale::telemetry
