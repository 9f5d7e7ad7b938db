#include "evaluation/treatment_eval.h"

#include <opencv2/imgproc.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <tuple>

#include "engine/pipeline/pipeline.h"
#include "engine/treatment/simulated_bar.h"
#include "engine/vision/segmenter.h"
#include "evaluation/roc.h"
#include "evaluation/seeds.h"
#include "evaluation/segmentation_eval.h"
#include "evaluation/tracking_eval.h"
#include "evaluation/treatment_score.h"

namespace plantscale::app {

namespace {

// Confusion of true pixel class (soil, crop, weed) × labelled (S, C, W).
using Confusion = std::array<std::array<double, 3>, 3>;
// Why a blob's pixels are labelled W (index into CropAsWeed's counts).
enum WeedReason : uint8_t {
  kNoDecision,    // no feature (the blob was not classified)
  kSmall,         // under the size filter
  kUnassociated,  // outside every association region
  kClippedCast,   // cut by the image border, or another rule
  kSplitPart,     // the part of a merged blob left to no crop
  kSplitClipped,  // the same of a blob cut by the image border
  kReasons
};

// One treatment chain under test on one run: the vehicle's pipeline into a
// simulated bar, with its scores.
struct Chain {
  treatment::SimulatedBar bar;
  geometry::CameraModel camera;  // the engine's (the vehicle's calibration), not the simulator's
  pipeline::Pipeline pipe;
  Confusion confusion{};
  std::array<double, kReasons> crop_as_weed_by{};
  std::vector<classify::ClassifierSample> samples;
  bool collect_samples = false;
  int frames_classified = 0, ticks = 0, ticks_fail_safe = 0;
  double first_classified_y = std::nan("");
  // Scratch.
  cv::Mat components, stats, centroids;

  Chain(const geometry::CameraOptions& engine_camera, const vision::SegmenterOptions& seg,
        const tracking::TrackerOptions& track, const treatment::TreatmentOptions& treat,
        double true_latency_s, const pipeline::MotionFusionOptions& motion = {},
        const pipeline::LearnedOptions& learned = {})
      : bar(treat.scheduler.bar, true_latency_s, treat.scheduler.tick_s),
        camera(engine_camera),
        pipe(camera, Options(seg, track, treat, motion, learned)) {
    pipe.set_sink(bar.Sink());
  }

  const treatment::TreatmentSystem& system() const { return *pipe.treatment(); }

  static pipeline::PipelineOptions Options(const vision::SegmenterOptions& seg,
                                           const tracking::TrackerOptions& track,
                                           const treatment::TreatmentOptions& treat,
                                           const pipeline::MotionFusionOptions& motion,
                                           const pipeline::LearnedOptions& learned) {
    pipeline::PipelineOptions o;
    o.segmenter = seg;
    o.learned = learned;
    o.tracker = track;
    o.treatment = treat;
    o.motion = motion;
    return o;
  }

  void Count(std::span<const treatment::TickResult> results) {
    for (const treatment::TickResult& r : results) {
      ++ticks;
      if (r.fail_reasons) ++ticks_fail_safe;
    }
  }

  void Odometry(const sim::OdometrySample& o) {
    Count(pipe.AddOdometry({o.utime, o.left_m_s, o.right_m_s}).ticks);
  }

  void Frame(const sim::SimFrame& frame, const cv::Mat& roi) {
    const pipeline::FrameResult& r =
        pipe.ProcessFrame(frame.truth.utime, frame.truth.index, frame.rendered.image);
    Count(r.ticks);
    if (!r.treatment || !r.treatment->classified) return;
    if (std::isnan(first_classified_y)) first_classified_y = frame.truth.pose.y_m;
    ++frames_classified;
    ScorePixels(r, *r.treatment, frame.rendered.labels, roi);
  }

  // Labels every blob's pixels C or W by its decision, and counts them
  // against the label image (thesis tables 7.5–7.8).
  void ScorePixels(const pipeline::FrameResult& seg, const treatment::FrameTreatment& t,
                   const cv::Mat& labels, const cv::Mat& roi) {
    const int n = cv::connectedComponentsWithStats(seg.mask, components, stats, centroids, 8,
                                                   CV_32S);
    // Component ↔ blob by bounding box and area (both label 8-connected runs).
    std::map<std::tuple<int, int, int, int, int>, int> by_box;
    for (int k = 1; k < n; ++k) {
      by_box[{stats.at<int>(k, cv::CC_STAT_LEFT), stats.at<int>(k, cv::CC_STAT_TOP),
              stats.at<int>(k, cv::CC_STAT_WIDTH), stats.at<int>(k, cv::CC_STAT_HEIGHT),
              stats.at<int>(k, cv::CC_STAT_AREA)}] = k;
    }
    std::vector<uint8_t> label_of(static_cast<size_t>(n), 2);  // unmatched plant matter: W
    std::vector<uint8_t> reason_of(static_cast<size_t>(n), kNoDecision);
    label_of[0] = 0;
    std::vector<int> feature_of(static_cast<size_t>(n), -1);
    for (size_t i = 0; i < t.decisions.size(); ++i) {
      const vision::Blob& b = seg.blobs[static_cast<size_t>(seg.blob_of_feature[i])];
      const auto it = by_box.find({b.bbox_px.x, b.bbox_px.y, b.bbox_px.width, b.bbox_px.height,
                                   b.area_px});
      if (it == by_box.end()) continue;
      const classify::BlobDecision& d = t.decisions[i];
      const auto k = static_cast<size_t>(it->second);
      label_of[k] = d.crop ? 1 : 2;
      reason_of[k] = d.area_m2 < d.size_filter_m2 ? kSmall
                     : !d.associated             ? kUnassociated
                                                 : kClippedCast;
      feature_of[k] = static_cast<int>(i);
    }
    cv::Mat label_px(components.size(), CV_8UC1), reason_px(components.size(), CV_8UC1);
    for (int v = 0; v < components.rows; ++v) {
      const int* comp = components.ptr<int>(v);
      uint8_t* out = label_px.ptr<uint8_t>(v);
      uint8_t* why = reason_px.ptr<uint8_t>(v);
      for (int u = 0; u < components.cols; ++u) {
        out[u] = label_of[static_cast<size_t>(comp[u])];
        why[u] = reason_of[static_cast<size_t>(comp[u])];
      }
    }
    // Blobs the treatment system split among the predicted crops (merged
    // plants): labelled pixel by pixel as it mapped them.
    for (const treatment::SplitBlob& b : t.split) {
      for (size_t q = 0; q < b.pixels.size(); ++q) {
        label_px.at<uint8_t>(b.pixels[q]) = b.crop[q] ? 1 : 2;
        reason_px.at<uint8_t>(b.pixels[q]) =
            t.decisions[static_cast<size_t>(b.feature)].clipped ? kSplitClipped : kSplitPart;
      }
    }
    cv::Mat valid;
    vision::EvaluationMask(labels, roi, 1, valid);
    std::vector<std::array<double, 3>> per_component(static_cast<size_t>(n), {0, 0, 0});
    for (int v = 0; v < labels.rows; ++v) {
      const uint8_t* truth = labels.ptr<uint8_t>(v);
      const uint8_t* ok = valid.ptr<uint8_t>(v);
      const int* comp = components.ptr<int>(v);
      for (int u = 0; u < labels.cols; ++u) {
        if (!ok[u] || truth[u] > 2) continue;
        const size_t k = static_cast<size_t>(comp[u]);
        const uint8_t label = label_px.at<uint8_t>(v, u);
        confusion[truth[u]][label] += 1.0;
        if (truth[u] == 1 && label == 2) crop_as_weed_by[reason_px.at<uint8_t>(v, u)] += 1.0;
        per_component[k][truth[u]] += 1.0;
      }
    }
    if (!collect_samples) return;
    for (int k = 1; k < n; ++k) {
      const int i = feature_of[static_cast<size_t>(k)];
      if (i < 0) continue;
      const classify::BlobDecision& d = t.decisions[static_cast<size_t>(i)];
      samples.push_back({d.area_m2, d.clipped, d.gamma2, per_component[static_cast<size_t>(k)][1],
                         per_component[static_cast<size_t>(k)][2]});
    }
  }
};

struct Sums {
  SprayScore spray;
  Confusion confusion{};
  std::array<double, kReasons> crop_as_weed_by{};
  int frames_classified = 0, ticks = 0, ticks_fail_safe = 0, shots = 0, map_resets = 0,
      plants = 0, confirmed = 0;
};

void Accumulate(const Chain& c, const SprayScore& s, int shots, Sums& sums) {
  sums.spray.Merge(s);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) sums.confusion[i][j] += c.confusion[i][j];
  }
  for (size_t k = 0; k < kReasons; ++k) sums.crop_as_weed_by[k] += c.crop_as_weed_by[k];
  sums.frames_classified += c.frames_classified;
  sums.ticks += c.ticks;
  sums.ticks_fail_safe += c.ticks_fail_safe;
  sums.shots += shots;
  sums.map_resets += c.system().map_resets();
  sums.plants += static_cast<int>(c.system().registry().recorded());
  sums.confirmed += c.system().registry().confirmed();
}

double Ratio(double a, double b) { return b > 0 ? a / b : 0.0; }

TreatmentMetrics Finish(const Sums& s) {
  TreatmentMetrics m = SprayMetrics(s.spray);
  const auto& c = s.confusion;
  const double crop = c[1][0] + c[1][1] + c[1][2];
  const double weed = c[2][0] + c[2][1] + c[2][2];
  m.crop_as_soil = Ratio(c[1][0], crop);
  m.crop_as_crop = Ratio(c[1][1], crop);
  m.crop_as_weed = Ratio(c[1][2], crop);
  m.crop_as_weed_no_decision = Ratio(s.crop_as_weed_by[kNoDecision], crop);
  m.crop_as_weed_small = Ratio(s.crop_as_weed_by[kSmall], crop);
  m.crop_as_weed_unassociated = Ratio(s.crop_as_weed_by[kUnassociated], crop);
  m.crop_as_weed_other = Ratio(s.crop_as_weed_by[kClippedCast], crop);
  m.crop_as_weed_split_part = Ratio(s.crop_as_weed_by[kSplitPart], crop);
  m.crop_as_weed_split_clipped = Ratio(s.crop_as_weed_by[kSplitClipped], crop);
  m.weed_as_soil = Ratio(c[2][0], weed);
  m.weed_as_crop = Ratio(c[2][1], weed);
  m.weed_as_weed = Ratio(c[2][2], weed);
  m.crop_pixel_rate = m.crop_as_crop;
  m.crop_pixel_rate_of_plant = Ratio(c[1][1], c[1][1] + c[1][2]);
  m.weed_pixel_fpr_of_plant = Ratio(c[2][1], c[2][1] + c[2][2]);
  m.frames_classified = s.frames_classified;
  m.ticks = s.ticks;
  m.ticks_fail_safe = s.ticks_fail_safe;
  m.shots = s.shots;
  m.map_resets = s.map_resets;
  m.plants_recorded = s.plants;
  m.plants_confirmed = s.confirmed;
  return m;
}

// The plants whose whole life under the camera and the bar fell inside the
// run: from past the far edge of the view when the chain first classified,
// to behind the bar at the end.
SprayScoreRegion Region(const sim::Simulator& sim, const Chain& c, double last_y,
                        const treatment::TreatmentOptions& t) {
  return TreatmentScoreRegion(sim, c.first_classified_y, last_y, t);
}

}  // namespace

TreatmentMetrics SprayMetrics(const SprayScore& p) {
  TreatmentMetrics m;
  m.crop_plants = p.crop_plants;
  m.crop_hits = p.crop_hits;
  m.crop_hit_rate = Ratio(p.crop_hits, p.crop_plants);
  m.weeds = p.weeds;
  m.weed_hits = p.weed_hits;
  m.weed_hit_rate = Ratio(p.weed_hits, p.weeds);
  m.weeds_clear = p.weeds_clear;
  m.weed_hit_rate_clear = Ratio(p.weed_hits_clear, p.weeds_clear);
  m.weeds_touching = p.weeds_touching;
  m.weed_hit_rate_touching = Ratio(p.weed_hits_touching, p.weeds_touching);
  m.weed_hit_rate_touching_crop_dry = Ratio(p.weed_hits_touching_crop_dry, p.weeds_touching);
  const double n = std::max(1, p.crop_hits);
  m.placement_bias_across_m = p.error_sum.x() / n;
  m.placement_bias_along_m = p.error_sum.y() / n;
  m.placement_rms_across_m = std::sqrt(p.error2_sum.x() / n);
  m.placement_rms_along_m = std::sqrt(p.error2_sum.y() / n);
  m.placement_rms_m = std::max(m.placement_rms_across_m, m.placement_rms_along_m);
  m.centre_bias_across_m = p.centre_error_sum.x() / n;
  m.centre_bias_along_m = p.centre_error_sum.y() / n;
  m.centre_rms_across_m = std::sqrt(p.centre_error2_sum.x() / n);
  m.centre_rms_along_m = std::sqrt(p.centre_error2_sum.y() / n);
  m.treated_area_fraction = Ratio(p.sprayed_bed_m2, p.bed_m2);
  return m;
}

SprayScoreRegion TreatmentScoreRegion(const sim::Simulator& sim, double first_classified_y,
                                      double last_y, const treatment::TreatmentOptions& t) {
  SprayScoreRegion r;
  const auto& cam = sim.camera().options();
  const auto far = sim.camera().ImageToPlane({cam.image_width_px / 2.0, 0.5}, 0.0);
  r.y_begin_m = first_classified_y + (far ? far->y() : 3.0) + 0.1;
  r.y_end_m = last_y - t.scheduler.bar.bar_offset_m - 0.3;
  const sim::FieldOptions& f = sim.options().field;
  r.bed_half_width_m = 0.5 * f.rows * f.row_spacing_m;
  r.patch_half_size_m = 0.45 * std::min(f.row_spacing_m, f.plant_spacing_m);
  return r;
}

OptionErrors TreatmentEvalOptions::Validate() const {
  OptionErrors e = Prefixed("sim", sim.Validate());
  if (!profiles) e.push_back({"profiles", "required (a crop and a vehicle profile)"});
  const OptionErrors t = Prefixed("treatment", treatment.Validate());
  e.insert(e.end(), t.begin(), t.end());
  const OptionErrors g = Prefixed("segmenter", segmenter.Validate());
  e.insert(e.end(), g.begin(), g.end());
  if (seeds < 1) e.push_back({"seeds", "must be >= 1"});
  if (true_valve_latency_s > 1.0) e.push_back({"true_valve_latency_s", "must be <= 1 s"});
  RequireInRange(e, "frame_lag_s", frame_lag_s, 0.0, 0.15);
  RequirePositive(e, "costs_ratio", costs_ratio);
  return e;
}

treatment::TreatmentOptions ThesisTreatmentOptions(const std::string& preset,
                                                   const geometry::CameraOptions& camera_options) {
  treatment::TreatmentOptions o;
  o.crop_footprint_scale = 1.0;  // the whole projected bounding box (§8.2)
  o.crop_footprint_min_half_m = 0.0;  // however small
  o.crop_footprint_per_plant = false;  // each feature's own box
  o.abstain_merged = false;
  o.clipped_on_crop_votes_weed = true;  // every feature's box votes
  o.split_merged = false;  // whole blobs, labelled and mapped
  o.close_on_uncertainty = false;  // the thesis's bar closed on a lost grid only
  o.weed_height_m = camera_options.virtual_plane_height_m;  // everything on the one plane (§2.3.8)
  // Table 7.2's operating points: size ς in pixels and clustering radius r
  // (A: 100 px, 450 mm; B, D: 30 px, 100 mm; C and the field: 80 px, 100 mm).
  double size_px = 80.0, radius_m = 0.1;
  if (preset == "A") size_px = 100.0, radius_m = 0.45;
  if (preset == "B" || preset == "D") size_px = 30.0;
  // Pixels to ground area at the image centre's pixel footprint.
  const geometry::CameraModel camera(camera_options);
  const Eigen::Vector2d centre(camera_options.image_width_px / 2.0,
                               camera_options.image_height_px / 2.0);
  const double pixel_m2 = std::abs(
      camera.ImageToPlaneJacobian(centre, camera_options.virtual_plane_height_m).determinant());
  o.classifier.min_crop_area_m2 = size_px * pixel_m2;
  o.classifier.crop_size_fraction = 0.0;  // ς fixed by hand per sequence
  // A Euclidean radius r: γ² ≤ 1 with σ = r (the tracker's H P Hᵀ is small).
  o.classifier.assoc_chi2 = 1.0;
  o.classifier.feature_sd_m = radius_m;
  o.classifier.plant_sd_m = 0.0;
  o.classifier.sure_crop_area_m2 = std::numeric_limits<double>::infinity();
  o.classifier.lone_crop_fraction = 0.0;  // under the size filter is weed
  o.classifier.camera_pitch_sd_rad = 0.0;
  o.classifier.camera_roll_sd_rad = 0.0;
  o.classifier.camera_height_sd_m = 0.0;
  return o;
}

geometry::CameraOptions TreatmentEngineCamera(const TreatmentEvalOptions& options, uint64_t seed) {
  if (!options.profiles) throw InvalidOptionsError("evaluate treatment", {{"profiles", "required"}});
  return ApplyCalibrationError(EngineCamera(*options.profiles),
                               DrawnCalibrationError(options.calibration_error, seed));
}

namespace {

// One seed's chains: ours, and the thesis's when the baseline is asked for.
struct SeedChains {
  Chain ours;
  std::optional<Chain> thesis;
  treatment::TreatmentOptions thesis_options;

  // `engine_camera`: the vehicle's calibration of this seed
  // (TreatmentEngineCamera), which both chains are given.
  SeedChains(const TreatmentEvalOptions& options, const std::string& preset,
             const geometry::CameraOptions& engine_camera, double true_latency_s)
      : ours(engine_camera,
             treatment::SegmenterOptionsFor(options.treatment.scheduler.mode, options.segmenter),
             OurTracker(options), options.treatment, true_latency_s,
             options.visual_motion ? VisualMotionOptions(*options.profiles)
                                   : pipeline::MotionFusionOptions{},
             options.learned),
        thesis_options(ThesisTreatmentOptions(preset, engine_camera)) {
    if (!ours.pipe.learned_fault().empty()) throw DataError(ours.pipe.learned_fault());
    ours.collect_samples = options.mrroc;
    thesis_options.scheduler = options.treatment.scheduler;
    // The thesis's chain commands its bar at the pose rate, as it did before
    // ours went to 200 Hz: the baseline stays where it was calibrated.
    thesis_options.scheduler.tick_s = thesis_options.scheduler.pose_period_s;
    if (options.baseline_thesis) {
      thesis.emplace(engine_camera, vision::ThesisSegmenterOptions(),
                     ThesisTrackerOptions(*options.profiles), thesis_options, true_latency_s);
    }
  }

  static tracking::TrackerOptions OurTracker(const TreatmentEvalOptions& options) {
    tracking::TrackerOptions t = ProductTrackerOptions(*options.profiles);
    if (options.adjust_tracker) options.adjust_tracker(t);
    return t;
  }
};

// What one seed's drive leaves to score: the true track, the distance, and
// where the odometry fault lasted (NaN without one).
struct SeedDrive {
  std::vector<treatment::FieldPose> track;
  double distance_m = 0.0;
  double fault_begin_y = std::nan(""), fault_end_y = std::nan("");
};

// Drives the simulator through the chains. The odometry goes in in time
// order; each frame goes in once the odometry has passed its capture by
// frame_lag_s (the frame reaches the pipeline that much late: the camera's
// latency and segmentation).
SeedDrive DriveSeed(const TreatmentEvalOptions& options, sim::Simulator& simulator,
                    SeedChains& chains, const cv::Mat& roi) {
  SeedDrive drive;
  const int64_t lag_us = std::llround(options.frame_lag_s * 1e6);
  std::deque<sim::SimFrame> pending;
  const auto process = [&] {
    chains.ours.Frame(pending.front(), roi);
    if (chains.thesis) chains.thesis->Frame(pending.front(), roi);
    pending.pop_front();
  };
  sim::SimFrame frame;
  while (simulator.Next(frame)) {
    const sim::Pose2& pose = frame.truth.pose;
    drive.track.push_back({frame.truth.utime, pose.x_m, pose.y_m, pose.heading_rad});
    const double distance = drive.distance_m = frame.truth.distance_m;
    if (options.odometry_fault.Active(distance)) {
      if (std::isnan(drive.fault_begin_y)) drive.fault_begin_y = pose.y_m;
      drive.fault_end_y = pose.y_m;
    }
    std::vector<sim::OdometrySample> odometry = std::move(frame.odometry);
    std::erase_if(odometry, [&](sim::OdometrySample& o) {
      return !ApplyOdometryFault(options.odometry_fault, distance, o);
    });
    pending.push_back(std::move(frame));
    frame = sim::SimFrame{};
    for (const sim::OdometrySample& o : odometry) {
      while (!pending.empty() && pending.front().truth.utime + lag_us < o.utime) process();
      chains.ours.Odometry(o);
      if (chains.thesis) chains.thesis->Odometry(o);
    }
    // Odometry that stopped passes no frame: the next frame's capture does.
    while (options.odometry_fault.kind == OdometryFaultKind::kStop && pending.size() > 1 &&
           pending.front().truth.utime + lag_us < pending.back().truth.utime) {
      process();
    }
  }
  while (!pending.empty()) process();
  return drive;
}

struct AllSums {
  Sums ours, thesis, fault;
  std::vector<classify::ClassifierSample> samples;
  double crop_pixels = 0.0, weed_pixels = 0.0;
};

// Scores one seed's shots against the simulator's field: each chain's over
// the scored region, and ours over the stretch the fault lasted.
void ScoreSeed(const TreatmentEvalOptions& options, const sim::Simulator& simulator,
               SeedChains& chains, const SeedDrive& drive, int seed_index, AllSums& sums) {
  const double last_y = drive.track.empty() ? 0.0 : drive.track.back().y_m;
  const auto score = [&](Chain& c, const treatment::TreatmentOptions& t, Sums& into) {
    const std::vector<treatment::Shot> shots = c.bar.Shots(drive.track);
    SprayScore s = ScoreSpray(simulator.field(), shots, Region(simulator, c, last_y, t));
    for (MissedCrop& m : s.missed) m.seed_index = seed_index;
    Accumulate(c, s, static_cast<int>(shots.size()), into);
  };
  score(chains.ours, options.treatment, sums.ours);
  if (!std::isnan(drive.fault_begin_y)) {
    // The plants the bar passed over while the fault lasted.
    SprayScoreRegion r = Region(simulator, chains.ours, last_y, options.treatment);
    const double bar = options.treatment.scheduler.bar.bar_offset_m;
    r.y_begin_m = std::max(r.y_begin_m, drive.fault_begin_y - bar);
    r.y_end_m = std::min(r.y_end_m, drive.fault_end_y - bar);
    const std::vector<treatment::Shot> shots = chains.ours.bar.Shots(drive.track);
    Accumulate(chains.ours, ScoreSpray(simulator.field(), shots, r),
               static_cast<int>(shots.size()), sums.fault);
  }
  if (chains.thesis) score(*chains.thesis, chains.thesis_options, sums.thesis);
}

// What the classifier's sweep and the example records take from ours.
void CollectSeed(Chain& ours, bool first_seed, AllSums& sums,
                 TreatmentEvaluation& result) {
  if (first_seed) {
    ours.pipe.treatment()->Explain();
    const auto& records = ours.system().registry().records();
    for (size_t i = 0; i < records.size() && result.example_why.size() < 4; i += 37) {
      result.example_why.push_back(records[i].why);
    }
  }
  sums.samples.insert(sums.samples.end(), ours.samples.begin(), ours.samples.end());
  for (int j = 0; j < 3; ++j) {
    sums.crop_pixels += ours.confusion[1][j];
    sums.weed_pixels += ours.confusion[2][j];
  }
}

// The classifier's two parameters swept over the samples (MRROC, §7.3).
void SweepMrroc(const TreatmentEvalOptions& options, const AllSums& sums,
                TreatmentEvaluation& result) {
  const std::vector<double> areas = {0.0,   0.0005, 0.001, 0.002, 0.003, 0.004, 0.005,
                                     0.006, 0.008,  0.01,  0.015, 0.02,  0.03};
  const std::vector<double> gates = {0.5, 1.0, 2.0, 4.0, 5.99, 9.21, 13.8, 20.0, 40.0, 100.0,
                                     1e12};
  result.mrroc = classify::SweepClassifier(sums.samples, areas, gates, sums.crop_pixels,
                                           sums.weed_pixels);
  result.operating_point = result.mrroc->OperatingPoint(options.costs_ratio);
  result.nearest_corner = result.mrroc->NearestToCorner();
}

}  // namespace

TreatmentEvaluation EvaluateTreatment(const TreatmentEvalOptions& options) {
  ThrowIfInvalid("evaluate treatment", options.Validate());
  TreatmentEvaluation result;
  result.preset = options.sim.preset;
  result.first_seed = options.sim.seed;
  result.seeds = options.seeds;
  result.engine = EngineUsed::Of(*options.profiles, options.calibration_error,
                                 options.calibration_error_text);
  result.odometry_fault = options.odometry_fault;
  result.visual_motion = options.visual_motion;
  result.costs_ratio = options.costs_ratio;
  result.mode = treatment::ToString(options.treatment.scheduler.mode);
  const double latency = options.true_valve_latency_s >= 0.0
                             ? options.true_valve_latency_s
                             : options.treatment.scheduler.bar.valve_latency_s;
  AllSums sums;
  ForEachSeed(options.sim, options.seeds, [&](int k, const sim::SimulatorOptions& so) {
    sim::Simulator simulator(so);
    const cv::Mat roi = WheelTrapezoid(simulator.camera(), so.vehicle.track_width_m);  // scoring
    RequireImageSize(options.profiles->vehicle, so.camera.image_width_px,
                     so.camera.image_height_px);
    SeedChains chains(options, so.preset, TreatmentEngineCamera(options, so.seed), latency);
    const SeedDrive drive = DriveSeed(options, simulator, chains, roi);
    result.distance_m = drive.distance_m;
    ScoreSeed(options, simulator, chains, drive, k, sums);
    result.camera_substitutions += chains.ours.pipe.camera_substitutions();
    CollectSeed(chains.ours, k == 0, sums, result);
  });
  result.ours = Finish(sums.ours);
  result.missed_crops = sums.ours.spray.missed;
  if (sums.thesis.ticks > 0) result.thesis = Finish(sums.thesis);
  if (sums.fault.ticks > 0) result.fault_stretch = SprayMetrics(sums.fault.spray);
  if (options.mrroc) SweepMrroc(options, sums, result);
  return result;
}

}  // namespace plantscale::app
