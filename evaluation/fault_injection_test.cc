// Fault injection, end to end on the simulator (issue 35; docs/faults.md):
// each fault injected once into the vehicle process on the field preset.
// Asserted for each: the nozzles commanded closed within 100 ms of message
// time where safety needs it (and kept spraying where it does not), the
// reason on the health channel and in the log, recovery once the fault
// clears, and every message logged before the fault still in the log, which
// reads whole.
//
// The table of docs/results/2026-11-27-fault-injection.md:
//   PLANTSCALE_FAULT_TABLE=docs/results/2026-11-27-fault-injection.md
//   PLANTSCALE_CONFIG_DIR=config build/tests/fault_test  (one command line)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "evaluation/fault_injection.h"
#include "telemetry/channels.h"

namespace plantscale::faults {
namespace {

namespace channels = telemetry::channels;
namespace fs = std::filesystem;

struct Expectation {
  FaultKind kind;
  double start_s, end_s;
  bool failsafe_needed;
  std::string health_text;  // a fault line on the heartbeat holds this
  std::string log_text;     // a heartbeat or event in the log holds this
};

struct Row {
  std::string fault;
  std::string failsafe;   // "12 ms" or "not needed (kept spraying)"
  std::string reason;     // the heartbeat's line
  std::string in_log;
  std::string recovery;
  int64_t records_lost = 0;
  int64_t not_logged = 0;
};

std::map<int, Row>& Table() {
  static std::map<int, Row> rows;
  return rows;
}

bool Holds(const std::vector<std::string>& lines, const std::string& text, std::string* found = nullptr) {
  for (const std::string& l : lines) {
    if (l.find(text) != std::string::npos) {
      if (found) *found = l;
      return true;
    }
  }
  return false;
}

double Ms(int64_t us) { return 1e-3 * static_cast<double>(us); }

std::string Fixed(double v, int digits) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

bool Failsafe(const TickRecord& t) { return t.fail_reasons != 0 || t.bar_failsafe; }

// Messages handed to LCM before the fault that are not in the log, in
// order and byte for byte; the log must hold nothing that was not handed.
int64_t RecordsLost(const FaultRunResult& r) {
  size_t j = 0;
  int64_t lost = 0;
  for (size_t i = 0; i < r.published_at_injection; ++i) {
    const Published& p = r.published[i];
    if (j < r.log.size() && r.log[j].channel == p.channel && r.log[j].data == p.bytes) {
      ++j;
    } else {
      ++lost;
    }
  }
  return lost;
}

// The log, after the messages before the fault: the rest of what was
// handed to LCM, in order, with gaps only (messages not logged).
int64_t NotLogged(const FaultRunResult& r, bool* in_order) {
  size_t j = std::min(r.published_at_injection, r.log.size());
  int64_t missing = 0;
  for (size_t i = r.published_at_injection; i < r.published.size(); ++i) {
    const Published& p = r.published[i];
    if (j < r.log.size() && r.log[j].channel == p.channel && r.log[j].data == p.bytes) {
      ++j;
    } else {
      ++missing;
    }
  }
  *in_order = j == r.log.size();
  return missing;
}

std::vector<std::string> LoggedLines(const FaultRunResult& r, int64_t from, int64_t to) {
  std::vector<std::string> lines;
  for (const telemetry::LogEvent& e : r.log) {
    if (e.utime < from || e.utime > to) continue;
    const auto* d = e.data.data();
    const auto n = e.data.size();
    if (e.channel == channels::kHealth) {
      if (auto h = telemetry::Decode<plantscale_health_t>(e.channel, d, n)) {
        lines.insert(lines.end(), h->faults.begin(), h->faults.end());
      }
    } else if (e.channel == channels::kEvents) {
      if (auto ev = telemetry::Decode<plantscale_event_t>(e.channel, d, n)) {
        lines.push_back(ev->kind + ": " + ev->text);
      }
    }
  }
  return lines;
}

void Check(const Expectation& x, int order) {
  const fs::path dir = fs::temp_directory_path() / "plantscale_fault_test";
  fs::create_directories(dir);
  FaultRunOptions o;
  o.fault = {x.kind, x.start_s, x.end_s};
  o.log = (dir / ("fault" + std::to_string(order) + ".lcmlog")).string();
  const FaultRunResult r = RunWithFault(o);
  Row row;
  row.fault = Describe(x.kind);
  SCOPED_TRACE(row.fault);
  ASSERT_GT(r.onset_utime, 0) << "the fault never met the vehicle";
  ASSERT_GT(r.clear_utime, r.onset_utime);
  ASSERT_GT(r.end_utime, r.clear_utime + 2'500'000) << "too short a run to see the recovery";

  // Spraying before the fault: the grid was tracked and the bar open.
  const auto before = std::count_if(r.ticks.begin(), r.ticks.end(), [&](const TickRecord& t) {
    return t.utime < r.onset_utime && t.utime > r.onset_utime - 1'000'000 && t.open_mask != 0 && !Failsafe(t);
  });
  ASSERT_GT(before, 0) << "no nozzle opened in the second before the fault";

  // When a tick was commanded, for the fault: a bad sample or frame is met
  // by the ticks from its own time on; a broken part by the ticks sent
  // after it broke. The ticks of a frame are computed and sent when the
  // frame is processed (at its capture time on the message clock), so the
  // time to fail-safe is counted to the frame that sent the first closed
  // command, whatever the time the command is stamped with.
  const auto met = [&](const TickRecord& t) { return r.broken_part ? t.frame_utime : t.utime; };
  std::optional<TickRecord> closed;
  int open_during = 0, failsafe_during = 0;
  for (const TickRecord& t : r.ticks) {
    if (met(t) < r.onset_utime || met(t) >= r.clear_utime) continue;
    if (Failsafe(t)) {
      ++failsafe_during;
      if (!closed) closed = t;
    }
    // Commanded open after fail-safe, before the fault cleared.
    if (closed && t.commanded_mask != 0 && x.failsafe_needed) ++open_during;
  }
  if (x.failsafe_needed) {
    ASSERT_TRUE(closed.has_value()) << "never fail-safe";
    const double ms = Ms(std::max(closed->frame_utime, r.onset_utime) - r.onset_utime);
    EXPECT_LE(ms, 100.0) << "fail-safe too late";
    EXPECT_EQ(open_during, 0) << "a nozzle commanded open after fail-safe, before the fault cleared";
    row.failsafe = Fixed(ms, 0) + " ms";
    if (!r.broken_part) row.failsafe += " (ticks closed from " + Fixed(Ms(closed->utime - r.onset_utime), 0) + " ms)";
  } else {
    EXPECT_EQ(failsafe_during, 0) << "fail-safe although the fault does not need it";
    row.failsafe = "not needed: kept spraying";
  }

  // Recovery: fail-safe lifted and nozzles opening again after the fault
  // cleared, the fault's line gone from the heartbeat after its hold.
  std::optional<int64_t> safe_again, open_again;
  for (const TickRecord& t : r.ticks) {
    if (met(t) < r.clear_utime) continue;
    if (!safe_again && !Failsafe(t)) safe_again = met(t);
    if (!open_again && !Failsafe(t) && t.commanded_mask != 0) open_again = met(t);
  }
  ASSERT_TRUE(safe_again.has_value()) << "no recovery";
  ASSERT_TRUE(open_again.has_value()) << "nozzles never opened again";
  EXPECT_LE(Ms(*safe_again - r.clear_utime), 1500.0);
  const std::string spraying = "nozzles opening on the next crop " +
                               Fixed(Ms(std::max<int64_t>(0, *open_again - r.clear_utime)), 0) + " ms after";
  row.recovery = x.failsafe_needed ? "yes: fail-safe lifted " +
                                         Fixed(Ms(std::max<int64_t>(0, *safe_again - r.clear_utime)), 0) +
                                         " ms after it cleared, " + spraying
                                   : "never stopped; " + spraying;
  if (x.kind == FaultKind::kSlipBurst || x.kind == FaultKind::kSpikeWithinLimit) {
    // The guard dead-reckons through it: the distance driven, tracker less
    // truth, moves by a few millimetres over the burst, not by the 15 %
    // (63 mm over 0.6 s) or the spike's 14 mm the wheels claimed.
    EXPECT_GE(r.slip_bursts, 1);
    const auto error_at = [&](int64_t utime) {
      const auto it = std::lower_bound(r.frames.begin(), r.frames.end(), utime,
                                       [](const FrameRecord& f, int64_t u) { return f.utime < u; });
      return it->tracker_distance_m - it->true_distance_m;
    };
    const double drift_mm = 1e3 * std::abs(error_at(r.clear_utime + 200'000) - error_at(r.onset_utime - 100'000));
    EXPECT_LT(drift_mm, 10.0);
    row.recovery += "; distance error moved by " + Fixed(drift_mm, 1) + " mm";
  }
  const FrameRecord& last = r.frames.back();
  EXPECT_FALSE(Holds(last.faults, x.health_text)) << "still reported at the end";

  // The reason on the heartbeat, as the station receives it (within the
  // fault and the 2 s after it), and in the log.
  std::vector<std::string> station;
  for (const plantscale_health_t& h : r.station_health) {
    if (h.utime >= r.onset_utime && h.utime <= r.clear_utime + 2'000'000) {
      station.insert(station.end(), h.faults.begin(), h.faults.end());
    }
  }
  std::string line;
  EXPECT_TRUE(Holds(station, x.health_text, &line)) << "not on the heartbeat: " << x.health_text;
  row.reason = line;
  std::string logged;
  const std::vector<std::string> log_lines = LoggedLines(r, r.onset_utime, r.clear_utime + 2'000'000);
  EXPECT_TRUE(Holds(log_lines, x.log_text, &logged)) << "not in the log: " << x.log_text;
  row.in_log = logged.find("log_resumed: ") == 0 ? "yes: event `log_resumed` and the heartbeat after it"
                                                 : "yes: heartbeat";
  if (x.kind == FaultKind::kStationLinkDown) {
    // The station heard nothing while the link was down; the log has it all.
    int logged_heartbeats = 0, heard = 0;
    for (const telemetry::LogEvent& e : r.log) {
      logged_heartbeats += e.channel == channels::kHealth && e.utime >= r.onset_utime && e.utime < r.clear_utime;
    }
    for (const plantscale_health_t& h : r.station_health) heard += h.utime >= r.onset_utime && h.utime < r.clear_utime;
    EXPECT_EQ(heard, 0);
    EXPECT_GE(logged_heartbeats, 1);
    row.in_log += " (" + std::to_string(logged_heartbeats) + " heartbeats logged while the station heard none)";
  }

  // Nothing logged before the fault is lost, the log reads whole and holds
  // exactly what was published, in order, less what a full disk refused.
  EXPECT_EQ(r.log_error, "");
  row.records_lost = RecordsLost(r);
  EXPECT_EQ(row.records_lost, 0);
  bool in_order = false;
  row.not_logged = NotLogged(r, &in_order);
  EXPECT_TRUE(in_order) << "the log holds what was not published";
  EXPECT_EQ(row.not_logged, r.log_status.not_logged);
  if (x.kind != FaultKind::kDiskFull) {
    EXPECT_EQ(row.not_logged, 0);
  }
  Table()[order] = row;
}

TEST(FaultInjection, CameraFramesStop) {
  Check({FaultKind::kCameraStops, 4.0, 5.0, true, "has no image", "has no image"}, 1);
}

TEST(FaultInjection, CorruptFrame) {
  Check({FaultKind::kCorruptFrame, 4.0, 4.1, true, "px, the calibration is", "px, the calibration is"}, 2);
}

TEST(FaultInjection, NanOdometry) {
  Check({FaultKind::kNanOdometry, 4.0, 4.3, true, "wheel speed is not a number", "wheel speed is not a number"}, 3);
}

TEST(FaultInjection, OdometrySpike) {
  Check({FaultKind::kSpikeOdometry, 4.0, 4.1, true, "beyond 3 m/s", "beyond 3 m/s"}, 4);
}

TEST(FaultInjection, OdometrySpikeWithinLimitsIsGated) {
  Check({FaultKind::kSpikeWithinLimit, 4.0, 4.1, false, "wheel slip", "wheel slip"}, 5);
}

TEST(FaultInjection, SlipBurstIsGated) {
  Check({FaultKind::kSlipBurst, 4.0, 4.6, false, "wheel slip", "wheel slip"}, 6);
}

TEST(FaultInjection, CanWriteErrors) {
  Check({FaultKind::kCanWriteErrors, 4.0, 4.5, true, "failed: Resource temporarily unavailable",
         "failed: Resource temporarily unavailable"},
        7);
}

TEST(FaultInjection, BarStopsAnswering) {
  Check({FaultKind::kBarSilent, 4.0, 5.0, true, "not acknowledged", "not acknowledged"}, 8);
}

TEST(FaultInjection, StationVanishes) {
  Check({FaultKind::kStationLinkDown, 4.0, 5.0, false, "messages not sent", "messages not sent"}, 9);
}

TEST(FaultInjection, DiskFullWhileLogging) {
  Check({FaultKind::kDiskFull, 4.0, 6.0, false, "log: not written", "log_resumed"}, 10);
}

// "2026-11-27 15:52 UTC": when the table was made.
std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", &utc);
  return text;
}

// PLANTSCALE_FAULT_TABLE=FILE: the table of the faults run, in markdown.
class TableWriter : public ::testing::Environment {
 public:
  void TearDown() override {
    const char* path = std::getenv("PLANTSCALE_FAULT_TABLE");
    if (path == nullptr || Table().empty()) return;
    std::ofstream out(path);
    out << "# Fault injection on the simulator, 2026-11-27\n\n"
        << "Made " << UtcNow() << ". "
        << "Issue 35. Each fault injected once into the vehicle process (the product's wiring,\n"
           "`app/vehicle/vehicle_process.h`) on the field preset, seed 1, 7 m at 0.7 m/s, from\n"
           "4.0 s of message time; LCM over memq://, the spray bar over a socketpair to the\n"
           "simulated bar, the log written to a file. The engine is configured from the preset's\n"
           "crop and vehicle profiles, so the fail-safe on uncertainty is on (its default since\n"
           "session 23, docs/fail-safe.md). What each fault is and what the vehicle does:\n"
           "[../faults.md](../faults.md). Made by (build first: `./plantscale.sh test` or\n"
           "`cmake --build build --target fault_test`):\n\n"
           "```\nPLANTSCALE_FAULT_TABLE=docs/results/2026-11-27-fault-injection.md "
           "PLANTSCALE_CONFIG_DIR=config build/tests/fault_test\n```\n\n"
           "Time to fail-safe: from when the fault arose (the bad sample's time, the bad frame's\n"
           "capture, the frame at which the part broke) to the frame whose processing sent the\n"
           "first all-closed command, on the message clock. A frame's scheduler ticks (5 ms) are\n"
           "computed and sent when the frame is processed; for a bad sample or frame the time the\n"
           "first closed tick is stamped with is in brackets. Records lost: messages logged before\n"
           "the fault that are not in the log read back (which reads whole in every run); not\n"
           "logged: messages published while the log could not be written. The same assertions\n"
           "run in ctest (`fault_test`): fail-safe within 100 ms where needed, none where not,\n"
           "the reason on the heartbeat and in the log, recovery, 0 records lost.\n\n";
    out << "| fault | time to fail-safe (message time) | reason on the heartbeat | in the log | "
           "recovery | records lost | not logged during the fault |\n"
           "|---|---|---|---|---|---|---|\n";
    for (const auto& [order, r] : Table()) {
      out << "| " << r.fault << " | " << r.failsafe << " | `" << r.reason << "` | " << r.in_log << " | "
          << r.recovery << " | " << r.records_lost << " | " << r.not_logged << " |\n";
    }
  }
};
[[maybe_unused]] const auto* const kTable = ::testing::AddGlobalTestEnvironment(new TableWriter);

}  // namespace
}  // namespace plantscale::faults
