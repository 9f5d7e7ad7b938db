#include "engine/tracking/grid_tracker.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "engine/tracking/association.h"
#include "engine/tracking/grid_tracker_internal.h"
#include "engine/tracking/observation_model.h"
#include "engine/tracking/process_model.h"
#include "engine/tracking/pseudo_observation.h"

namespace plantscale::tracking {

using geometry::GridState;
using geometry::Matrix5d;

namespace {

geometry::GridModelOptions ModelOptions(const TrackerOptions& o) {
  geometry::GridModelOptions m;
  m.rows_each_side = o.rows_each_side;
  m.in_view_margin_px = o.edge_margin_px;
  return m;
}

std::optional<geometry::CentroidHeights> MakeHeights(const geometry::CameraModel& camera,
                                                     const TrackerOptions& o) {
  if (o.crop_radius_m <= 0.0 || o.crop_height_m <= 0.0) return std::nullopt;
  geometry::CentroidHeightOptions h;
  h.shape = {o.crop_radius_m, o.crop_height_m};
  return geometry::CentroidHeights(camera, h);
}

}  // namespace

GridTracker::GridTracker(const geometry::CameraModel& camera, const TrackerOptions& options)
    : camera_(camera),
      options_(options),
      model_(camera, ModelOptions(options)),
      heights_((ThrowIfInvalid("grid tracker", options.Validate()), MakeHeights(camera, options))),
      initialiser_(options.init, options.row_spacing_m, options.plant_spacing_m,
                   options.rows_each_side, options.track_width_m),
      filter_(options),
      wheels_(options),
      sizes_(options, camera.height()),
      loss_(options),
      spacing_check_(options.estimate_spacing ? options.spacing_check_chi2 : 0.0) {
  Reset();
}

void GridTracker::Reset() {
  held_lag_ = false;
  mode_ = TrackerMode::kInitialising;
  filter_.Reset();
  initialiser_.Reset();
  wheels_.Reset();
  since_frame_ = {};
  lines_in_view_ = -1;
  loss_.Reset(filter_.x()(GridState::kForward));
  spacing_check_.Start(options_.row_spacing_m, 0.0);
  spacing_reported_ = false;
}

GridState GridTracker::state() const { return filter_.state(); }

Matrix5d GridTracker::covariance() const { return filter_.covariance(); }

void GridTracker::Initialise(int64_t utime, const GridState& s, const Matrix5d& covariance) {
  held_lag_ = false;
  filter_.Restart(s, covariance);
  mode_ = TrackerMode::kTracking;
  if (utime_ < 0 || utime > utime_) utime_ = utime;
  lines_in_view_ = -1;
  loss_.Start(utime, filter_.x()(GridState::kForward));
  spacing_check_.Start(s.row_spacing_m, covariance(3, 3),
                       std::pow(options_.spacing_check_scale_sd * s.row_spacing_m, 2));
  FrameReport ignored;
  ShiftReference(ignored);
}

InputStatus GridTracker::AddOdometry(int64_t utime, double left_m_s, double right_m_s) {
  return AddOdometry(utime, left_m_s, right_m_s, options_.wheel_sd_fraction);
}

InputStatus GridTracker::AddOdometry(int64_t utime, double left_m_s, double right_m_s,
                                     double sd_fraction) {
  CatchUp();
  const OdometryIntake in = wheels_.Accept(utime, utime_, left_m_s, right_m_s, sd_fraction);
  if (in.step) Predict(*in.step);
  if (in.advance) utime_ = utime;
  return in.status;
}

void GridTracker::PredictTo(int64_t utime) {
  if (utime_ >= 0 && utime > utime_) {
    if (const std::optional<WheelStep> step = wheels_.StepTo(utime, utime_)) Predict(*step);
  }
  if (utime_ < 0 || utime > utime_) utime_ = utime;
}

void GridTracker::Predict(const WheelStep& step) {
  const WheelIncrement& measured = step.u;
  since_frame_.left_m += measured.left_m;
  since_frame_.right_m += measured.right_m;
  const double distance = std::abs(0.5 * (measured.left_m + measured.right_m));
  if (mode_ != TrackerMode::kTracking) {
    loss_.Coast(0.5 * (measured.left_m + measured.right_m));
    return;
  }
  const Transition t = TransitionFrom(filter_.layout(), options_, state(), filter_.OdometryScale(),
                                      measured, step.left_sd_m, step.right_sd_m, step.dt_s);
  filter_.Predict(t, distance);
}

GridAhead GridTracker::PredictAhead(double distance_m, double step_m) const {
  const int h = filter_.layout().head();
  const WheelMotion wheels{wheels_.left_m_s(), wheels_.right_m_s(), wheels_.have_speeds(),
                           filter_.OdometryScale()};
  return PredictGridAhead(filter_.layout(), options_, state(), filter_.p().topLeftCorner(h, h),
                          wheels, distance_m, step_m);
}

Eigen::Vector2d GridTracker::PlantPosition(int m, int n) const {
  return PlantPosition(m, n, Eigen::Vector2d::Ones());
}

Eigen::Vector2d GridTracker::PlantPosition(int m, int n, const Eigen::Vector2d& weight) const {
  const int offset = filter_.OffsetIndex(m, n);
  const Eigen::Vector2d delta =
      offset >= 0 ? Eigen::Vector2d(weight.cwiseProduct(filter_.x().segment<2>(offset)))
                  : Eigen::Vector2d::Zero();
  return PlantWithOffset(state(), m, n, delta);
}

std::optional<Eigen::Matrix2d> GridTracker::PlantOffsetCovariance(int m, int n) const {
  const int offset = filter_.OffsetIndex(m, n);
  if (offset < 0) return std::nullopt;
  return Eigen::Matrix2d(filter_.p().block<2, 2>(offset, offset));
}

std::optional<double> GridTracker::PlantHeightOffset(int m, int n) const {
  const int offset = filter_.OffsetIndex(m, n);
  if (offset < 0 || filter_.layout().plant_states() < 3) return std::nullopt;
  return filter_.x()(offset + 2);
}

Eigen::Vector4d GridTracker::calibration_estimate() const {
  if (!options_.CalibrationStates()) return Eigen::Vector4d::Zero();
  return filter_.x().segment<4>(filter_.layout().calibration_index());
}

Eigen::Matrix4d GridTracker::calibration_covariance() const {
  if (!options_.CalibrationStates()) return Eigen::Matrix4d::Zero();
  const int c = filter_.layout().calibration_index();
  return filter_.p().block<4, 4>(c, c);
}

void GridTracker::ShiftReference(FrameReport& report) {
  GridState s = state();
  const int k = model_.ShiftReference(s);
  if (k == 0) return;
  const double l = s.plant_spacing_m;
  filter_.ShiftLines(k, s);
  loss_.Shifted(k, l);
  report.lines_shifted += k;
}

FrameReport GridTracker::ProcessFrame(int64_t utime, int width, int height,
                                      std::span<const Feature> features) {
  FrameReport report = UpdateAtCapture(utime, width, height, features);
  CatchUp();
  return report;
}

void GridTracker::CatchUp() {
  if (!held_lag_) return;
  held_lag_ = false;
  if (mode_ == TrackerMode::kTracking) filter_.SetPose(caught_up_);
}

bool GridTracker::InitialiseFrom(int64_t utime, const std::vector<Feature>& valid,
                                 FrameReport& report) {
  const InitialiserResult init = initialiser_.Offer(valid, since_frame_);
  since_frame_ = {};
  if (!init.state) {
    report.skipped_reason = "initialising: " + init.reason;
    report.mode = mode_;
    return false;
  }
  Matrix5d p0 = Matrix5d::Zero();
  p0(0, 0) = std::pow(options_.init.offset_sd_m, 2);
  p0(1, 1) = std::pow(options_.init.forward_sd_m, 2);
  p0(2, 2) = std::pow(options_.init.bearing_sd_rad, 2);
  p0(3, 3) = std::pow(options_.row_spacing_sd_m, 2);
  p0(4, 4) = std::pow(options_.plant_spacing_sd_m, 2);
  Initialise(utime, *init.state, p0);
  report.initialised_now = true;
  return true;
}

FrameReport GridTracker::UpdateAtCapture(int64_t utime, int width, int height,
                                         std::span<const Feature> features) {
  CatchUp();
  FrameReport report;
  report.mode = mode_;
  if (RefuseFrame(camera_, options_, utime_, utime, width, height, report)) return report;
  PredictTo(utime);
  // A frame captured before the newest odometry (the camera's latency, or
  // odometry that arrived while the frame was being segmented) is compared
  // with the grid where it was at capture: the mean is driven back over the
  // lag with the newest wheel speeds for the update, and held there until
  // CatchUp drives it forward again. The covariance already holds the lag's
  // process noise.
  const double lag_s = utime_ > utime ? (utime_ - utime) * 1e-6 : 0.0;
  const WheelIncrement lag = wheels_.Over(lag_s);
  const std::vector<Feature> valid = ValidFeatures(features, centroid_heights(), report);
  if (mode_ != TrackerMode::kTracking && !InitialiseFrom(utime, valid, report)) return report;
  since_frame_ = {};

  filter_.AddFrameNoise();  // thesis eq. 4.2
  ShiftReference(report);
  const bool rewind = lag_s > 0.0 && wheels_.have_speeds() && mode_ == TrackerMode::kTracking;
  // The mean alone, driven over the lag (out-of-sequence frames).
  const auto move_mean = [&](const WheelIncrement& measured) {
    const double scale = filter_.OdometryScale();
    const WheelIncrement u{scale * measured.left_m, scale * measured.right_m};
    const MotionPrediction f = PredictGridMotion(state(), u, options_.track_width_m);
    filter_.SetPose({f.state.offset_m, f.state.forward_m, f.state.bearing_rad});
  };
  // A state initialised from this frame already stands at its capture.
  if (rewind && !report.initialised_now) move_mean({-lag.left_m, -lag.right_m});
  Update(valid, report);
  const Eigen::Vector3d at_capture = filter_.pose();
  if (rewind) move_mean(lag);
  CheckLost(utime, report);
  if (rewind && mode_ == TrackerMode::kTracking) {
    // Held at capture; CatchUp puts back the mean driven over the lag.
    caught_up_ = filter_.pose();
    filter_.SetPose(at_capture);
    held_lag_ = true;
  }
  report.mode = mode_;
  return report;
}

void GridTracker::Update(std::span<const Feature> features, FrameReport& report) {
  const GridState s = state();
  const std::vector<geometry::GridPlant> in_view = model_.PlantsInView(s);
  report.predicted = static_cast<int>(in_view.size());
  NoteLinesInView(in_view);
  filter_.Marginalise(in_view, spread_);
  const ObservationModel h(camera_, options_, centroid_heights());
  const Eigen::Vector3d bounce_prior = BouncePrior(options_);
  const FeatureFlags flags = MarkSkippedFeatures(options_, features, in_view);
  const std::vector<Candidate> matches =
      Associate(Gate(h, filter_, s, features, flags, in_view, bounce_prior), in_view.size(),
                features.size());
  report.matched = static_cast<int>(matches.size());
  for (const Candidate& c : matches) {
    const auto& g = in_view[static_cast<size_t>(c.plant)];
    report.associations.push_back({c.feature, g.m, g.n, c.gamma2});
  }
  const std::vector<Strip> strips =
      options_.merged_row_strips
          ? FindStrips(h, filter_, s, features, flags, in_view, matches, bounce_prior)
          : std::vector<Strip>{};
  report.strips = static_cast<int>(strips.size());
  const bool observable = Observable(options_, matches, in_view, report);
  if (!observable && (strips.empty() || !options_.strips_alone)) return;
  if (!observable) report.skipped_reason.clear();  // the strips alone: the rows' lateral position
  report.nis = UpdateOnFrame(filter_, h, s, features, in_view,
                             observable ? matches : std::vector<Candidate>{}, strips, bounce_prior);
  if (observable && options_.HeightFromSize()) {
    // The matches hold no merged or weed-sized blob (FeatureFlags::skipped).
    std::vector<SizeMatch> sized;
    for (const Candidate& c : matches) {
      const auto& g = in_view[static_cast<size_t>(c.plant)];
      sized.push_back({g.m, g.n, c.feature});
    }
    const PseudoObservation z = sizes_.Observe(filter_, *heights_, features, sized);
    if (z.factor.rows() > 0) filter_.Apply(z);
    sizes_.Learn(features, sized);
  }
  report.updated = true;
  loss_.Updated(utime_);
  if (options_.estimate_spacing) {
    const std::optional<SpacingMismatch> m = spacing_check_.Check(
        filter_.x()(GridState::kRowSpacing), filter_.p()(GridState::kRowSpacing, GridState::kRowSpacing));
    if (m && !spacing_reported_) {
      report.row_spacing_mismatch = m;
      spacing_reported_ = true;
    }
  }
}

void GridTracker::NoteLinesInView(const std::vector<geometry::GridPlant>& in_view) {
  if (in_view.empty()) return;
  int first = in_view.front().m;
  int last = in_view.front().m;
  for (const auto& g : in_view) {
    first = std::min(first, g.m);
    last = std::max(last, g.m);
  }
  first += loss_.lines_passed();
  last += loss_.lines_passed();
  if (lines_in_view_ >= 0) {
    // The spacing check's prior widens by the walk the filter adds.
    spacing_check_.AddNoise(
        filter_.AddSpacingNoise(std::abs(first - first_line_in_view_) + std::abs(last - lines_in_view_)));
  }
  first_line_in_view_ = first;
  lines_in_view_ = last;
}

void GridTracker::CheckLost(int64_t utime, FrameReport& report) {
  const std::string reason = loss_.Check(filter_, utime);
  if (reason.empty()) return;
  loss_.Lost(forward_distance_m());
  mode_ = TrackerMode::kLost;
  filter_.Lose();
  initialiser_.Reset();
  report.skipped_reason = "grid lost: " + reason;
}

}  // namespace plantscale::tracking
