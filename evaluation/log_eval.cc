#include "evaluation/log_eval.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>

#include "app/config/config_loader.h"
#include "app/config/profiles.h"
#include "engine/common/options.h"
#include "engine/treatment/simulated_bar.h"
#include "evaluation/treatment_score.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"
#include "telemetry/log.h"

namespace plantscale::app {
namespace {

namespace ch = telemetry::channels;
using telemetry::FilterMode;

// What the scoring needs from the log, in log order.
struct Collected {
  std::optional<std::string> run_config;
  int station_commands = 0;  // applied "command" events (pause, start, mode)
  std::vector<LogEvaluation::Said> row_spacing_events;
  std::vector<telemetry::GridEstimate> grid;
  std::map<int, geometry::GridState> truth;  // by frame index
  std::vector<treatment::FieldPose> poses;   // true vehicle pose per frame
  std::vector<telemetry::NozzleShot> shots;
};

template <typename Message>
Message DecodeOrThrow(const telemetry::LogEvent& e) {
  std::string error;
  std::optional<Message> m =
      telemetry::Decode<Message>(e.channel, e.data.data(), e.data.size(), &error);
  if (!m) throw DataError(error);
  return std::move(*m);
}

void Take(const telemetry::LogEvent& e, Collected& c, LogMessages& n) {
  if (e.channel == ch::kEvents) {
    const auto m = DecodeOrThrow<plantscale_event_t>(e);
    if (m.kind == "run_config" && !c.run_config) c.run_config = m.text;
    c.station_commands += m.kind == "command";
    if (m.kind == "row_spacing_mismatch") c.row_spacing_events.push_back({m.utime, m.text});
  } else if (e.channel == ch::kGrid) {
    c.grid.push_back(telemetry::FromLcm(DecodeOrThrow<plantscale_grid_state_t>(e)));
    ++n.grid;
  } else if (e.channel == ch::kSimTruth) {
    const telemetry::GridEstimate t = telemetry::FromLcm(DecodeOrThrow<plantscale_grid_state_t>(e));
    c.truth[t.frame_index] = t.state;
    ++n.truth;
  } else if (e.channel == ch::kSimTruthPose) {
    const auto m = DecodeOrThrow<plantscale_pose_t>(e);
    const telemetry::Pose p = telemetry::FromLcm(m);
    c.poses.push_back({m.utime, p.x_m, p.y_m, p.heading_rad});
    ++n.truth_pose;
  } else if (e.channel == ch::kNozzles) {
    const telemetry::NozzleBar bar = telemetry::FromLcm(DecodeOrThrow<plantscale_nozzles_t>(e));
    c.shots.insert(c.shots.end(), bar.shots.begin(), bar.shots.end());
    ++n.nozzles;
  }
}

Collected Read(const std::filesystem::path& log, LogEvaluation& result) {
  telemetry::LogReader reader(log);
  Collected c;
  while (const std::optional<telemetry::LogEvent> e = reader.Next()) {
    ++result.messages.events;
    try {
      Take(*e, c, result.messages);
    } catch (const std::exception& ex) {
      if (++result.messages.undecodable <= 10) {
        result.problems.push_back("event " + std::to_string(e->eventnum) + " on " + e->channel +
                                  ": " + ex.what() + " (skipped)");
      }
    }
  }
  if (result.messages.events == 0) {
    throw telemetry::LogError(reader.error().empty() ? log.string() + ": no LCM events"
                                                     : reader.error());
  }
  if (!reader.error().empty()) {
    result.problems.push_back(reader.error() + " (scored up to the last whole event)");
  }
  if (c.station_commands > 0) {
    result.problems.push_back(
        "the station commanded the run " + std::to_string(c.station_commands) +
        " time(s) (pause, mode): scored as a run spraying the crop throughout");
  }
  std::stable_sort(c.poses.begin(), c.poses.end(),
                   [](const auto& a, const auto& b) { return a.utime < b.utime; });
  return c;
}

// The bar's commands behind the logged shots: at every opening and closing,
// the mask of the nozzles open from then on. A SimulatedBar given them makes
// the same shots as the scheduler's own commands (it only looks at changes).
void CommandBar(const std::vector<telemetry::NozzleShot>& shots, int nozzles,
                treatment::SimulatedBar& bar, LogEvaluation& result) {
  std::map<int64_t, std::vector<std::pair<int, bool>>> changes;  // utime → (nozzle, opens)
  int bad = 0;
  for (const telemetry::NozzleShot& s : shots) {
    if (s.nozzle < 0 || s.nozzle >= nozzles || s.close_utime <= s.open_utime) {
      ++bad;
      continue;
    }
    changes[s.open_utime].push_back({s.nozzle, true});
    changes[s.close_utime].push_back({s.nozzle, false});
  }
  if (bad > 0) {
    result.problems.push_back(std::to_string(bad) +
                              " shot(s) of a nozzle the bar does not have, "
                              "or not closing after they open (skipped)");
  }
  uint64_t mask = 0;
  for (const auto& [utime, at] : changes) {
    for (const auto& [nozzle, opens] : at) {  // closings first: a nozzle may reopen at once
      if (!opens) mask &= ~(uint64_t{1} << nozzle);
    }
    for (const auto& [nozzle, opens] : at) {
      if (opens) mask |= uint64_t{1} << nozzle;
    }
    bar.Command(utime, mask);
  }
}

bool Tracked(FilterMode m) { return m == FilterMode::kTracking || m == FilterMode::kDeadReckoning; }

// Path length driven along the true pose track, at any time (interpolated),
// from where the vehicle started (x = start_offset_m, y = 0: the simulator's
// distance_m, which the evaluations measure with).
class PathDistance {
 public:
  PathDistance(const std::vector<treatment::FieldPose>& poses, const sim::VehicleOptions& vehicle)
      : poses_(poses) {
    for (size_t i = 0; i < poses.size(); ++i) {
      const double x0 = i > 0 ? poses[i - 1].x_m : vehicle.start_offset_m;
      const double y0 = i > 0 ? poses[i - 1].y_m : 0.0;
      cumulative_.push_back((i > 0 ? cumulative_.back() : 0.0) +
                            std::hypot(poses[i].x_m - x0, poses[i].y_m - y0));
    }
  }
  double At(int64_t utime) const {
    if (poses_.empty()) return 0.0;
    const auto it =
        std::upper_bound(poses_.begin(), poses_.end(), utime,
                         [](int64_t t, const treatment::FieldPose& p) { return t < p.utime; });
    if (it == poses_.begin()) return 0.0;
    if (it == poses_.end()) return cumulative_.back();
    const auto i = static_cast<size_t>(it - poses_.begin());
    const double f = static_cast<double>(utime - poses_[i - 1].utime) /
                     static_cast<double>(poses_[i].utime - poses_[i - 1].utime);
    return cumulative_[i - 1] + f * (cumulative_[i] - cumulative_[i - 1]);
  }
  double total() const { return cumulative_.empty() ? 0.0 : cumulative_.back(); }

 private:
  const std::vector<treatment::FieldPose>& poses_;
  std::vector<double> cumulative_;
};

TreatmentMetrics ScoreTreatment(const Collected& c, const sim::Simulator& simulator,
                                LogEvaluation& result) {
  // The bar of the vehicle profile the run was published with (the
  // preset's by name in logs from before profiles).
  const Profiles profiles = LoadProfiles(result.run.crop, result.run.vehicle,
                                         simulator.options().preset, result.config_dir);
  const treatment::TreatmentOptions t = ProductTreatmentOptions(profiles);
  // The true valves open as scheduled (evaluate treatment without --true-latency-ms).
  treatment::SimulatedBar bar(t.scheduler.bar, t.scheduler.bar.valve_latency_s, t.scheduler.tick_s);
  CommandBar(c.shots, t.scheduler.bar.nozzles, bar, result);
  const std::vector<treatment::Shot> shots = bar.Shots(c.poses);
  const auto first = std::find_if(c.grid.begin(), c.grid.end(),
                                  [](const telemetry::GridEstimate& g) { return Tracked(g.mode); });
  TreatmentMetrics m;
  if (first == c.grid.end()) {
    result.problems.push_back("the grid was never tracked: nothing classified, nothing scored");
  } else {
    const double first_classified_y = treatment::Interpolate(c.poses, first->utime).y_m;
    const SprayScoreRegion region =
        TreatmentScoreRegion(simulator, first_classified_y, c.poses.back().y_m, t);
    m = SprayMetrics(ScoreSpray(simulator.field(), shots, region));
  }
  m.shots = static_cast<int>(shots.size());
  bool tracked = false;
  for (const telemetry::GridEstimate& g : c.grid) {
    m.frames_classified += Tracked(g.mode);
    m.map_resets += Tracked(g.mode) && !tracked;  // each (re)initialisation starts a new map
    tracked = Tracked(g.mode);
  }
  return m;
}

TrackingMetrics ScoreTracking(const Collected& c, const sim::VehicleOptions& vehicle,
                              const LogEvalOptions& options, LogEvaluation& result) {
  const PathDistance distance(c.poses, vehicle);
  TrackingMetrics m;
  std::vector<double> init_frames;
  int init_trials = 0, init_successes = 0, spacing_frames = 0;
  bool ever_tracked = false, was_tracked = false;
  double init_distance_m = 0.0, estimated_m = 0.0, last_distance_m = 0.0;
  const telemetry::GridEstimate* previous = nullptr;
  for (size_t i = 0; i < c.grid.size(); ++i) {
    const telemetry::GridEstimate& g = c.grid[i];
    const auto truth = c.truth.find(g.frame_index);
    const bool tracked = Tracked(g.mode);
    if (tracked && !ever_tracked) {
      ever_tracked = true;
      init_distance_m = distance.At(g.utime);
      ++init_trials;
      init_frames.push_back(static_cast<double>(i + 1));
      if (truth != c.truth.end() && InitialisedOnTruth(g.state, truth->second)) ++init_successes;
    }
    if (was_tracked && g.mode == FilterMode::kLost) ++m.losses;
    // The forward distance the tracker has driven: Y falls as the vehicle
    // moves on and rises by l̄ at each plant line passed.
    if (tracked && was_tracked && previous != nullptr) {
      estimated_m -=
          std::remainder(g.state.forward_m - previous->state.forward_m, g.state.plant_spacing_m);
    }
    was_tracked = tracked;
    previous = &g;
    if (!tracked) continue;
    last_distance_m = distance.At(g.utime);
    ++m.frames_tracking;
    m.updates += g.mode == FilterMode::kTracking;
    m.mean_matched += g.validated;  // sums until FinishTrackingMetrics
    const double past = last_distance_m - init_distance_m;
    if (past < options.settle_m) continue;
    if (truth == c.truth.end()) {
      ++result.messages.grid_without_truth;
      continue;
    }
    const geometry::GridState& t = truth->second;
    const GridErrors e = ScoreGrid(g.state, g.covariance.topLeftCorner<3, 3>(), t);
    ++m.frames;
    m.lateral_rmse_m += e.lateral_m * e.lateral_m;
    m.lateral_mean_m += e.lateral_m;
    m.forward_mean_m += e.forward_m;
    m.bearing_rmse_deg += e.bearing_rad * e.bearing_rad;
    m.lateral_sd_mean_m += e.lateral_sd_m;
    m.nees_mean += e.nees;
    m.normalised_error2 += e.normalised2;
    m.nees_in_bounds_fraction += e.nees_in_bounds;
    if (past >= options.spacing_settle_m) {
      const double row = g.state.row_spacing_m - t.row_spacing_m;
      const double plant = g.state.plant_spacing_m - t.plant_spacing_m;
      m.row_spacing_error_m += row * row;
      m.row_spacing_mean_error_m += row;
      m.plant_spacing_error_m += plant * plant;
      m.plant_spacing_mean_error_m += plant;
      ++spacing_frames;
    }
  }
  const double driven_m = last_distance_m - init_distance_m;
  m.run_lateral_rmse_m.push_back(m.frames > 0 ? std::sqrt(m.lateral_rmse_m / m.frames)
                                              : std::nan(""));
  m.run_forward_drift_cm_per_m.push_back(driven_m > 0 ? 100.0 * (estimated_m - driven_m) / driven_m
                                                      : std::nan(""));
  FinishTrackingMetrics(m, spacing_frames, init_frames, init_trials, init_successes);
  return m;
}

std::filesystem::path ConfigDirFor(const LogEvalOptions& options, const SimRunConfig& run) {
  if (!options.config_dir.empty()) return options.config_dir;
  std::error_code ec;
  if (!run.config_dir.empty() && std::filesystem::is_directory(run.config_dir, ec)) {
    return run.config_dir;
  }
  return DefaultConfigDir();
}

}  // namespace

const std::vector<std::string>& TreatmentKeysNotInLogs() {
  static const std::vector<std::string> keys = {
      "crop_pixel_rate", "crop_pixel_rate_of_plant", "weed_pixel_fpr_of_plant", "pixels",
      "ticks",           "ticks_fail_safe",          "plants_recorded",         "plants_confirmed"};
  return keys;
}

LogEvaluation EvaluateLog(const LogEvalOptions& options) {
  LogEvaluation result;
  result.log = options.log.string();
  const Collected c = Read(options.log, result);
  if (!c.run_config) {
    throw ConfigError(result.log, "run_config",
                      "the log has no run_config event (PLANTSCALE_EVENTS), so the simulated run "
                      "cannot be rebuilt: evaluate log scores logs of `plantscale simulate "
                      "--publish --log`, not of `plantscale run` or of builds before run_config");
  }
  result.run = ParseRunConfig(*c.run_config, result.log);
  if (c.truth.empty() || c.poses.empty()) {
    throw ConfigError(result.log, ch::kSimTruth,
                      std::string("no simulator truth (") + ch::kSimTruth + " and " +
                          ch::kSimTruthPose + ") to score against");
  }
  result.config_dir = ConfigDirFor(options, result.run);
  const sim::Simulator simulator(SimulatorOptionsOf(result.run, result.config_dir));
  result.distance_m = PathDistance(c.poses, simulator.options().vehicle).total();
  result.messages.shots = static_cast<int>(c.shots.size());
  result.treatment = ScoreTreatment(c, simulator, result);
  result.tracking = ScoreTracking(c, simulator.options().vehicle, options, result);
  result.row_spacing_events = c.row_spacing_events;
  result.tracking.row_spacing_events = c.row_spacing_events.empty() ? 0 : 1;  // runs with one
  return result;
}

}  // namespace plantscale::app
