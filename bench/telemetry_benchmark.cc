// Telemetry benchmarks: publish→receive latency of a grid-state message over
// real LCM (udpm:// by default, needs the multicast route on lo:
//   sudo ip route add 224.0.0.0/4 dev lo
// or run inside `unshare -rn` after `ip link set lo up; ip route add
// 224.0.0.0/4 dev lo`), and the cost of encoding and publishing over memq://.
// PLANTSCALE_BENCH_LCM_URL overrides the URL. Issue 8 figures: p99 ≤ 10 ms,
// and no message lost over 10 minutes of fast replay.

#include <benchmark/benchmark.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

#include "engine/common/stats.h"
#include "review/synthetic_run.h"
#include "telemetry/can/protocol.h"
#include "telemetry/can/simulated_bar.h"
#include "telemetry/can/spray_bar.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"
#include "telemetry/publisher.h"
#include "telemetry/replay.h"
#include "telemetry/subscriber.h"
#include "telemetry/transport.h"

namespace plantscale::telemetry {
namespace {

std::string BenchUrl() {
  const char* url = std::getenv("PLANTSCALE_BENCH_LCM_URL");
  return url ? url : LcmTransportOptions{}.url;
}

// A sending and a receiving LCM instance on the benchmark URL; false (and
// the benchmark skipped, saying why: most often the missing multicast
// route) when LCM cannot start.
bool OpenPair(benchmark::State& state, std::unique_ptr<LcmTransport>& tx, std::unique_ptr<LcmTransport>& rx) {
  try {
    tx = std::make_unique<LcmTransport>(BenchUrl());
    rx = std::make_unique<LcmTransport>(BenchUrl());
    return true;
  } catch (const TransportError& e) {
    state.SkipWithError(e.what());
    return false;
  }
}

plantscale_grid_state_t SomeGrid() {
  GridEstimate e;
  e.lines_in_view = {0, 1, 2, 3, 4};
  e.covariance = geometry::Matrix5d::Identity() * 1e-4;
  return ToLcm(e);
}

// Each iteration publishes one grid state (stamped with the wall clock) and
// waits for it on a second LCM instance; counters give p50/p99/max in ms.
void BM_PublishReceiveLatency(benchmark::State& state) {
  std::unique_ptr<LcmTransport> tx, rx;
  if (!OpenPair(state, tx, rx)) return;
  std::vector<double> latencies_ms;
  std::atomic<int64_t> received{0};
  rx->Subscribe(channels::kGrid, [&](const ReceivedMessage& m) {
    const auto msg = Decode<plantscale_grid_state_t>(m.channel, m.data, m.size);
    if (msg) latencies_ms.push_back(1e-3 * static_cast<double>(WallUtime() - msg->utime));
    ++received;
  });
  plantscale_grid_state_t grid = SomeGrid();
  int64_t sent = 0;
  for (auto _ : state) {
    grid.utime = WallUtime();
    grid.seq = sent++;
    const Bytes b = Encode(grid);
    tx->Publish(channels::kGrid, b.data(), b.size());
    while (received < sent && rx->Handle(50)) {
    }
  }
  state.counters["p50_ms"] = Percentile(latencies_ms, 0.50);
  state.counters["p99_ms"] = Percentile(latencies_ms, 0.99);
  state.counters["max_ms"] = Percentile(latencies_ms, 1.0);
  state.counters["lost"] = static_cast<double>(sent - received);
  state.counters["bytes"] = static_cast<double>(Encode(grid).size());
}
BENCHMARK(BM_PublishReceiveLatency)->Iterations(2000)->UseRealTime();

// Issue 8 figure: no message lost over 10 minutes of a 12.5 Hz run replayed
// fast. A synthetic 10-minute run (every channel the vehicle publishes:
// grid, plants, tiles, nozzles, heartbeat, thumbnails, odometry, events) is
// logged, then replayed at `speed`× over real LCM to a subscriber on a second
// LCM instance, which counts sequence gaps. Counters: messages, lost.
void BM_TenMinuteFastReplayNoLoss(benchmark::State& state) {
  const double speed = static_cast<double>(state.range(0));
  const std::filesystem::path log =
      std::filesystem::temp_directory_path() / ("plantscale_bench_10min_" + std::to_string(::getpid()) + ".lcmlog");
  review::SyntheticRunOptions o;
  o.speed_m_s = 0.5;
  o.length_m = 600.0 * o.speed_m_s;  // 10 minutes
  review::WriteSyntheticLog(log, o);
  std::unique_ptr<LcmTransport> tx, rx;
  if (!OpenPair(state, tx, rx)) return;
  int64_t messages = 0, lost = 0;
  for (auto _ : state) {
    Subscriber sub;
    sub.Attach(*rx);
    std::atomic<bool> done{false};
    std::thread receiver([&] {
      while (!done) rx->Handle(20);
      while (rx->Handle(200)) {
      }
    });
    const ReplaySummary r = Replay(log, *tx, ReplayOptions{speed, 0.0, ".*"});
    done = true;
    receiver.join();
    const TelemetrySnapshot snap = sub.Snapshot();
    messages = 0, lost = 0;
    for (const auto& [name, c] : snap.channels) {
      messages += c.received;
      lost += c.lost;
    }
    lost += r.published - messages;  // also messages missing at the end
  }
  std::filesystem::remove(log);
  state.counters["messages"] = static_cast<double>(messages);
  state.counters["lost"] = static_cast<double>(lost);
}
BENCHMARK(BM_TenMinuteFastReplayNoLoss)->Arg(20)->Arg(100)->Iterations(1)->UseRealTime()->Unit(benchmark::kSecond);

// Encoding plus the publisher's rate and budget bookkeeping over memq://.
void BM_PublisherGridState(benchmark::State& state) {
  LcmTransport memq("memq://");
  PublisherOptions options;
  options.channels.clear();  // no rate limit: measure the work per message
  options.budget_kbit_s = 1e9;
  Publisher publisher(memq, options);
  plantscale_grid_state_t grid = SomeGrid();
  int64_t utime = 0;
  for (auto _ : state) {
    grid.utime = (utime += 80'000);
    benchmark::DoNotOptimize(publisher.Publish(channels::kGrid, grid));
    if (utime % 8'000'000 == 0)
      while (memq.Handle(0)) {
      }
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PublisherGridState);

// Spray bar (telemetry/can): encode + decode of one nozzle command, and one
// scheduler tick over a socketpair (command, simulated bar acknowledges,
// vehicle reads the acknowledgement): the syscalls dominate.
void BM_CanCommandEncodeDecode(benchmark::State& state) {
  const can::ProtocolIds ids;
  can::NozzleCommand c{0, 0, 0x5A, 200};
  for (auto _ : state) {
    ++c.seq;
    const can_frame f = can::Encode(ids, c);
    benchmark::DoNotOptimize(can::Decode(ids, f));
  }
}
BENCHMARK(BM_CanCommandEncodeDecode);

void BM_SprayBarTickOverSocketpair(benchmark::State& state) {
  auto [vehicle_end, bar_end] = can::CanFramePipe();
  can::SprayBar bar(std::move(vehicle_end), can::BarLinkOptions{}, "socketpair");
  can::SimulatedBar sim(std::move(bar_end), can::SimulatedBarOptions{});
  const auto sink = bar.Sink();
  int64_t utime = 1'000'000'000;
  uint64_t mask = 0;
  for (auto _ : state) {
    utime += 20'000;
    mask = (mask + 1) & 0xFF;
    sink(utime, mask);
    sim.Step(utime);
  }
  state.counters["failsafe"] = bar.status().failsafe ? 1 : 0;
}
BENCHMARK(BM_SprayBarTickOverSocketpair);

}  // namespace
}  // namespace plantscale::telemetry

BENCHMARK_MAIN();
