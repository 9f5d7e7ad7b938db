// Fuzz target: the LCM log reader (telemetry/log.h) on arbitrary files. The
// input is written to a file and read as `plantscale telemetry-stats` and
// `replay` do: LogReader to the end (each event handed to a Subscriber, as
// the station and the report read logs), then MeasureLog. A bad log may
// only end early with error() set, or throw LogError.
#include <cstdint>
#include <string>

#include "telemetry/log.h"
#include "telemetry/log_stats.h"
#include "telemetry/subscriber.h"
#include "tests/fuzz/fuzz_util.h"

namespace tel = plantscale::telemetry;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = plantscale::fuzz::WriteScratch("fuzz.lcmlog", data, size);
  try {
    tel::LogReader reader(path);
    tel::Subscriber subscriber;
    int64_t events = 0;
    while (const auto e = reader.Next()) {
      ++events;
      subscriber.Feed(e->channel, e->data.data(), e->data.size(), e->utime);
    }
    if (events != reader.events_read()) plantscale::fuzz::Fail("events_read() miscounts");
    (void)subscriber.Snapshot();
    const tel::LogTraffic traffic = tel::MeasureLog(path);
    if (traffic.events != events) plantscale::fuzz::Fail("MeasureLog and LogReader disagree");
    if (traffic.error != reader.error()) plantscale::fuzz::Fail("MeasureLog's error differs");
  } catch (const tel::LogError&) {
    // the documented refusal
  }
  return 0;
}
