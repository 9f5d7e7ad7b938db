// Fuzz target: every LCM message type (telemetry/lcmtypes/*.lcm) through the
// project's decode path. Byte 0 picks the type; the rest are the message's
// bytes, as received on its channel:
//   1. telemetry::Decode<T> must never throw or crash; a message it accepts
//      must encode again and decode to the same bytes (unless a string
//      holds a NUL, see StringsHaveNul);
//   2. the station's conversions (telemetry/convert.h FromLcm) may refuse a
//      decoded message only with DataError;
//   3. telemetry::Subscriber::Feed on the type's channel (decode, convert,
//      sequence tracking, state) must never throw.
#include <plantscale_lcmtypes/plantscale_blob_t.hpp>
#include <plantscale_lcmtypes/plantscale_command_t.hpp>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <plantscale_lcmtypes/plantscale_grid_state_t.hpp>
#include <plantscale_lcmtypes/plantscale_health_t.hpp>
#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_nozzles_t.hpp>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_list_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_t.hpp>
#include <plantscale_lcmtypes/plantscale_pose_t.hpp>
#include <plantscale_lcmtypes/plantscale_shot_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>

#include <cstdint>
#include <cstring>
#include <string>

#include "engine/common/options.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"
#include "telemetry/subscriber.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

namespace tel = plantscale::telemetry;
namespace ch = plantscale::telemetry::channels;

struct NoConversion {
  template <typename M>
  void operator()(const M&) const {}
};
struct Convert {
  template <typename M>
  void operator()(const M& m) const {
    (void)tel::FromLcm(m);
  }
  void operator()(const plantscale_plant_list_t& m) const {
    for (const plantscale_plant_t& p : m.plants) (void)tel::FromLcm(p);
  }
};

// LCM strings are C strings: encode() writes up to the first NUL, so a
// decoded string with a NUL inside does not survive encoding (nothing in the
// project encodes such a string; the received one is kept as it came).
bool HasNul(const std::string& s) { return s.find('\0') != std::string::npos; }
template <typename M>
bool StringsHaveNul(const M&) {
  return false;
}
bool StringsHaveNul(const plantscale_command_t& m) { return HasNul(m.origin); }
bool StringsHaveNul(const plantscale_event_t& m) { return HasNul(m.kind) || HasNul(m.text); }
bool StringsHaveNul(const plantscale_health_t& m) {
  bool nul = HasNul(m.source);
  for (const std::string& f : m.faults) nul = nul || HasNul(f);
  return nul;
}

template <typename M, typename Conversion>
void DecodeConvert(const char* channel, const uint8_t* data, size_t size, Conversion convert) {
  std::string error;
  const std::optional<M> m = tel::Decode<M>(channel, data, size, &error);
  if (!m) {
    if (error.empty()) plantscale::fuzz::Fail("Decode refused without a reason");
  } else if (!StringsHaveNul(*m)) {
    const tel::Bytes again = tel::Encode(*m);
    const std::optional<M> m2 = tel::Decode<M>(channel, again.data(), again.size());
    if (!m2) plantscale::fuzz::Fail("a decoded message does not decode after encoding");
    const tel::Bytes third = tel::Encode(*m2);
    if (third != again) plantscale::fuzz::Fail("encode(decode(encode(m))) != encode(m)");
  }
  if (m) {
    try {
      convert(*m);
    } catch (const plantscale::DataError&) {
      // the documented refusal
    }
  }
  if (channel[0] != '\0') {
    tel::Subscriber subscriber;
    subscriber.Feed(channel, data, size, 1);
    (void)subscriber.Snapshot();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t* bytes = data + 1;
  const size_t n = size - 1;
  switch (data[0] % 16) {
    case 0: DecodeConvert<plantscale_grid_state_t>(ch::kGrid, bytes, n, Convert{}); break;
    case 1: DecodeConvert<plantscale_pose_t>(ch::kPose, bytes, n, Convert{}); break;
    case 2: DecodeConvert<plantscale_plant_list_t>(ch::kPlants, bytes, n, Convert{}); break;
    case 3: DecodeConvert<plantscale_map_tile_t>(ch::kMapTiles, bytes, n, Convert{}); break;
    case 4: DecodeConvert<plantscale_nozzles_t>(ch::kNozzles, bytes, n, Convert{}); break;
    case 5: DecodeConvert<plantscale_health_t>(ch::kHealth, bytes, n, Convert{}); break;
    case 6: DecodeConvert<plantscale_thumbnail_t>(ch::kThumbnail, bytes, n, NoConversion{}); break;
    case 7: DecodeConvert<plantscale_odometry_t>(ch::kOdometry, bytes, n, NoConversion{}); break;
    case 8: DecodeConvert<plantscale_command_t>(ch::kCommand, bytes, n, NoConversion{}); break;
    case 9: DecodeConvert<plantscale_event_t>(ch::kEvents, bytes, n, NoConversion{}); break;
    case 10: DecodeConvert<plantscale_plant_t>("", bytes, n, Convert{}); break;
    case 11: DecodeConvert<plantscale_shot_t>("", bytes, n, NoConversion{}); break;
    case 12: DecodeConvert<plantscale_blob_t>("", bytes, n, NoConversion{}); break;
    case 13: DecodeConvert<plantscale_grid_state_t>(ch::kSimTruth, bytes, n, Convert{}); break;
    case 14: DecodeConvert<plantscale_pose_t>(ch::kSimTruthPose, bytes, n, Convert{}); break;
    default: {  // an unknown channel
      tel::Subscriber subscriber;
      subscriber.Feed("FUZZ_UNKNOWN", bytes, n, 1);
      break;
    }
  }
  return 0;
}
