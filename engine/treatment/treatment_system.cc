#include "engine/treatment/treatment_system.h"

#include <algorithm>

namespace plantscale::treatment {

OptionErrors TreatmentOptions::Validate() const {
  OptionErrors e = Prefixed("classifier", classifier.Validate());
  const auto add = [&e](OptionErrors more) { e.insert(e.end(), more.begin(), more.end()); };
  add(Prefixed("map", map.Validate()));
  add(Prefixed("scheduler", scheduler.Validate()));
  add(Prefixed("registry", registry.Validate()));
  RequireInRange(e, "crop_footprint_scale", crop_footprint_scale, 0.05, 2.0);
  RequireInRange(e, "weed_footprint_scale", weed_footprint_scale, 0.05, 2.0);
  return e;
}

void FeatureBlobIndices(std::span<const vision::Blob> blobs, std::vector<int>& out) {
  out.clear();
  for (size_t i = 0; i < blobs.size(); ++i) {
    if (blobs[i].on_ground) out.push_back(static_cast<int>(i));
  }
}

bool TreatmentSystem::CoversAPrediction(const vision::Blob& b,
                                        std::span<const classify::PredictedCrop> crops) const {
  const std::optional<Quad> q =
      FootprintOnPlane(camera_, b.centroid_px, b.bbox_px.x, b.bbox_px.y,
                       b.bbox_px.x + b.bbox_px.width, b.bbox_px.y + b.bbox_px.height, 1.0);
  if (!q) return false;
  for (const classify::PredictedCrop& c : crops) {
    bool pos = false, neg = false;
    for (size_t i = 0; i < 4; ++i) {
      const Eigen::Vector2d& a = (*q)[i];
      const Eigen::Vector2d& e = (*q)[(i + 1) % 4];
      const double cross = (e.x() - a.x()) * (c.ground_m.y() - a.y()) -
                           (e.y() - a.y()) * (c.ground_m.x() - a.x());
      pos |= cross > 0.0;
      neg |= cross < 0.0;
    }
    if (!(pos && neg)) return true;
  }
  return false;
}

TreatmentSystem::TreatmentSystem(const geometry::CameraModel& camera,
                                 const TreatmentOptions& options, NozzleSink sink)
    : camera_(camera),
      options_(options),
      classifier_((ThrowIfInvalid("treatment", options.Validate()), options.classifier)),
      map_(options.map),
      scheduler_(options.scheduler, std::move(sink)),
      registry_(options.registry) {}

void TreatmentSystem::AddFootprint(const BedPose& pose, const vision::Blob& b, bool crop) {
  AddFootprint(pose, b.centroid_px, b.bbox_px, crop);
}

void TreatmentSystem::AddFootprint(const BedPose& pose, const Eigen::Vector2d& centroid_px,
                                   const cv::Rect& box, bool crop) {
  const double scale = crop ? options_.crop_footprint_scale : options_.weed_footprint_scale;
  const std::optional<Quad> q = FootprintOnPlane(camera_, centroid_px, box.x, box.y,
                                                 box.x + box.width, box.y + box.height, scale);
  if (!q) return;
  Quad bed;
  for (size_t i = 0; i < 4; ++i) bed[i] = VehicleToBed(pose, (*q)[i]);
  map_.AddFootprint(bed, crop);
}

const FrameTreatment& TreatmentSystem::OnFrame(int64_t utime, const tracking::GridTracker& tracker,
                                               const tracking::FrameReport& report,
                                               std::span<const vision::Blob> blobs,
                                               std::span<const tracking::Feature> features,
                                               std::span<const int> blob_of_feature) {
  last_frame_utime_ = utime;
  frame_.classified = false;
  frame_.map_reset = false;
  frame_.decisions.clear();
  frame_.plant_ids.assign(features.size(), -1);
  if (report.initialised_now) {
    // A new bed frame: what was mapped before cannot be placed in it.
    map_.Clear();
    registry_.Clear();
    frame_.map_reset = true;
    ++map_resets_;
  }
  if (tracker.mode() != tracking::TrackerMode::kTracking) return frame_;
  const geometry::GridState state = tracker.state();
  const std::vector<classify::PredictedCrop> crops = classify::PredictCrops(tracker.model(), state);
  classifier_.Classify(features, crops, tracker.covariance(), frame_.decisions);
  frame_.classified = true;
  const BedPose pose = BedPoseFromGrid(utime, state, tracker.forward_distance_m(), 0.0);
  // What the camera saw this frame (the image on the plane): soil there is soil.
  const double w = camera_.width(), h = camera_.height();
  if (const std::optional<Quad> view = FootprintOnPlane(camera_, {0.5 * w, 0.5 * h}, 0.0, 0.0, w, h, 1.0)) {
    Quad bed;
    for (size_t i = 0; i < 4; ++i) bed[i] = VehicleToBed(pose, (*view)[i]);
    map_.MarkObserved(bed);
  }
  struct PlantFootprint {
    int m, n;
    double area_px;
    Eigen::Vector2d moment_px;
    cv::Rect box;
  };
  std::vector<PlantFootprint> plants;
  for (size_t i = 0; i < features.size(); ++i) {
    const classify::BlobDecision& d = frame_.decisions[i];
    const vision::Blob& blob = blobs[static_cast<size_t>(blob_of_feature[i])];
    if (d.crop && d.associated && options_.crop_footprint_per_plant) {
      auto it = std::find_if(plants.begin(), plants.end(),
                             [&](const PlantFootprint& p) { return p.m == d.m && p.n == d.n; });
      if (it == plants.end()) {
        plants.push_back({d.m, d.n, 0.0, Eigen::Vector2d::Zero(), blob.bbox_px});
        it = plants.end() - 1;
      }
      it->area_px += blob.area_px;
      it->moment_px += blob.area_px * blob.centroid_px;
      it->box |= blob.bbox_px;
    } else if (options_.abstain_merged && !d.crop && !d.associated &&
               (d.clipped || d.area_m2 >= options_.classifier.min_crop_area_m2) &&
               CoversAPrediction(blob, crops)) {
      // Possibly merged plants: no votes either way.
    } else if (!d.crop || d.associated) {
      // Crop by size alone (merged plants): its centroid is no plant's
      // centre, so it marks no cells; the plants in it are mapped from other
      // frames.
      AddFootprint(pose, blob, d.crop);
    }
    frame_.plant_ids[i] = registry_.Observe(
        VehicleToBed(pose, features[i].ground_m), d, options_.classifier,
        d.associated ? std::optional<Eigen::Vector2d>(VehicleToBed(pose, d.predicted_ground_m))
                     : std::nullopt);
  }
  for (const PlantFootprint& p : plants) {
    if (p.area_px > 0.0) AddFootprint(pose, p.moment_px / p.area_px, p.box, true);
  }
  return frame_;
}

TickResult TreatmentSystem::OnPose(int64_t utime, const tracking::GridTracker& tracker,
                                   double speed_m_s, bool odometry_ok, bool camera_ok) {
  SafetyInputs safety;
  safety.pose_utime = tracker.utime();
  safety.last_frame_utime = last_frame_utime_;
  safety.camera_ok = camera_ok;
  safety.odometry_valid = odometry_ok;
  safety.tracking = tracker.mode() == tracking::TrackerMode::kTracking;
  const BedPose pose =
      BedPoseFromGrid(tracker.utime(), tracker.state(), tracker.forward_distance_m(), speed_m_s);
  return Tick(utime, pose, safety);
}

TickResult TreatmentSystem::Tick(int64_t utime, const BedPose& pose, const SafetyInputs& safety) {
  TickResult r = scheduler_.Tick(utime, pose, map_, safety);
  for (const NozzleTarget& t : r.opened) {
    registry_.MarkSprayed(t, &newly_sprayed_);
    map_.MarkTreated(t.x0, t.x1, t.y0, t.y1);
  }
  return r;
}

}  // namespace plantscale::treatment
