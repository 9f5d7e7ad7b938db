#include "evaluation/tracking_eval.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/common/stats.h"
#include "engine/pipeline/pipeline.h"
#include "engine/tracking/blob_features.h"
#include "engine/tracking/state_layout.h"
#include "evaluation/seeds.h"

namespace plantscale::app {

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;
// Two-sided 95 % interval of χ² with 3 degrees of freedom.
constexpr double kNeesLow = 0.2158;
constexpr double kNeesHigh = 9.3484;

// Each plant line's planted y and the mean deviation across of its crops'
// roots from their planted rows (what a rule laid across the line reads,
// thesis fig. 8.1).
struct PlantLineReference {
  std::vector<double> y_m;
  std::vector<double> mean_root_dev_m;  // NaN: no crop in the line
};

PlantLineReference PlantLines(const sim::Field& field) {
  PlantLineReference r;
  r.y_m = field.line_y_m();
  std::vector<double> sum(r.y_m.size(), 0.0);
  std::vector<int> n(r.y_m.size(), 0);
  for (const sim::Plant& p : field.plants()) {
    if (p.cls != sim::PlantClass::kCrop || p.line < 0 || p.line >= static_cast<int>(r.y_m.size()))
      continue;
    sum[p.line] += p.position_m.x() - field.RowX(p.row, r.y_m[p.line]);
    ++n[p.line];
  }
  r.mean_root_dev_m.resize(r.y_m.size());
  for (size_t i = 0; i < r.y_m.size(); ++i) {
    r.mean_root_dev_m[i] = n[i] > 0 ? sum[i] / n[i] : std::nan("");
  }
  return r;
}

TrackingRun::CalibrationEstimate CalibrationOf(const tracking::GridTracker& tracker) {
  TrackingRun::CalibrationEstimate c;
  if (!tracker.options().CalibrationStates()) return c;
  const Eigen::Vector4d prior = tracking::CalibrationPrior(tracker.options());  // variances
  const Eigen::Vector4d value = tracker.calibration_estimate();
  const Eigen::Vector4d sd = tracker.calibration_covariance().diagonal().cwiseMax(0.0).cwiseSqrt();
  for (int i = 0; i < 4; ++i) {
    if (prior(i) > 0.0) {  // a state with no prior is not carried
      c.value(i) = value(i);
      c.sd(i) = sd(i);
    }
  }
  return c;
}

// One tracker under test on one run, with its error sums.
struct Scorer {
  geometry::CameraModel camera;  // the engine's (the vehicle's calibration), not the simulator's
  pipeline::Pipeline pipe;  // segmentation and tracking
  const tracking::GridTracker& tracker;
  const TrackingEvalOptions& options;
  std::ostream* trace = nullptr;  // ours only
  uint64_t seed = 0;
  CalibrationError calibration_error;  // the seed's draw
  std::span<const tracking::Feature> features;  // the last frame's, as the tracker measured them
  bool ever_tracked = false;
  double init_distance_m = 0.0;
  int start_frame = 0;
  // Sums.
  double lat2 = 0.0, lat = 0.0, bear2 = 0.0, sd = 0.0, nees = 0.0;
  Eigen::Vector3d normalised2 = Eigen::Vector3d::Zero();
  int scored = 0, nees_in = 0;
  int lost_scored = 0;  // of `scored`, frames on which the grid was lost
  double row2 = 0.0, plant2 = 0.0, row1 = 0.0, plant1 = 0.0, fwd = 0.0;
  int spacing_scored = 0;
  int tracking_frames = 0, updates = 0, losses = 0;
  double matched = 0.0;
  // The thesis's field protocol (§8.1, fig. 8.1): the offset at each line of
  // plants against the mean root position of that line's plants.
  const PlantLineReference* lines = nullptr;
  size_t next_line = 0;
  double line_lat2 = 0.0, line_lat = 0.0;
  int lines_scored = 0;
  std::vector<double> init_frames;
  int init_trials = 0, init_successes = 0;
  int fault_frames = 0, fault_tracking = 0, fault_losses = 0;
  std::vector<RowSpacingEvent> row_spacing_events;
  TrackingRun::CalibrationEstimate calibration_at_20m;
  double fault_lat2 = 0.0, fault_fwd2 = 0.0;

  Scorer(const geometry::CameraOptions& camera_options,
         const tracking::TrackerOptions& tracker_options,
         const vision::SegmenterOptions& segmenter_options, const TrackingEvalOptions& o,
         bool visual)
      : camera(camera_options),
        pipe(camera, Options(segmenter_options, tracker_options, o, visual)),
        tracker(pipe.tracker()),
        options(o) {}

  static pipeline::PipelineOptions Options(const vision::SegmenterOptions& segmenter,
                                           const tracking::TrackerOptions& tracker,
                                           const TrackingEvalOptions& o, bool visual) {
    pipeline::PipelineOptions p;
    p.segmenter = segmenter;
    p.tracker = tracker;
    p.treat = false;
    if (visual) p.motion = VisualMotionOptions(*o.profiles);
    return p;
  }

  // Over the faulty stretch: tracking or not, lost, errors.
  void ScoreFault(const sim::SimFrame& frame, bool was_tracking, const geometry::GridState& est) {
    if (!options.odometry_fault.Active(frame.truth.distance_m)) return;
    ++fault_frames;
    if (was_tracking && tracker.mode() == tracking::TrackerMode::kLost) ++fault_losses;
    if (tracker.mode() != tracking::TrackerMode::kTracking) return;
    ++fault_tracking;
    const GridErrors g = ScoreGrid(est, tracker.covariance().topLeftCorner<3, 3>(), frame.truth.grid);
    fault_lat2 += g.lateral_m * g.lateral_m;
    fault_fwd2 += g.forward_m * g.forward_m;
  }

  void AddOdometry(const sim::OdometrySample& o) {
    pipe.AddOdometry({o.utime, o.left_m_s, o.right_m_s});
  }

  void Frame(const sim::SimFrame& frame, int index) {
    const bool was_tracking = tracker.mode() == tracking::TrackerMode::kTracking;
    const pipeline::FrameResult& f =
        pipe.ProcessFrame(frame.truth.utime, frame.truth.index, frame.rendered.image);
    const tracking::FrameReport& r = f.report;
    features = f.track_features;
    const geometry::GridState est = f.state;
    const geometry::GridState& truth = frame.truth.grid;
    if (r.initialised_now && !ever_tracked) {
      ever_tracked = true;
      init_distance_m = frame.truth.distance_m;
      ++init_trials;
      init_frames.push_back(index - start_frame + 1);
      if (InitCorrect(est, truth)) ++init_successes;
    }
    if (was_tracking && tracker.mode() == tracking::TrackerMode::kLost) ++losses;
    if (r.row_spacing_mismatch) {
      row_spacing_events.push_back({frame.truth.distance_m, frame.truth.distance_m - init_distance_m,
                                    truth.row_spacing_m, *r.row_spacing_mismatch});
    }
    ScoreFault(frame, was_tracking, est);
    const double past = frame.truth.distance_m - init_distance_m;
    if (ever_tracked && past >= 20.0 && std::isnan(calibration_at_20m.value(0))) {
      calibration_at_20m = CalibrationOf(tracker);
    }
    if (tracker.mode() != tracking::TrackerMode::kTracking) {
      if (ever_tracked && past >= options.settle_m) ScoreLost(est, truth);
      return;
    }
    ++tracking_frames;
    if (r.updated) ++updates;
    matched += r.matched;
    if (past < options.settle_m) return;
    if (lines != nullptr) ScoreLines(frame, f.state);
    const Eigen::Matrix3d p = tracker.covariance().topLeftCorner<3, 3>();
    const GridErrors g = ScoreGrid(est, p, truth);
    const double e_lat = g.lateral_m, e_fwd = g.forward_m, e_bear = g.bearing_rad, n = g.nees;
    AddErrors(g);
    sd += g.lateral_sd_m;
    nees += n;
    normalised2 += g.normalised2;
    nees_in += g.nees_in_bounds;
    if (trace) {
      *trace << seed << ',' << index << ',' << frame.truth.distance_m << ',' << e_lat << ','
             << e_fwd << ',' << e_bear << ',' << std::sqrt(p(0, 0)) << ',' << std::sqrt(p(1, 1))
             << ',' << std::sqrt(p(2, 2)) << ',' << est.row_spacing_m << ','
             << truth.row_spacing_m << ',' << est.plant_spacing_m << ','
             << truth.plant_spacing_m << ',' << r.matched << ',' << tracker.odometry_scale()
             << ',' << n << ',' << tracker.forward_distance_m() << ',' << past << '\n';
    }
    if (past >= options.spacing_settle_m) {
      row2 += std::pow(est.row_spacing_m - truth.row_spacing_m, 2);
      row1 += est.row_spacing_m - truth.row_spacing_m;
      plant1 += est.plant_spacing_m - truth.plant_spacing_m;
      plant2 += std::pow(est.plant_spacing_m - truth.plant_spacing_m, 2);
      ++spacing_scored;
    }
  }

  // A frame after the first start on which the grid is lost (or starting
  // again): every run counts, so the estimate the tracker holds (dead
  // reckoned from its last update) is scored until it recovers, and the
  // frame is outside the NEES bounds (the filter no longer vouches for it).
  // Its σ and NEES stay out of the means of the filter's own figures.
  void ScoreLost(const geometry::GridState& est, const geometry::GridState& truth) {
    AddErrors(GridErrorsOf(est, truth));
    ++lost_scored;
  }

  // A scored frame's errors into the sums of every frame (tracking or lost).
  void AddErrors(const GridErrors& g) {
    lat += g.lateral_m;
    fwd += g.forward_m;
    lat2 += g.lateral_m * g.lateral_m;
    bear2 += g.bearing_rad * g.bearing_rad;
    ++scored;
  }

  // Lines the vehicle's ground point passed since the last frame scored:
  // the estimate against the trail (the true position) read from the mean
  // root position of the line's plants.
  void ScoreLines(const sim::SimFrame& frame, const geometry::GridState& est) {
    const sim::Pose2& p = frame.truth.pose;
    const double c = std::cos(p.heading_rad);
    while (next_line < lines->y_m.size() && lines->y_m[next_line] <= p.y_m) {
      const size_t i = next_line++;
      // Only lines passed since the previous frame (not those before the
      // scoring started).
      if (lines->y_m[i] <= p.y_m - 0.5 * options.sim.vehicle.speed_m_s) continue;
      const double dev = lines->mean_root_dev_m[i];
      if (!std::isfinite(dev)) continue;
      const double e = est.offset_m - (-(p.x_m - dev) / c);
      line_lat += e;
      line_lat2 += e * e;
      ++lines_scored;
    }
  }

  static bool InitCorrect(const geometry::GridState& est, const geometry::GridState& truth) {
    return InitialisedOnTruth(est, truth);
  }
};

// Fresh initialisations at intervals along the run: frames to initialise
// and whether the grid it started on was the right one.
struct InitProbe {
  geometry::CameraModel camera;
  tracking::GridTracker tracker;
  bool active = false;
  int start = 0;
  double next_at_m = 0.0;

  InitProbe(const geometry::CameraOptions& c, const tracking::TrackerOptions& o)
      : camera(c), tracker(camera, o) {}
};

double run_lateral_rmse_or_nan(const Scorer& s) {
  return s.scored > 0 ? std::sqrt(s.lat2 / s.scored) : std::nan("");
}

void Accumulate(const Scorer& s, double driven_m, double estimated_m, TrackingMetrics& m,
                std::vector<double>& init_frames, int& init_trials, int& init_successes) {
  m.frames += s.scored;
  m.frames_lost += s.lost_scored;
  m.frames_tracking += s.tracking_frames;
  m.updates += s.updates;
  m.losses += s.losses;
  m.lateral_rmse_m += s.lat2;  // sums until Finish
  m.lateral_mean_m += s.lat;
  m.forward_mean_m += s.fwd;
  m.row_spacing_mean_error_m += s.row1;
  m.plant_spacing_mean_error_m += s.plant1;
  m.bearing_rmse_deg += s.bear2;
  m.lateral_sd_mean_m += s.sd;
  m.nees_mean += s.nees;
  m.normalised_error2 += s.normalised2;
  m.nees_in_bounds_fraction += s.nees_in;
  m.row_spacing_error_m += s.row2;
  m.plant_spacing_error_m += s.plant2;
  m.mean_matched += s.matched;
  m.run_lateral_rmse_m.push_back(s.scored > 0 ? std::sqrt(s.lat2 / s.scored) : std::nan(""));
  TrackingRun run;
  run.seed = s.seed;
  run.calibration_error = s.calibration_error;
  run.started = s.ever_tracked;
  run.frames = s.scored;
  run.frames_lost = s.lost_scored;
  run.losses = s.losses;
  run.lateral_rmse_m = run_lateral_rmse_or_nan(s);
  run.nees_in_bounds_fraction = s.scored > 0 ? static_cast<double>(s.nees_in) / s.scored : 0.0;
  run.row_spacing_events = s.row_spacing_events;
  run.calibration_at_20m = s.calibration_at_20m;
  if (s.ever_tracked) run.calibration_at_end = CalibrationOf(s.tracker);
  m.row_spacing_events += s.row_spacing_events.empty() ? 0 : 1;
  m.runs.push_back(run);
  m.runs_not_started += s.ever_tracked ? 0 : 1;
  m.plant_lines_scored += s.lines_scored;
  m.plant_line_lateral_rmse_m += s.line_lat2;  // sums until Finish
  m.plant_line_lateral_mean_m += s.line_lat;
  m.run_plant_line_lateral_rmse_m.push_back(
      s.lines_scored > 0 ? std::sqrt(s.line_lat2 / s.lines_scored) : std::nan(""));
  m.run_forward_drift_cm_per_m.push_back(driven_m > 0 ? 100.0 * (estimated_m - driven_m) / driven_m
                                                      : std::nan(""));
  init_frames.insert(init_frames.end(), s.init_frames.begin(), s.init_frames.end());
  init_trials += s.init_trials;
  init_successes += s.init_successes;
  m.fault_frames += s.fault_frames;
  m.fault_frames_tracking += s.fault_tracking;
  m.fault_losses += s.fault_losses;
  m.fault_lateral_rmse_m += s.fault_lat2;  // sums until Finish
  m.fault_forward_rmse_m += s.fault_fwd2;
  m.camera_substitutions += s.pipe.camera_substitutions();
  const tracking::GridTracker::PlantSpread& spread = s.tracker.measured_plant_spread();
  m.plant_spread.across_sum2 += spread.across_sum2;
  m.plant_spread.along_sum2 += spread.along_sum2;
  m.plant_spread.across += spread.across;
  m.plant_spread.along += spread.along;
}

}  // namespace

void FinishTrackingMetrics(TrackingMetrics& m, int spacing_frames,
                           const std::vector<double>& init_frames, int init_trials,
                           int init_successes) {
  const double n = std::max(1, m.frames);
  // The filter's own figures (σ, NEES) over the frames it vouched for.
  const double vouched = std::max(1, m.frames - m.frames_lost);
  m.lateral_rmse_m = std::sqrt(m.lateral_rmse_m / n);
  const double lines = std::max(1, m.plant_lines_scored);
  m.plant_line_lateral_rmse_m = std::sqrt(m.plant_line_lateral_rmse_m / lines);
  m.plant_line_lateral_mean_m /= lines;
  m.lateral_mean_m /= n;
  m.forward_mean_m /= n;
  m.row_spacing_mean_error_m /= std::max(1, spacing_frames);
  m.plant_spacing_mean_error_m /= std::max(1, spacing_frames);
  m.bearing_rmse_deg = std::sqrt(m.bearing_rmse_deg / n) * kDeg;
  m.lateral_sd_mean_m /= vouched;
  m.nees_mean /= vouched;
  m.normalised_error2 /= vouched;
  m.nees_in_bounds_fraction /= n;
  m.row_spacing_error_m = std::sqrt(m.row_spacing_error_m / std::max(1, spacing_frames));
  m.plant_spacing_error_m = std::sqrt(m.plant_spacing_error_m / std::max(1, spacing_frames));
  m.mean_matched /= std::max(1, m.frames_tracking);
  double sum = 0.0;
  double worst = 0.0;
  for (double d : m.run_forward_drift_cm_per_m) {
    sum += d;
    worst = std::max(worst, std::abs(d));
  }
  m.forward_drift_cm_per_m = m.run_forward_drift_cm_per_m.empty()
                                 ? 0.0
                                 : sum / static_cast<double>(m.run_forward_drift_cm_per_m.size());
  m.forward_drift_abs_max_cm_per_m = worst;
  m.init_trials = init_trials;
  m.init_success_rate = init_trials > 0 ? static_cast<double>(init_successes) / init_trials : 0.0;
  m.init_frames_p95 = Percentile(init_frames, 0.95);
  m.fault_lateral_rmse_m = std::sqrt(m.fault_lateral_rmse_m / std::max(1, m.fault_frames_tracking));
  m.fault_forward_rmse_m = std::sqrt(m.fault_forward_rmse_m / std::max(1, m.fault_frames_tracking));
}

GridErrors GridErrorsOf(const geometry::GridState& est, const geometry::GridState& truth) {
  GridErrors g;
  g.lateral_m = est.offset_m - truth.offset_m;
  g.bearing_rad = est.bearing_rad - truth.bearing_rad;
  g.forward_m = std::remainder(est.forward_m - truth.forward_m, truth.plant_spacing_m);
  return g;
}

GridErrors ScoreGrid(const geometry::GridState& est, const Eigen::Matrix3d& p,
                     const geometry::GridState& truth) {
  GridErrors g = GridErrorsOf(est, truth);
  g.lateral_sd_m = std::sqrt(p(0, 0));
  const Eigen::Vector3d e(g.lateral_m, g.forward_m, g.bearing_rad);
  g.nees = e.dot(p.ldlt().solve(e));
  g.normalised2 = e.cwiseAbs2().cwiseQuotient(p.diagonal());
  g.nees_in_bounds = g.nees >= kNeesLow && g.nees <= kNeesHigh;
  return g;
}

bool InitialisedOnTruth(const geometry::GridState& est, const geometry::GridState& truth) {
  return std::abs(est.offset_m - truth.offset_m) < 0.25 * truth.row_spacing_m &&
         std::abs(std::remainder(est.forward_m - truth.forward_m, truth.plant_spacing_m)) <
             0.25 * truth.plant_spacing_m &&
         std::abs(est.bearing_rad - truth.bearing_rad) < 0.035;
}

OptionErrors TrackingEvalOptions::Validate() const {
  OptionErrors e = Prefixed("sim", sim.Validate());
  if (!profiles) e.push_back({"profiles", "required (a crop and a vehicle profile)"});
  if (seeds < 1) e.push_back({"seeds", "must be >= 1"});
  RequireInRange(e, "spacing_offset_m", spacing_offset_m, -0.1, 0.1);
  RequireNonNegative(e, "settle_m", settle_m);
  RequireNonNegative(e, "spacing_settle_m", spacing_settle_m);
  RequirePositive(e, "init_probe_interval_m", init_probe_interval_m);
  if (init_probe_max_frames < 1) e.push_back({"init_probe_max_frames", "must be >= 1"});
  return e;
}

TrackingEngine TrackingEngineOf(const TrackingEvalOptions& options, uint64_t seed) {
  if (!options.profiles) throw InvalidOptionsError("evaluate tracking", {{"profiles", "required"}});
  const Profiles& p = *options.profiles;
  TrackingEngine e;
  e.calibration_error = DrawnCalibrationError(options.calibration_error, seed);
  e.camera = ApplyCalibrationError(EngineCamera(p), e.calibration_error);
  e.ours = ProductTrackerOptions(p);
  e.ours.row_spacing_m += options.spacing_offset_m;
  e.ours.plant_spacing_m += options.spacing_offset_m;
  if (options.centroids_on_virtual_plane) e.ours.crop_radius_m = e.ours.crop_height_m = 0.0;
  if (options.calibration_scale_consider) {
    e.ours.calibration_pitch_sd_rad = p.vehicle.calibration_tilt_sd_rad;
    e.ours.calibration_height_sd_m = p.vehicle.calibration_height_sd_m;
    e.ours.calibration_focal_sd = p.vehicle.calibration_focal_sd;
    e.ours.calibration_scale_consider = true;
  }
  e.thesis = ThesisTrackerOptions(p);
  return e;
}

namespace {

// One chain's figures over the seeds, before FinishTrackingMetrics.
struct ChainTally {
  TrackingMetrics metrics;
  std::vector<double> init_frames;
  int init_trials = 0, init_successes = 0, spacing_frames = 0;

  void Add(const Scorer& s, double last_distance_m) {
    Accumulate(s, last_distance_m - s.init_distance_m, s.tracker.forward_distance_m(), metrics,
               init_frames, init_trials, init_successes);
    spacing_frames += s.spacing_scored;
  }
  void Finish() {
    FinishTrackingMetrics(metrics, spacing_frames, init_frames, init_trials, init_successes);
  }
};

const char* const kTraceHeader =
    "seed,frame,distance_m,offset_error_m,forward_error_m,bearing_error_rad,"
    "offset_sd_m,forward_sd_m,bearing_sd_rad,row_spacing_m,true_row_spacing_m,"
    "plant_spacing_m,true_plant_spacing_m,matched,odometry_scale,nees,"
    "forward_distance_m,true_distance_m\n";

// The initialisation probe: every init_probe_interval_m a fresh tracker
// starts from ours's features of the frame, and counts a trial when it
// initialises (a success when it is right) or runs out of frames.
void StepProbe(InitProbe& probe, const sim::SimFrame& frame, int index, const Scorer& ours,
               const TrackingEvalOptions& options, ChainTally& tally) {
  if (!probe.active && frame.truth.distance_m >= probe.next_at_m) {
    probe.tracker.Reset();
    probe.active = true;
    probe.start = index;
    probe.next_at_m += options.init_probe_interval_m;
  }
  if (!probe.active) return;
  const tracking::FrameReport r = probe.tracker.ProcessFrame(
      frame.truth.utime, frame.rendered.image.cols, frame.rendered.image.rows, ours.features);
  const int frames = index - probe.start + 1;
  if (r.initialised_now) {
    ++tally.init_trials;
    tally.init_frames.push_back(frames);
    if (Scorer::InitCorrect(probe.tracker.state(), frame.truth.grid)) ++tally.init_successes;
    probe.active = false;
  } else if (frames >= options.init_probe_max_frames) {
    ++tally.init_trials;  // a failure
    probe.active = false;
  }
}

// Drives one seed through the scorers and the probe; returns the distance
// driven. Odometry up to the frame's capture goes in before the frame, the
// rest after it, so that the estimate is scored at the time of its truth.
double DriveSeed(const TrackingEvalOptions& options, sim::Simulator& simulator, Scorer& ours,
                 std::optional<Scorer>& thesis, InitProbe& probe, ChainTally& ours_tally) {
  sim::SimFrame frame;
  int index = 0;
  double last_distance = 0.0;
  std::vector<sim::OdometrySample> later;
  const auto add = [&](sim::OdometrySample o) {
    if (!ApplyOdometryFault(options.odometry_fault, frame.truth.distance_m, o)) return;
    ours.AddOdometry(o);
    if (thesis) thesis->AddOdometry(o);
    probe.tracker.AddOdometry(o.utime, o.left_m_s, o.right_m_s);
  };
  while (simulator.Next(frame)) {
    for (const sim::OdometrySample& o : later) add(o);
    later.clear();
    for (const sim::OdometrySample& o : frame.odometry) {
      if (o.utime <= frame.truth.utime) {
        add(o);
      } else {
        later.push_back(o);
      }
    }
    ours.Frame(frame, index);
    if (thesis) thesis->Frame(frame, index);
    StepProbe(probe, frame, index, ours, options, ours_tally);
    last_distance = frame.truth.distance_m;
    ++index;
  }
  return last_distance;
}

// With the plant-lines reference the lateral figures are those scored at
// each line of plants (thesis §8.1); the grid's stay beside them.
TrackingMetrics AtReference(TrackingMetrics m, TrackingReference reference) {
  if (reference != TrackingReference::kPlantLines) return m;
  m.lateral_rmse_m = m.plant_line_lateral_rmse_m;
  m.lateral_mean_m = m.plant_line_lateral_mean_m;
  m.run_lateral_rmse_m = m.run_plant_line_lateral_rmse_m;
  return m;
}

}  // namespace

const char* Name(TrackingReference reference) {
  return reference == TrackingReference::kPlantLines ? "plant-lines" : "grid";
}

TrackingEvaluation EvaluateTracking(const TrackingEvalOptions& options) {
  ThrowIfInvalid("evaluate tracking", options.Validate());
  TrackingEvaluation result;
  result.preset = options.sim.preset;
  result.seeds = options.seeds;
  result.spacing_offset_m = options.spacing_offset_m;
  result.engine = EngineUsed::Of(*options.profiles, options.calibration_error,
                                 options.calibration_error_text);
  result.odometry_fault = options.odometry_fault;
  result.visual_motion = options.visual_motion;
  result.reference = options.reference;
  result.planter_sd_profile_m = options.profiles->crop.planter_sd_m;
  result.planter_sd_generator_m =
      std::hypot(options.sim.field.planting_jitter_m, options.sim.field.crop_lean_sd_m);
  const vision::SegmenterOptions ours_seg;
  ChainTally ours_tally, thesis_tally;
  ForEachSeed(options.sim, options.seeds, [&](int k, const sim::SimulatorOptions& so) {
    sim::Simulator simulator(so);
    RequireImageSize(options.profiles->vehicle, so.camera.image_width_px,
                     so.camera.image_height_px);
    const TrackingEngine engine = TrackingEngineOf(options, so.seed);
    const PlantLineReference plant_lines = PlantLines(simulator.field());
    Scorer ours(engine.camera, engine.ours, ours_seg, options, options.visual_motion);
    ours.lines = &plant_lines;
    ours.trace = options.trace;
    ours.seed = so.seed;
    ours.calibration_error = engine.calibration_error;
    if (options.trace && k == 0) *options.trace << kTraceHeader;
    std::optional<Scorer> thesis;
    if (options.baseline_thesis) {
      thesis.emplace(engine.camera, engine.thesis, vision::ThesisSegmenterOptions(), options,
                     false);
      thesis->lines = &plant_lines;
      thesis->seed = so.seed;
      thesis->calibration_error = engine.calibration_error;
    }
    InitProbe probe(engine.camera, engine.ours);
    probe.next_at_m = options.init_probe_interval_m;
    result.distance_m = DriveSeed(options, simulator, ours, thesis, probe, ours_tally);
    ours_tally.Add(ours, result.distance_m);
    if (thesis) thesis_tally.Add(*thesis, result.distance_m);
  });
  ours_tally.Finish();
  result.grid_lateral_rmse_m = ours_tally.metrics.lateral_rmse_m;
  result.ours = AtReference(ours_tally.metrics, options.reference);
  if (options.baseline_thesis) {
    thesis_tally.Finish();
    result.thesis_grid_lateral_rmse_m = thesis_tally.metrics.lateral_rmse_m;
    result.thesis = AtReference(thesis_tally.metrics, options.reference);
  }
  return result;
}

}  // namespace plantscale::app
