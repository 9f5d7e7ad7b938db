#include "app/tracking_eval.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/common/stats.h"
#include "engine/pipeline/pipeline.h"
#include "engine/tracking/blob_features.h"

namespace plantscale::app {

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;
// Two-sided 95 % interval of χ² with 3 degrees of freedom.
constexpr double kNeesLow = 0.2158;
constexpr double kNeesHigh = 9.3484;

int RowsEachSide(const sim::SimulatorOptions& s) { return (s.field.rows - 1) / 2; }

// One tracker under test on one run, with its error sums.
struct Scorer {
  pipeline::Pipeline pipe;  // segmentation and tracking
  const tracking::GridTracker& tracker;
  const TrackingEvalOptions& options;
  std::ostream* trace = nullptr;  // ours only
  uint64_t seed = 0;
  std::span<const tracking::Feature> features;  // the last frame's, as the tracker measured them
  bool ever_tracked = false;
  double init_distance_m = 0.0;
  int start_frame = 0;
  // Sums.
  double lat2 = 0.0, lat = 0.0, bear2 = 0.0, sd = 0.0, nees = 0.0;
  Eigen::Vector3d normalised2 = Eigen::Vector3d::Zero();
  int scored = 0, nees_in = 0;
  double row2 = 0.0, plant2 = 0.0, row1 = 0.0, plant1 = 0.0, fwd = 0.0;
  int spacing_scored = 0;
  int tracking_frames = 0, updates = 0, losses = 0;
  double matched = 0.0;
  std::vector<double> init_frames;
  int init_trials = 0, init_successes = 0;

  Scorer(const sim::Simulator& sim, const tracking::TrackerOptions& tracker_options,
         const vision::SegmenterOptions& segmenter_options, const TrackingEvalOptions& o)
      : pipe(sim.camera(), Options(segmenter_options, tracker_options)),
        tracker(pipe.tracker()),
        options(o) {}

  static pipeline::PipelineOptions Options(const vision::SegmenterOptions& segmenter,
                                           const tracking::TrackerOptions& tracker) {
    pipeline::PipelineOptions p;
    p.segmenter = segmenter;
    p.tracker = tracker;
    p.treat = false;
    return p;
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
    if (tracker.mode() != tracking::TrackerMode::kTracking) return;
    ++tracking_frames;
    if (r.updated) ++updates;
    matched += r.matched;
    const double past = frame.truth.distance_m - init_distance_m;
    if (past < options.settle_m) return;
    const Eigen::Matrix3d p = tracker.covariance().topLeftCorner<3, 3>();
    const GridErrors g = ScoreGrid(est, p, truth);
    const double e_lat = g.lateral_m, e_fwd = g.forward_m, e_bear = g.bearing_rad, n = g.nees;
    lat += e_lat;
    fwd += e_fwd;
    lat2 += e_lat * e_lat;
    bear2 += e_bear * e_bear;
    sd += g.lateral_sd_m;
    nees += n;
    normalised2 += g.normalised2;
    nees_in += g.nees_in_bounds;
    ++scored;
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

  static bool InitCorrect(const geometry::GridState& est, const geometry::GridState& truth) {
    return InitialisedOnTruth(est, truth);
  }
};

// Fresh initialisations at intervals along the run: frames to initialise
// and whether the grid it started on was the right one.
struct InitProbe {
  tracking::GridTracker tracker;
  bool active = false;
  int start = 0;
  double next_at_m = 0.0;

  InitProbe(const sim::Simulator& sim, const tracking::TrackerOptions& o)
      : tracker(sim.camera(), o) {}
};

void Accumulate(const Scorer& s, double driven_m, double estimated_m, TrackingMetrics& m,
                std::vector<double>& init_frames, int& init_trials, int& init_successes) {
  m.frames += s.scored;
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
  m.run_forward_drift_cm_per_m.push_back(driven_m > 0 ? 100.0 * (estimated_m - driven_m) / driven_m
                                                      : std::nan(""));
  init_frames.insert(init_frames.end(), s.init_frames.begin(), s.init_frames.end());
  init_trials += s.init_trials;
  init_successes += s.init_successes;
}

}  // namespace

void FinishTrackingMetrics(TrackingMetrics& m, int spacing_frames,
                           const std::vector<double>& init_frames, int init_trials,
                           int init_successes) {
  const double n = std::max(1, m.frames);
  m.lateral_rmse_m = std::sqrt(m.lateral_rmse_m / n);
  m.lateral_mean_m /= n;
  m.forward_mean_m /= n;
  m.row_spacing_mean_error_m /= std::max(1, spacing_frames);
  m.plant_spacing_mean_error_m /= std::max(1, spacing_frames);
  m.bearing_rmse_deg = std::sqrt(m.bearing_rmse_deg / n) * kDeg;
  m.lateral_sd_mean_m /= n;
  m.nees_mean /= n;
  m.normalised_error2 /= n;
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
}

GridErrors ScoreGrid(const geometry::GridState& est, const Eigen::Matrix3d& p,
                     const geometry::GridState& truth) {
  GridErrors g;
  g.lateral_m = est.offset_m - truth.offset_m;
  g.bearing_rad = est.bearing_rad - truth.bearing_rad;
  g.forward_m = std::remainder(est.forward_m - truth.forward_m, truth.plant_spacing_m);
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
  if (seeds < 1) e.push_back({"seeds", "must be >= 1"});
  RequireInRange(e, "spacing_offset_m", spacing_offset_m, -0.1, 0.1);
  RequireNonNegative(e, "settle_m", settle_m);
  RequireNonNegative(e, "spacing_settle_m", spacing_settle_m);
  RequirePositive(e, "init_probe_interval_m", init_probe_interval_m);
  if (init_probe_max_frames < 1) e.push_back({"init_probe_max_frames", "must be >= 1"});
  return e;
}

tracking::TrackerOptions OurTrackerOptions(const sim::SimulatorOptions& s, double offset) {
  tracking::TrackerOptions o;
  o.rows_each_side = RowsEachSide(s);
  o.row_spacing_m = s.field.row_spacing_m + offset;
  o.plant_spacing_m = s.field.plant_spacing_m + offset;
  o.track_width_m = s.vehicle.track_width_m;
  // The crop as a grower knows it: mean leaf-tip radius and height, how
  // much plants vary in size (their centroid heights scale with them), and
  // how precisely the planter places them (plus their lean).
  o.crop_radius_m = s.field.crop_radius_m;
  o.crop_height_m = s.field.crop_height_ratio * s.field.crop_radius_m;
  o.plant_height_sd_m = std::max(0.002, s.field.crop_radius_sd_fraction * o.crop_height_m);
  o.plant_offset_sd_m = std::max(0.002, std::hypot(s.field.planting_jitter_m, s.field.crop_lean_sd_m));
  // A centroid's wander as the view changes is the parallax of the plant's
  // leaves: it scales with the crop's height from where it was measured.
  const double wander = o.crop_height_m / tracking::TrackerOptions::kOffsetWalkCropHeightM;
  o.plant_offset_walk_across_sd_per_sqrt_m *= wander;
  o.plant_offset_walk_along_sd_per_sqrt_m *= wander;
  // The vehicle's camera bounce as its suspension was measured: size and
  // how long it lasts.
  o.camera_pitch_sd_rad = std::max(1e-4, s.vehicle.bump_pitch_sd_rad);
  o.camera_roll_sd_rad = std::max(1e-4, s.vehicle.bump_roll_sd_rad);
  o.camera_height_sd_m = std::max(1e-4, s.vehicle.bump_height_sd_m);
  o.camera_bounce_correlation_s = s.vehicle.bump_correlation_s;
  return o;
}

tracking::TrackerOptions ProductTrackerOptions(const sim::SimulatorOptions& s) {
  tracking::TrackerOptions o = OurTrackerOptions(s, 0.0);
  o.row_spacing_m = s.field.NominalRowSpacing();
  o.plant_spacing_m = s.field.NominalPlantSpacing();
  return o;
}

tracking::TrackerOptions ThesisTrackerOptions(const sim::SimulatorOptions& s) {
  tracking::TrackerOptions o;
  o.estimate_spacing = false;
  o.estimate_odometry_scale = false;
  o.slip_guard.enabled = false;
  o.plant_offsets = false;
  o.model_bounce = false;
  o.skip_merged_features = false;  // every feature in the gate (§6.2)
  o.space = tracking::ObservationSpace::kImage;
  o.rows_each_side = RowsEachSide(s);
  o.row_spacing_m = s.field.NominalRowSpacing();
  o.plant_spacing_m = s.field.NominalPlantSpacing();
  o.track_width_m = s.vehicle.track_width_m;
  o.feature_sd_m = 0.01;
  o.pixel_sd_px = 0.0;
  o.forward_sd_per_sqrt_m = 0.0;
  o.lateral_sd_per_sqrt_m = 0.0;
  o.bearing_sd_per_sqrt_m = 0.0;
  o.frame_offset_sd_m = 0.002;
  o.frame_forward_sd_m = 0.004;
  o.frame_bearing_sd_rad = 0.002;
  o.edge_margin_px = 0.0;
  return o;
}

TrackingEvaluation EvaluateTracking(const TrackingEvalOptions& options) {
  ThrowIfInvalid("evaluate tracking", options.Validate());
  TrackingEvaluation result;
  result.preset = options.sim.preset;
  result.seeds = options.seeds;
  vision::SegmenterOptions ours_seg;
  const vision::SegmenterOptions thesis_seg = vision::ThesisSegmenterOptions();

  std::vector<double> init_frames_ours, init_frames_thesis;
  int trials_ours = 0, successes_ours = 0, trials_thesis = 0, successes_thesis = 0;
  int spacing_ours = 0, spacing_thesis = 0;
  TrackingMetrics thesis_metrics;
  for (int k = 0; k < options.seeds; ++k) {
    sim::SimulatorOptions so = options.sim;
    so.seed = options.sim.seed + static_cast<uint64_t>(k);
    sim::Simulator simulator(so);
    tracking::TrackerOptions ours_options = OurTrackerOptions(so, options.spacing_offset_m);
    if (options.centroids_on_virtual_plane) ours_options.crop_radius_m = ours_options.crop_height_m = 0.0;
    Scorer ours(simulator, ours_options, ours_seg, options);
    ours.trace = options.trace;
    ours.seed = so.seed;
    if (options.trace && k == 0) {
      *options.trace << "seed,frame,distance_m,offset_error_m,forward_error_m,bearing_error_rad,"
                        "offset_sd_m,forward_sd_m,bearing_sd_rad,row_spacing_m,true_row_spacing_m,"
                        "plant_spacing_m,true_plant_spacing_m,matched,odometry_scale,nees,"
                        "forward_distance_m,true_distance_m\n";
    }
    std::optional<Scorer> thesis;
    if (options.baseline_thesis) thesis.emplace(simulator, ThesisTrackerOptions(so), thesis_seg, options);
    InitProbe probe(simulator, ours_options);
    probe.next_at_m = options.init_probe_interval_m;

    sim::SimFrame frame;
    int index = 0;
    double last_distance = 0.0;
    // Odometry up to the frame's capture goes in before the frame, the rest
    // after it, so that the estimate is scored at the time of its truth.
    std::vector<sim::OdometrySample> later;
    const auto add = [&](const sim::OdometrySample& o) {
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
      // The initialisation probe reuses ours's features of this frame.
      if (!probe.active && frame.truth.distance_m >= probe.next_at_m) {
        probe.tracker.Reset();
        probe.active = true;
        probe.start = index;
        probe.next_at_m += options.init_probe_interval_m;
      }
      if (probe.active) {
        const tracking::FrameReport r = probe.tracker.ProcessFrame(
            frame.truth.utime, frame.rendered.image.cols, frame.rendered.image.rows, ours.features);
        const int frames = index - probe.start + 1;
        if (r.initialised_now) {
          ++trials_ours;
          init_frames_ours.push_back(frames);
          if (Scorer::InitCorrect(probe.tracker.state(), frame.truth.grid)) ++successes_ours;
          probe.active = false;
        } else if (frames >= options.init_probe_max_frames) {
          ++trials_ours;  // a failure
          probe.active = false;
        }
      }
      last_distance = frame.truth.distance_m;
      ++index;
    }
    result.distance_m = last_distance;
    Accumulate(ours, last_distance - ours.init_distance_m, ours.tracker.forward_distance_m(),
               result.ours, init_frames_ours, trials_ours, successes_ours);
    spacing_ours += ours.spacing_scored;
    if (thesis) {
      Accumulate(*thesis, last_distance - thesis->init_distance_m,
                 thesis->tracker.forward_distance_m(), thesis_metrics, init_frames_thesis,
                 trials_thesis, successes_thesis);
      spacing_thesis += thesis->spacing_scored;
    }
  }
  FinishTrackingMetrics(result.ours, spacing_ours, init_frames_ours, trials_ours, successes_ours);
  if (options.baseline_thesis) {
    FinishTrackingMetrics(thesis_metrics, spacing_thesis, init_frames_thesis, trials_thesis,
                          successes_thesis);
    result.thesis = thesis_metrics;
  }
  return result;
}

}  // namespace plantscale::app
