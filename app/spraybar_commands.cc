#include "app/spraybar_commands.h"

#include <chrono>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>

#include "app/config/config_loader.h"
#include "app/telemetry_commands.h"
#include "telemetry/transport.h"

namespace plantscale::app {
namespace {

namespace can = plantscale::telemetry::can;

struct SprayBarArgs {
  std::string can;
  int nozzles = 8;
  double seconds = 2.0;
  double tick_hz = 50.0;
  bool test_pattern = false;
  bool json = false;
};

// Walking test pattern: nozzle k open for 0.2 s in turn, then a 0.2 s gap
// with all closed.
uint64_t PatternMask(double t_s, int nozzles) {
  const int slot = static_cast<int>(t_s / 0.2) % (nozzles + 1);
  return slot < nozzles ? uint64_t{1} << slot : 0;
}

int RunSprayBar(const SprayBarArgs& a) {
  if (!(a.seconds > 0 && a.seconds <= 3600)) {
    throw ConfigError("command line", "--seconds", "must be in (0, 3600]");
  }
  if (!(a.tick_hz >= 5 && a.tick_hz <= 1000)) {
    throw ConfigError("command line", "--tick-hz", "must be in [5, 1000]");
  }
  can::BarLinkOptions options;
  options.num_nozzles = a.nozzles;
  ThrowIfInvalid("spraybar --nozzles", options.Validate());
  PublishArgs endpoint_args;
  endpoint_args.can = a.can;
  const SprayBarEndpoint e = OpenSprayBar(endpoint_args, true, options);
  can::SprayBar& bar = *e.bar;
  const auto sink = bar.Sink();
  using Clock = std::chrono::steady_clock;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / a.tick_hz));
  const Clock::time_point start = Clock::now();
  const int64_t start_utime = telemetry::WallUtime();
  const int ticks = static_cast<int>(a.seconds * a.tick_hz);
  int ticks_failsafe = 0;
  for (int i = 0; i < ticks; ++i) {
    std::this_thread::sleep_until(start + i * period);
    const int64_t utime =
        start_utime +
        std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start).count();
    const double t_s = 1e-6 * static_cast<double>(utime - start_utime);
    sink(utime, a.test_pattern ? PatternMask(t_s, a.nozzles) : 0);
    if (e.simulated) e.simulated->Step(utime);
    ticks_failsafe += bar.status().failsafe ? 1 : 0;
  }
  bar.Poll(start_utime +
           std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start).count());
  const can::SprayBarStatus& s = bar.status();
  nlohmann::json faults = nlohmann::json::array();
  for (can::NozzleFault f : s.nozzle_faults) faults.push_back(can::NozzleFaultName(f));
  if (a.json) {
    nlohmann::json j = {{"interface", a.can},
                        {"nozzles", a.nozzles},
                        {"seconds", a.seconds},
                        {"test_pattern", a.test_pattern},
                        {"commands", s.commands_sent},
                        {"acks", s.acks},
                        {"heartbeats", s.heartbeats},
                        {"frames_rejected", s.frames_rejected},
                        {"sequence_gaps", s.sequence_gaps},
                        {"ticks_failsafe", ticks_failsafe},
                        {"failsafe", s.failsafe},
                        {"reasons", s.reasons},
                        {"nozzle_faults", faults},
                        {"last_error", s.last_error}};
    std::cout << j.dump(2) << '\n';
  } else {
    std::cout << "plantscale spraybar: " << a.can << ", " << a.nozzles << " nozzles, " << std::fixed
              << std::setprecision(1) << a.seconds << " s at " << a.tick_hz << " Hz"
              << (a.test_pattern ? ", walking test pattern" : ", all closed") << '\n'
              << "  commands " << s.commands_sent << ", acks " << s.acks << ", heartbeats "
              << s.heartbeats << ", frames rejected " << s.frames_rejected << ", sequence gaps "
              << s.sequence_gaps << ", ticks fail-safe " << ticks_failsafe << " of " << ticks
              << '\n';
    for (size_t i = 0; i < s.nozzle_faults.size(); ++i) {
      std::cout << "  nozzle " << std::setw(2) << i << "  "
                << can::NozzleFaultName(s.nozzle_faults[i]) << '\n';
    }
    if (!s.last_error.empty()) std::cout << "  last error: " << s.last_error << '\n';
    std::cout << "  state: " << (s.failsafe ? "FAIL-SAFE" : "ok") << '\n';
    for (const std::string& r : s.reasons) std::cout << "    " << r << '\n';
  }
  return s.failsafe ? 1 : 0;
}

}  // namespace

void AddSprayBarCommands(CommandRegistry& registry) {
  SprayBarArgs& a = registry.Keep(SprayBarArgs{});
  CLI::App* c = registry.Add(
      "spraybar", "diagnose the spray bar: supervise it for a while and report its state",
      [&a] { return RunSprayBar(a); });
  c->add_option("--can", a.can, "SocketCAN interface of the bar, or 'simulated'")->required();
  c->add_option("--nozzles", a.nozzles, "nozzles on the bar (1..64)")->capture_default_str();
  c->add_option("--seconds", a.seconds, "how long to supervise it")->capture_default_str();
  c->add_option("--tick-hz", a.tick_hz, "command rate, Hz")->capture_default_str();
  c->add_flag("--test-pattern", a.test_pattern,
              "open each nozzle in turn for 0.2 s (default: all closed)");
  c->add_flag("--json", a.json,
              "JSON: interface, nozzles, commands, acks, heartbeats, frames_rejected, "
              "sequence_gaps, failsafe, reasons, nozzle_faults");
}

}  // namespace plantscale::app
