// Fuzz target: the native map file reader (maps/map_file.h, ".psmap").
// Byte 0 chooses the form of the rest:
//   even: the rest is a CBOR payload; the target writes a valid header with
//         its length and CRC-32 in front (else the checksum would stop
//         nearly every mutation before the CBOR and the fields are read);
//   odd:  the rest is the whole file, header included.
// Bad input may only throw DataError; a map that was read must write and
// read back to the same map.
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>

#include "maps/map_file.h"
#include "tests/fuzz/fuzz_util.h"

namespace maps = plantscale::maps;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  std::string file;
  if (data[0] % 2 == 0) {
    char header[96];
    std::snprintf(header, sizeof header, "%s %d %zu %08x\n", maps::kMapFileMagic,
                  maps::kMapFileVersion, size - 1, maps::Crc32(data + 1, size - 1));
    file = header;
  }
  file.append(reinterpret_cast<const char*>(data + 1), size - 1);
  std::istringstream in(file);
  try {
    const maps::CropMap map = maps::ReadMap(in, "fuzz.psmap");
    std::ostringstream out;
    maps::WriteMap(map, out, "fuzz.psmap");
    std::istringstream again(out.str());
    const maps::CropMap map2 = maps::ReadMap(again, "fuzz.psmap");
    std::ostringstream out2;
    maps::WriteMap(map2, out2, "fuzz.psmap");
    if (out2.str() != out.str()) plantscale::fuzz::Fail("a map read back differs");
  } catch (const plantscale::DataError&) {
    // the documented refusal
  }
  return 0;
}
