#include "engine/treatment/treatment_system.h"

#include <opencv2/imgproc.hpp>
#include <algorithm>
#include <cmath>
#include <limits>

namespace plantscale::treatment {

OptionErrors TreatmentOptions::Validate() const {
  OptionErrors e = Prefixed("classifier", classifier.Validate());
  const auto add = [&e](OptionErrors more) { e.insert(e.end(), more.begin(), more.end()); };
  add(Prefixed("map", map.Validate()));
  add(Prefixed("scheduler", scheduler.Validate()));
  add(Prefixed("registry", registry.Validate()));
  RequireInRange(e, "crop_footprint_scale", crop_footprint_scale, 0.05, 2.0);
  RequireInRange(e, "crop_footprint_min_half_m", crop_footprint_min_half_m, 0.0, 0.5);
  RequireInRange(e, "weed_footprint_scale", weed_footprint_scale, 0.05, 2.0);
  RequireInRange(e, "weed_height_m", weed_height_m, 0.0, 0.5);
  RequireInRange(e, "outline_height_m", outline_height_m, 0.0, 0.5);
  RequireInRange(e, "min_weed_part_m2", min_weed_part_m2, 0.0, 1.0);
  RequireInRange(e, "own_offset_fraction_across", own_offset_fraction_across, 0.0, 1.0);
  RequireInRange(e, "own_offset_fraction_along", own_offset_fraction_along, 0.0, 1.0);
  RequireInRange(e, "uncertainty_margin_across_m", uncertainty_margin_across_m, 0.0, 1.0);
  RequireInRange(e, "uncertainty_margin_along_m", uncertainty_margin_along_m, 0.0, 1.0);
  if (close_on_uncertainty && !(UncertaintyMargin().minCoeff() > 0.0)) {
    e.push_back({"uncertainty_margin_across_m",
                 "derives no margin (crop_footprint_min_half_m is 0): set the margins"});
  }
  return e;
}

Eigen::Vector2d TreatmentOptions::UncertaintyMargin(double crop_radius_m) const {
  if (!close_on_uncertainty) return Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  const double half = std::max(crop_footprint_scale * std::max(0.0, crop_radius_m), crop_footprint_min_half_m);
  const double across = half + 0.5 * scheduler.bar.nozzle_spacing_m;
  return {uncertainty_margin_across_m > 0.0 ? uncertainty_margin_across_m : across,
          uncertainty_margin_along_m > 0.0 ? uncertainty_margin_along_m : half};
}

namespace {

SchedulerOptions WithMargins(const TreatmentOptions& o) {
  SchedulerOptions s = o.scheduler;
  const Eigen::Vector2d margin = o.UncertaintyMargin();
  s.fail_safe.max_reach_across_m = margin.x();
  s.fail_safe.max_reach_along_m = margin.y();
  return s;
}

// The vehicle y of the image's bottom edge on the virtual plane (the view's nearest).
double ViewNearY(const geometry::CameraModel& camera) {
  const double w = camera.width(), h = camera.height();
  const std::optional<Quad> view = FootprintOnPlane(camera, {0.5 * w, 0.5 * h}, 0.0, 0.0, w, h, 1.0);
  if (!view) return 0.0;
  double y = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& c : *view) y = std::min(y, c.y());
  return y;
}

}  // namespace

void FeatureBlobIndices(std::span<const vision::Blob> blobs, std::vector<int>& out) {
  out.clear();
  for (size_t i = 0; i < blobs.size(); ++i) {
    if (blobs[i].on_ground) out.push_back(static_cast<int>(i));
  }
}

std::optional<Quad> TreatmentSystem::BoxOnCropPlane(const vision::Blob& b) const {
  return FootprintOnPlane(camera_, b.centroid_px, b.bbox_px.x, b.bbox_px.y,
                          b.bbox_px.x + b.bbox_px.width, b.bbox_px.y + b.bbox_px.height, 1.0,
                          CropPlaneHeight(b.centroid_px));
}

bool TreatmentSystem::CoversAPrediction(const vision::Blob& b,
                                        std::span<const classify::PredictedCrop> crops) const {
  const std::optional<Quad> q = BoxOnCropPlane(b);
  if (!q) return false;
  return std::any_of(crops.begin(), crops.end(), [&](const classify::PredictedCrop& c) {
    return InsideQuad(*q, c.ground_m);
  });
}

bool TreatmentSystem::VotesWeed(const classify::BlobDecision& d, const vision::Blob& b,
                                std::span<const classify::PredictedCrop> crops) const {
  if (!d.clipped || options_.clipped_on_crop_votes_weed) return true;
  return !CoversAPrediction(b, crops);
}

TreatmentSystem::TreatmentSystem(const geometry::CameraModel& camera,
                                 const TreatmentOptions& options, NozzleSink sink)
    : camera_(camera),
      options_(options),
      classifier_((ThrowIfInvalid("treatment", options.Validate()), options.classifier)),
      map_(options.map),
      scheduler_(WithMargins(options), std::move(sink)),
      registry_(options.registry),
      view_near_y_m_(ViewNearY(camera)) {
  options_.scheduler = scheduler_.options();
}

PlantReach TreatmentSystem::ReachAtBar(const tracking::GridTracker& tracker) const {
  if (!options_.close_on_uncertainty) return {};
  // Dead reckoning from now until the spray lands: the valves' latency and
  // the pose period the ticks are led over, in increments of one period.
  const SchedulerOptions& s = scheduler_.options();
  const double travel = std::abs(tracker.ground_speed_m_s());
  const double ahead = travel * (s.bar.valve_latency_s + s.pose_period_s);
  const double step = std::max(travel * s.pose_period_s, 1e-3);
  return PlantReachAtBar(tracker, ahead, s.bar.bar_offset_m, step);
}

double TreatmentSystem::CropPlaneHeight(const Eigen::Vector2d& centroid_px) const {
  return heights_ ? heights_->HeightAt(centroid_px) : camera_.options().virtual_plane_height_m;
}

void TreatmentSystem::AddFootprint(const BedPose& pose, const vision::Blob& b, bool crop) {
  AddFootprint(pose, b.centroid_px, b.bbox_px, crop);
}

void TreatmentSystem::AddFootprint(const BedPose& pose, const Eigen::Vector2d& centroid_px,
                                   const cv::Rect& box, bool crop,
                                   std::optional<Eigen::Vector2d> centre_m) {
  if (const std::optional<Quad> q = BedFootprint(pose, centroid_px, box, crop, centre_m)) {
    map_.AddFootprint(*q, crop);
  }
}

std::optional<Quad> TreatmentSystem::BedFootprint(const BedPose& pose,
                                                  const Eigen::Vector2d& centroid_px,
                                                  const cv::Rect& box, bool crop,
                                                  std::optional<Eigen::Vector2d> centre_m) const {
  const double scale = crop ? options_.crop_footprint_scale : options_.weed_footprint_scale;
  // Weeds stand lower than crops: their footprints lie at the weeds' height.
  const std::optional<double> plane = crop ? CropPlaneHeight(centroid_px) : options_.weed_height_m;
  const std::optional<Quad> q = FootprintOnPlane(camera_, centroid_px, box.x, box.y,
                                                 box.x + box.width, box.y + box.height, scale, plane);
  if (!q) return std::nullopt;
  Eigen::Vector2d low = (*q)[0];
  Eigen::Vector2d high = (*q)[0];
  for (const Eigen::Vector2d& corner : *q) {
    low = low.cwiseMin(corner);
    high = high.cwiseMax(corner);
  }
  const Eigen::Vector2d middle = 0.5 * (low + high);
  // A small crop's footprint is widened to cover the placement error.
  Eigen::Vector2d stretch = Eigen::Vector2d::Ones();
  if (crop) {
    const Eigen::Vector2d half = 0.5 * (high - low);
    for (int k = 0; k < 2; ++k) {
      if (half[k] > 0.0) stretch[k] = std::max(1.0, options_.crop_footprint_min_half_m / half[k]);
    }
  }
  // Moved as a whole so that its middle lands on centre_m: the image box
  // projects further beyond its centroid than short of it (perspective),
  // and the spray should straddle the plant evenly.
  const Eigen::Vector2d to = centre_m ? *centre_m : middle;
  Quad bed;
  for (size_t i = 0; i < 4; ++i) {
    bed[i] = VehicleToBed(pose, to + stretch.cwiseProduct((*q)[i] - middle));
  }
  return bed;
}

namespace {

// Frames after which a plant no longer seen is forgotten (8 s at 12.5 Hz:
// long past the bar; its cells stay where it was last placed).
constexpr int64_t kFollowFrames = 100;

}  // namespace

void TreatmentSystem::PlaceFollowing(std::pair<int, int> key, const Quad& bed_quad,
                                     double along_bed_m, bool moves) {
  const auto [it, added] = followed_.try_emplace(key);
  FollowedPlant& plant = it->second;
  plant.last_frame = frames_;
  if (added) plant.along_bed_m = along_bed_m;
  const size_t earlier = plant.spans.size();
  map_.AppendSpans(bed_quad, along_bed_m, plant.spans);
  const std::span<const ColumnSpan> spans(plant.spans);
  if (!moves || along_bed_m == plant.along_bed_m) {
    map_.AddSpans(spans.subspan(earlier), plant.along_bed_m, 1, true);
    return;
  }
  map_.AddSpans(spans.first(earlier), plant.along_bed_m, -1, true);
  plant.along_bed_m = along_bed_m;
  map_.AddSpans(spans, plant.along_bed_m, 1, true);
}

bool TreatmentSystem::BlobPixels(const cv::Mat& mask, const vision::Blob& blob,
                                 std::vector<cv::Point>& out) {
  out.clear();
  const cv::Rect box = blob.bbox_px & cv::Rect(0, 0, mask.cols, mask.rows);
  if (box != blob.bbox_px || box.empty()) return false;
  // The blob is the component spanning its whole box with its area.
  const int n = cv::connectedComponentsWithStats(mask(box), components_, stats_, centroids_, 8,
                                                 CV_32S);
  int label = -1;
  for (int k = 1; k < n && label < 0; ++k) {
    if (stats_.at<int>(k, cv::CC_STAT_LEFT) == 0 && stats_.at<int>(k, cv::CC_STAT_TOP) == 0 &&
        stats_.at<int>(k, cv::CC_STAT_WIDTH) == box.width &&
        stats_.at<int>(k, cv::CC_STAT_HEIGHT) == box.height &&
        stats_.at<int>(k, cv::CC_STAT_AREA) == blob.area_px) {
      label = k;
    }
  }
  if (label < 0) return false;
  out.reserve(static_cast<size_t>(blob.area_px));
  for (int v = 0; v < components_.rows; ++v) {
    const int* c = components_.ptr<int>(v);
    for (int u = 0; u < components_.cols; ++u) {
      if (c[u] == label) out.emplace_back(box.x + u, box.y + v);
    }
  }
  return true;
}

bool TreatmentSystem::SplitMergedBlob(int feature, const vision::Blob& blob,
                                      const classify::BlobDecision& d,
                                      std::span<const classify::PredictedCrop> crops,
                                      const geometry::Matrix5d& covariance, const cv::Mat& mask) {
  if (crops.empty() || !BlobPixels(mask, blob, split_pixels_)) return false;
  SplitBlob split;
  split.feature = feature;
  split_ground_.clear();
  const double h = CropPlaneHeight(blob.centroid_px);
  for (const cv::Point& p : split_pixels_) {
    const auto g = camera_.ImageToPlane({p.x + 0.5, p.y + 0.5}, h);
    if (!g) continue;
    split_ground_.push_back(*g);
    split.pixels.push_back(p);
  }
  if (split.pixels.empty()) return false;
  // Each pixel stands for an equal share of the blob's ground area.
  split_area_.assign(split.pixels.size(), d.area_m2 / static_cast<double>(split.pixels.size()));
  classifier_.SplitMerged(split_ground_, split_area_, d.clipped, crops, covariance, split.crop,
                          &split_part_);
  // A part's class: that of its pixels (SplitMerged labels a part as a whole).
  split_part_crop_.assign(crops.size(), 0);
  for (size_t q = 0; q < split.crop.size(); ++q) {
    if (split_part_[q] >= 0 && split.crop[q]) split_part_crop_[static_cast<size_t>(split_part_[q])] = 1;
  }
  frame_.split.push_back(std::move(split));
  return true;
}

void TreatmentSystem::AddDoubt(const BedPose& pose, const vision::Blob& b) {
  if (const std::optional<Quad> q = BoxOnCropPlane(b)) map_.AddDoubt(VehicleToBed(pose, *q));
}

std::vector<vision::Blob> TreatmentSystem::WeedParts(std::span<const cv::Point> pixels,
                                                    std::span<const uint8_t> weed, double pixel_area_m2) {
  std::vector<vision::Blob> out;
  cv::Rect box;
  for (size_t q = 0; q < pixels.size(); ++q) {
    if (weed[q]) box |= cv::Rect(pixels[q].x, pixels[q].y, 1, 1);
  }
  if (box.empty()) return out;
  parts_.create(box.height, box.width, CV_8UC1);
  parts_.setTo(0);
  for (size_t q = 0; q < pixels.size(); ++q) {
    if (weed[q]) parts_.at<uint8_t>(pixels[q] - box.tl()) = 255;
  }
  const int n = cv::connectedComponentsWithStats(parts_, components_, stats_, centroids_, 8, CV_32S);
  const double min_px = options_.min_weed_part_m2 / pixel_area_m2;
  std::vector<int> part_of(static_cast<size_t>(n), -1);  // per label
  for (int k = 1; k < n; ++k) {
    if (stats_.at<int>(k, cv::CC_STAT_AREA) < min_px) continue;
    part_of[static_cast<size_t>(k)] = static_cast<int>(out.size());
    vision::Blob& b = out.emplace_back();
    b.area_px = stats_.at<int>(k, cv::CC_STAT_AREA);
    b.bbox_px = cv::Rect(box.x + stats_.at<int>(k, cv::CC_STAT_LEFT), box.y + stats_.at<int>(k, cv::CC_STAT_TOP),
                         stats_.at<int>(k, cv::CC_STAT_WIDTH), stats_.at<int>(k, cv::CC_STAT_HEIGHT));
    // Pixel centres at +0.5, as the blobs' centroids.
    b.centroid_px = Eigen::Vector2d(box.x + centroids_.at<double>(k, 0) + 0.5,
                                    box.y + centroids_.at<double>(k, 1) + 0.5);
  }
  for (size_t q = 0; q < pixels.size(); ++q) {
    const int j = weed[q] ? part_of[static_cast<size_t>(components_.at<int>(pixels[q] - box.tl()))] : -1;
    if (j < 0) continue;
    vision::Blob& b = out[static_cast<size_t>(j)];
    const Eigen::Vector2d d(pixels[q].x + 0.5 - b.centroid_px.x(), pixels[q].y + 0.5 - b.centroid_px.y());
    b.covariance_px2 += d * d.transpose() / static_cast<double>(b.area_px);
  }
  return out;
}

void TreatmentSystem::VoteWeedParts(const BedPose& pose, std::span<const cv::Point> pixels,
                                    std::span<const uint8_t> weed, double pixel_area_m2) {
  for (const vision::Blob& part : WeedParts(pixels, weed, pixel_area_m2)) {
    AddFootprint(pose, part.centroid_px, part.bbox_px, false);
  }
}

int TreatmentSystem::ObserveWeedsBeyondOutline(const vision::Blob& blob, const classify::BlobDecision& d,
                                               const cv::Mat& mask, const BedPose& pose) {
  const double limit = classifier_.options().outline_limit_sd;
  // A blob the model classified was already cut where crop meets weed.
  if (!(limit > 0.0) || !d.crop || !d.associated || d.clipped || d.fragment || d.lone ||
      d.learned_class >= 0 || mask.empty() ||
      !BlobPixels(mask, blob, split_pixels_)) {
    return 0;
  }
  const double h = CropPlaneHeight(blob.centroid_px);
  split_ground_.clear();
  outline_pixels_.clear();
  for (const cv::Point& p : split_pixels_) {
    if (const auto g = camera_.ImageToPlane({p.x + 0.5, p.y + 0.5}, h)) {
      split_ground_.push_back(*g);
      outline_pixels_.push_back(p);
    }
  }
  if (classify::BeyondCropOutline(split_ground_, limit, beyond_) == 0) return 0;
  int observed = 0;
  for (vision::Blob& part : WeedParts(outline_pixels_, beyond_, d.area_m2 / static_cast<double>(blob.area_px))) {
    const std::optional<Eigen::Vector2d> low = camera_.ImageToPlane(part.centroid_px, options_.weed_height_m);
    const std::optional<Eigen::Vector2d> on_plane = camera_.ImageToPlane(part.centroid_px, h);
    if (!low || !on_plane) continue;
    part.ground_m = *on_plane;
    classify::BlobDecision w;
    w.area_m2 = d.area_m2 * part.area_px / static_cast<double>(blob.area_px);
    w.size_filter_m2 = d.size_filter_m2;
    const int id = registry_.Observe(VehicleToBed(pose, *low), w);
    registry_.AddSize(id, SizeSampleOf(part, w));
    if (options_.outline_weed_votes) AddFootprint(pose, part.centroid_px, part.bbox_px, false);
    ++observed;
  }
  return observed;
}

const FrameTreatment& TreatmentSystem::OnFrame(int64_t utime, const tracking::GridTracker& tracker,
                                               const tracking::FrameReport& report,
                                               std::span<const vision::Blob> blobs,
                                               std::span<const tracking::Feature> features,
                                               std::span<const int> blob_of_feature,
                                               const cv::Mat& mask) {
  StartFrame(utime, tracker, report, features.size());
  if (tracker.mode() != tracking::TrackerMode::kTracking) return frame_;
  const geometry::GridState state = tracker.state();
  const std::vector<classify::PredictedCrop> crops =
      classify::PredictCrops(tracker.model(), state, classifier_.crop_reach_m());
  classifier_.Classify(features, crops, tracker.covariance(), frame_.decisions);
  // The grower's model, where it classified the blobs and is sure.
  for (size_t i = 0; i < features.size(); ++i) {
    const vision::Blob& b = blobs[static_cast<size_t>(blob_of_feature[i])];
    if (b.learned_class >= 0) {
      classify::FuseLearned(b.learned_class, b.learned_confidence, options_.classifier,
                            frame_.decisions[i]);
    }
  }
  frame_.classified = true;
  const BedPose pose = BedPoseFromGrid(utime, state, tracker.forward_distance_m(), 0.0);
  // What the camera saw this frame (the image on the plane): soil there is soil.
  const double w = camera_.width(), h = camera_.height();
  std::optional<Quad> seen;  // on the bed
  if (const std::optional<Quad> view = FootprintOnPlane(camera_, {0.5 * w, 0.5 * h}, 0.0, 0.0, w, h, 1.0)) {
    const Quad bed = VehicleToBed(pose, *view);
    map_.MarkObserved(bed);
    seen = bed;
  }
  std::vector<PlantFootprint> plants;
  for (size_t i = 0; i < features.size(); ++i) {
    const classify::BlobDecision& d = frame_.decisions[i];
    const vision::Blob& blob = blobs[static_cast<size_t>(blob_of_feature[i])];
    MapBlob(static_cast<int>(i), blob, d, crops, tracker, mask, pose, plants);
    // Crop by the model but no crop's region took it: a crop seen far off
    // before the grid places it, a leaf cut off, touching crops. Its
    // plants are recorded from the frames that place them; a record of its
    // own would count a crop twice.
    if (d.learned && d.crop && !d.associated) continue;
    const std::optional<Eigen::Vector2d> low =
        d.crop ? std::nullopt : camera_.ImageToPlane(blob.centroid_px, options_.weed_height_m);
    frame_.plant_ids[i] = registry_.Observe(
        VehicleToBed(pose, low ? *low : features[i].ground_m), d,
        d.associated ? std::optional<Eigen::Vector2d>(VehicleToBed(pose, d.predicted_ground_m))
                     : std::nullopt);
    registry_.AddSize(frame_.plant_ids[i], SizeSampleOf(blob, d));
    ObserveWeedsBeyondOutline(blob, d, mask, pose);
  }
  if (seen) registry_.CountView(*seen);
  registry_.EndFrame();
  last_view_ = seen;
  last_predicted_bed_.clear();
  for (const classify::PredictedCrop& c : crops) last_predicted_bed_.push_back(VehicleToBed(pose, c.ground_m));
  last_plant_spacing_m_ = state.plant_spacing_m;
  PlacePlantFootprints(plants, tracker, pose);
  // Plants long out of view stay where they were last placed.
  std::erase_if(followed_,
                [&](const auto& f) { return frames_ - f.second.last_frame > kFollowFrames; });
  return frame_;
}

void TreatmentSystem::StartFrame(int64_t utime, const tracking::GridTracker& tracker,
                                 const tracking::FrameReport& report, size_t features) {
  last_frame_utime_ = utime;
  ++frames_;
  heights_ = tracker.centroid_heights();
  frame_.classified = false;
  frame_.map_reset = false;
  frame_.decisions.clear();
  frame_.split.clear();
  frame_.plant_ids.assign(features, -1);
  if (report.initialised_now) {
    // A new bed frame: what was mapped before cannot be placed in it.
    map_.Clear();
    registry_.Clear();
    last_view_.reset();
    followed_.clear();
    frame_.map_reset = true;
    ++map_resets_;
  }
}

// The blob's share of its record's size: the area and the pixels'
// covariance of its core (the mask before the segmenter's growth,
// vision::Blob::core_area_px: growth adds a ring of soil the smoothing
// lit and the shaded flank below the leaf tips, neither in the leaf-tip
// outline) on the plane of the leaf tips (outline_height_m). A ray's
// footprint on a horizontal plane grows with the plane's depth below the
// camera, so lengths on it scale by (C − z) / (C − h) from the virtual
// plane at h, C the camera's height.
// A crop is read on its blob's core at the leaf tips' plane; a weed on the
// whole grown blob at the weeds' plane (treatment_system.h, weed_height_m):
// thresholding the σ = 2 smoothed image cuts a weed a few pixels across
// down to about a third of its area, which the growth gives back.
SizeSample TreatmentSystem::SizeSampleOf(const vision::Blob& blob, const classify::BlobDecision& d) const {
  const double h = camera_.options().virtual_plane_height_m, c = camera_.options().height_m;
  const double z = !d.crop                         ? options_.weed_height_m
                   : options_.outline_height_m > 0.0 ? options_.outline_height_m
                                                     : h;
  const double scale = (c - z) / (c - h), scale2 = scale * scale;
  const vision::BlobCore core =
      d.crop ? vision::CoreOf(blob)
             : vision::BlobCore{static_cast<double>(blob.area_px), blob.centroid_px, blob.covariance_px2};
  const double area = blob.area_px > 0 ? d.area_m2 * core.area_px / blob.area_px : d.area_m2;
  const std::optional<Eigen::Vector2d> centre = camera_.ImageToPlane(core.centroid_px, h);
  const Eigen::Matrix2d j = camera_.ImageToPlaneJacobian(core.centroid_px, h);
  return {area * scale2, centre ? *centre : blob.ground_m, scale2 * j * core.covariance_px2 * j.transpose(),
          d.clipped};
}

// Pixels of plant (m, n): one footprint per plant and frame.
void TreatmentSystem::AddToPlant(std::vector<PlantFootprint>& plants, int m, int n, double area_px,
                                 const Eigen::Vector2d& moment_px, const cv::Rect& box) {
  auto it = std::find_if(plants.begin(), plants.end(),
                         [&](const PlantFootprint& p) { return p.m == m && p.n == n; });
  if (it == plants.end()) {
    plants.push_back({m, n, 0.0, Eigen::Vector2d::Zero(), box});
    it = plants.end() - 1;
  }
  it->area_px += area_px;
  it->moment_px += moment_px;
  it->box |= box;
}

// One blob's votes on the map: a crop joins its plant's footprint (or marks
// its own), a merged blob is split among the predicted crops, a weed votes.
void TreatmentSystem::MapBlob(int feature, const vision::Blob& blob, const classify::BlobDecision& d,
                              const std::vector<classify::PredictedCrop>& crops,
                              const tracking::GridTracker& tracker, const cv::Mat& mask,
                              const BedPose& pose, std::vector<PlantFootprint>& plants) {
  // The model sure of crop but no crop's region took it: touching crops,
  // split among the predictions as the rule's merged blobs are.
  const bool maybe_merged =
      d.learned ? d.crop && !d.associated
                : !d.crop && !d.associated && (d.clipped || d.area_m2 >= d.size_filter_m2);
  if (d.learned && !d.crop) {
    // A weed by the model: its own box, wherever it stands.
    if (VotesWeed(d, blob, crops)) AddFootprint(pose, blob, false);
  } else if (d.crop && d.associated && options_.crop_footprint_per_plant) {
    AddToPlant(plants, d.m, d.n, blob.area_px, blob.area_px * blob.centroid_px, blob.bbox_px);
  } else if (maybe_merged && options_.split_merged && !mask.empty() &&
             SplitMergedBlob(feature, blob, d, crops, tracker.covariance(), mask)) {
    MapSplitParts(blob, d, crops, pose, plants);
  } else if (options_.abstain_merged && maybe_merged && CoversAPrediction(blob, crops)) {
    // Possibly merged plants: no votes either way.
  } else if (!d.crop || d.associated) {
    // Crop by size alone (merged plants): its centroid is no plant's
    // centre, so it marks no cells; the plants in it are mapped from other
    // frames.
    if (d.crop || VotesWeed(d, blob, crops)) AddFootprint(pose, blob, d.crop);
  }
}

// The parts of a split blob (frame_.split.back(), split_part_): crop ones
// join their plant's footprint, weed ones vote weed.
void TreatmentSystem::MapSplitParts(const vision::Blob& blob, const classify::BlobDecision& d,
                                    const std::vector<classify::PredictedCrop>& crops,
                                    const BedPose& pose, std::vector<PlantFootprint>& plants) {
  const SplitBlob& split = frame_.split.back();
  const std::vector<int>& part = split_part_;
  std::vector<cv::Rect> box(crops.size() + 1);
  std::vector<double> area(crops.size() + 1, 0.0);
  std::vector<Eigen::Vector2d> moment(crops.size() + 1, Eigen::Vector2d::Zero());
  for (size_t q = 0; q < split.pixels.size(); ++q) {
    const size_t k = static_cast<size_t>(part[q] + 1);  // 0: beyond every radius
    const cv::Point& p = split.pixels[q];
    box[k] |= cv::Rect(p.x, p.y, 1, 1);
    area[k] += 1.0;
    moment[k] += Eigen::Vector2d(p.x + 0.5, p.y + 0.5);
  }
  for (size_t k = 1; k < box.size(); ++k) {
    if (!(area[k] > 0.0) || !split_part_crop_[k - 1]) continue;
    if (options_.crop_footprint_per_plant) {
      AddToPlant(plants, crops[k - 1].m, crops[k - 1].n, area[k], moment[k], box[k]);
    } else {
      AddFootprint(pose, moment[k] / area[k], box[k], true);
    }
  }
  if (d.learned || !VotesWeed(d, blob, crops)) return;  // the model's crop: no weed in it
  if (!options_.merged_weed_parts_only) {
    AddFootprint(pose, blob, false);
    return;
  }
  // Only plant matter beyond every predicted crop's split radius: a part
  // near a prediction that failed its tests is most likely that crop's
  // leaves cut off-centre, not a weed.
  beyond_.resize(part.size());
  for (size_t q = 0; q < part.size(); ++q) beyond_[q] = part[q] < 0 ? 1 : 0;
  VoteWeedParts(pose, split.pixels, beyond_, d.area_m2 / static_cast<double>(split.pixels.size()));
  AddDoubt(pose, blob);
}

// Each crop plant's footprint of this frame, at its tracked position (or
// where its pixels are), following the plant when so configured.
void TreatmentSystem::PlacePlantFootprints(const std::vector<PlantFootprint>& plants,
                                           const tracking::GridTracker& tracker, const BedPose& pose) {
  const bool follow =
      options_.crop_footprint_at_tracked_plant && options_.crop_footprint_follows_plant;
  const Eigen::Vector2d own_offset_weight(options_.own_offset_fraction_across,
                                          options_.own_offset_fraction_along);
  for (const PlantFootprint& p : plants) {
    if (!(p.area_px > 0.0)) continue;
    const std::optional<Eigen::Vector2d> centre =
        options_.crop_footprint_at_tracked_plant
            ? std::optional<Eigen::Vector2d>(tracker.PlantPosition(p.m, p.n, own_offset_weight))
            : std::nullopt;
    if (!follow) {
      AddFootprint(pose, p.moment_px / p.area_px, p.box, true, centre);
    } else if (const auto q = BedFootprint(pose, p.moment_px / p.area_px, p.box, true, centre)) {
      // Only an estimate with the plant's own offset moves it: beyond the
      // view's border the tracker has let that go and holds the grid node.
      PlaceFollowing({tracker.lines_passed() + p.m, p.n}, *q, VehicleToBed(pose, *centre).y(),
                     tracker.PlantOffsetCovariance(p.m, p.n).has_value());
    }
  }
}

std::vector<int> TreatmentSystem::FlushRecordsInView() {
  if (!last_view_) return {};
  return registry_.FlushInView(*last_view_, last_predicted_bed_, 0.5 * last_plant_spacing_m_);
}

void TreatmentSystem::ForgetBehind(double bed_y_m) {
  constexpr int kStep = 256;
  const double row = std::min(std::floor((bed_y_m - map_.options().start_y_m) / map_.options().cell_m),
                              double{1 << 28});
  if (!(row >= map_.first_row() + kStep)) return;
  const int before = static_cast<int>(row) / kStep * kStep;
  registry_.TakeFinalCounts(map_, before);
  registry_.LetGoFinal();
  map_.ForgetBefore(before);
}

BedPose TrackerPose(const tracking::GridTracker& tracker, int64_t utime, bool speed_known) {
  // The wheels' speed past the slip guard, corrected by the scale the
  // tracker has learnt: the latency lead and the tick's strip are ground
  // distances.
  BedPose pose = BedPoseFromGrid(utime, tracker.state(), tracker.forward_distance_m(),
                                 speed_known ? tracker.ground_speed_m_s() : 0.0);
  pose.distance_m -= pose.speed_m_s * 1e-6 * static_cast<double>(tracker.utime() - utime);
  return pose;
}

std::span<const TickResult> TreatmentSystem::OnPose(int64_t utime,
                                                    const tracking::GridTracker& tracker,
                                                    bool odometry_ok, bool camera_ok) {
  SafetyInputs safety;
  safety.pose_utime = tracker.utime();
  safety.last_frame_utime = last_frame_utime_;
  safety.camera_ok = camera_ok;
  safety.odometry_valid = odometry_ok;
  safety.tracking = tracker.mode() == tracking::TrackerMode::kTracking;
  const PlantReach reach = ReachAtBar(tracker);
  safety.reach_across_m = reach.across_m;
  safety.reach_along_m = reach.along_m;
  return TicksFrom(utime, TrackerPose(tracker, tracker.utime(), true), safety);
}

std::span<const TickResult> TreatmentSystem::TicksFrom(int64_t utime, const BedPose& pose,
                                                       const SafetyInputs& safety, int count) {
  const SchedulerOptions& o = scheduler_.options();
  const int64_t tick_us = std::llround(o.tick_s * 1e6);
  const int n = count > 0 ? count : o.TicksPerPose();
  pose_ticks_.clear();
  for (int k = 0; k < n; ++k) pose_ticks_.push_back(Tick(utime + k * tick_us, pose, safety));
  return pose_ticks_;
}

TickResult TreatmentSystem::Tick(int64_t utime, const BedPose& pose, const SafetyInputs& safety) {
  TickResult r = scheduler_.Tick(utime, pose, map_, safety);
  for (const NozzleTarget& t : r.opened) {
    registry_.MarkSprayed(t, &newly_sprayed_);
    map_.MarkTreated(t.x0, t.x1, t.y0, t.y1);
  }
  return r;
}

vision::SegmenterOptions SegmenterOptionsFor(SprayMode mode, vision::SegmenterOptions base) {
  if (mode == SprayMode::kWeed) {
    base.soil_growth.join_min_area_px = std::numeric_limits<int>::max();
  }
  return base;
}

}  // namespace plantscale::treatment
