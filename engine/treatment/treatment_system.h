#pragma once
// The treatment chain of one vehicle (docs/design.md §1): classify each frame's
// blobs against the tracker's predicted crop grid, accumulate their
// footprints in the treatment map and the plant registry, and from every
// 50 Hz pose schedule the nozzles at 200 Hz (with the fail-safe). Composed
// with segmentation and the tracker by the vehicle pipeline
// (engine/pipeline), which every user runs.

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "engine/classify/crop_classifier.h"
#include "engine/geometry/camera_model.h"
#include "engine/tracking/grid_tracker.h"
#include "engine/treatment/bar_uncertainty.h"
#include "engine/treatment/nozzle_scheduler.h"
#include "engine/treatment/plant_registry.h"
#include "engine/treatment/treatment_map.h"
#include "engine/vision/blobs.h"
#include "engine/vision/segmenter.h"

namespace plantscale::treatment {

struct TreatmentOptions {
  classify::ClassifierOptions classifier;
  TreatmentMapOptions map;
  SchedulerOptions scheduler;
  RegistryOptions registry;
  // Crop blobs mark the map only when associated with a predicted crop. A
  // crop footprint is its blob's bounding box scaled about the centroid by
  // this (1: the thesis's whole box); weeds always use the whole box. The
  // spray must cover the root despite the placement error: on a crop some
  // 0.28 m across, 0.30 reaches about 3σ of the placement each side of the
  // plant (docs/results/2026-11-27-option-choices.md).
  double crop_footprint_scale = 0.30;
  // Scaled footprints of small crops are stretched to at least this half
  // size along and across (vehicle frame): 0.30 of a 3-week crop's box is
  // under 2σ of the placement, and the crops missed on the small-crop
  // presets were missed by a few millimetres.
  double crop_footprint_min_half_m = 0.025;
  double weed_footprint_scale = 1.0;
  // Weeds are low, so a weed blob's record and footprint are located at
  // this height rather than on the crop's plane: on the 0.1 m plane a weed
  // 3 m ahead of a camera at 1.5 m lands 20 cm beyond where it is, and
  // slides towards the camera as it nears, leaving a trail of records.
  double weed_height_m = 0.005;
  // A crop's size (PlantRegistry) is its outline at the leaf tips, which
  // stand at this height: its blobs' areas, measured on the crops' virtual
  // plane, are taken to this plane. 0: left on the virtual plane. A weed's
  // is taken to weed_height_m.
  double outline_height_m = 0.0;
  // Crop blobs of one frame associated with the same predicted plant are
  // its leaves, cut apart by segmentation: they mark one footprint, their
  // joint bounding box scaled about their joint (area-weighted) centroid,
  // so the footprint is centred on the plant's canopy rather than on each
  // leaf. Off: every blob its own footprint (as before).
  bool crop_footprint_per_plant = true;
  // That footprint is centred where the tracker holds the plant (its grid
  // position plus its own offset, learnt from every frame that saw it)
  // rather than on this frame's centroid, whose place moves with the view
  // (the plant's own centroid height, leaves lost or gained by
  // segmentation): each frame votes the same cells. Needs
  // crop_footprint_per_plant.
  bool crop_footprint_at_tracked_plant = true;
  // And the footprints a plant marked in earlier frames follow it along the
  // row: each frame, all of them are taken out of the map and put back
  // where the tracker now holds the plant along, so its cells stand at its
  // latest (nearest) estimate instead of being smeared over the estimates
  // of every frame, the far ones carrying the parallax of the plant's own
  // height. Across, where that error is wander about the plant, each
  // footprint stays where its frame put it: their spread averages it.
  // Beyond the view's border the tracker drops the plant's own offset, so
  // footprints of those frames join the others where they stand.
  // Needs crop_footprint_at_tracked_plant.
  bool crop_footprint_follows_plant = true;
  // The spray is aimed at the root, which the camera does not see: what the
  // tracker holds as a plant's own offset from its grid node is where its
  // canopy is located, which adds to the root's planting error the lean of
  // the canopy and, along the rows, a bias of the located centroid that
  // stays with the plant (its height's parallax, leaves hidden behind the
  // rim, neighbours touching it). The grid node shares none of these, so
  // the footprint stands at the node plus this fraction of the plant's own
  // offset (across, along the rows), the weight of the root's own scatter
  // in the offset. Across, where the located centroid is better, the whole
  // offset. Needs crop_footprint_at_tracked_plant.
  double own_offset_fraction_across = 1.0;
  double own_offset_fraction_along = 0.7;
  // A blob that passed the size filter but missed every association region
  // while its bounding box covers a predicted crop position may be touching
  // plants merged (its centroid between them): it casts no weed votes, which
  // would otherwise outvote the crop cells those plants marked in other
  // frames. Off by default: it hits the last crops at the cost of more than
  // twice the treated area and the weeds under it.
  bool abstain_merged = false;
  // A blob that passed the size filter but missed every association region
  // may be touching plants merged, its centroid between them (thesis fig.
  // 2.17): when OnFrame has the mask, its pixels are split among the
  // predicted crops (CropClassifier::SplitMerged) and each crop part marks
  // its plant's footprint; what votes weed is merged_weed_parts_only's.
  bool split_merged = true;
  // A blob cut by the image border whose box covers a predicted crop is most
  // likely that crop entering or leaving the view: its centroid is biased
  // inward, it misses the association region, and its whole box voted weed
  // for the 5–10 frames it took to cross the border, so every crop stood in
  // a band of weed cells. Off: it casts no weed votes. On suits touching
  // plants, where those votes hold merged plants' crop cells in check.
  bool clipped_on_crop_votes_weed = false;
  // A merged blob split among the predicted crops (split_merged) votes
  // weed only with its plant matter beyond every prediction's split radius,
  // each 8-connected part of it (of at least min_weed_part_m2 on the
  // ground) its own bounding box at the weeds' height; its whole box, on
  // the crops' plane, casts a doubt vote (CellCounts::doubt), which a crop
  // cell must outvote as it does the weed counter but which makes no weed
  // cell. Off: the whole box votes weed on the weeds' plane (as the thesis's
  // unassociated blobs). That box, as wide as two crops and projected on
  // the weeds' low plane (far beyond the crops when they are far ahead),
  // left blocks of weed cells beside the crops on the map.
  bool merged_weed_parts_only = true;
  double min_weed_part_m2 = 0.0003;  // a disk of 10 mm radius: the field's smallest weeds
  // Weeds merged with a crop's blob (ClassifierOptions::outline_limit_sd):
  // each 8-connected part (of at least min_weed_part_m2) of an associated,
  // uncut crop blob's plant matter beyond its outline is a weed of its own
  // in the plant registry, at its centroid on the weeds' plane; with
  // outline_weed_votes it also votes weed on the map with its bounding box
  // there. Off: in weed mode those boxes, against the crops' leaves, are
  // sprayed (the field's treated area doubles, the crops' edges hit); in
  // crop mode they change next to nothing
  // (docs/results/2026-11-27-report.md, session 27).
  bool outline_weed_votes = false;
  // Fail-safe on uncertainty (bar_uncertainty.h): the bar closes while the
  // 95 % ellipse of where the plants at the bar stand, as the grid is held
  // now and dead-reckoned until the spray lands, reaches further from them
  // than the sprayed footprint does, across or along the rows
  // (kPositionUncertain). The margins (0: derived, UncertaintyMargin) set
  // scheduler.fail_safe.max_reach_*. On by default: in normal tracking it
  // stays open, and a coasting tracker closes the bar (docs/fail-safe.md).
  bool close_on_uncertainty = true;
  double uncertainty_margin_across_m = 0.0;
  double uncertainty_margin_along_m = 0.0;
  // (across, along): the margins as set, or derived from the footprint a
  // crop's root is sprayed with: its box scaled by crop_footprint_scale,
  // for a crop of `crop_radius_m` (TrackerOptions::crop_radius_m; 0:
  // unknown) some crop_footprint_scale × crop_radius_m each way, and at
  // least crop_footprint_min_half_m; across, the nozzles whose strips touch
  // it spray on past its edge, by half a nozzle's width on average (a
  // 0.14 m crop: 42 mm along, 53 mm across). Infinite when
  // close_on_uncertainty is off. The vehicle pipeline sets the margins so.
  Eigen::Vector2d UncertaintyMargin(double crop_radius_m = 0.0) const;

  OptionErrors Validate() const;
};

// A blob split among the predicted crops: its pixels and their labels.
struct SplitBlob {
  int feature = 0;                 // index into the frame's features
  std::vector<cv::Point> pixels;   // image pixels of the blob (those on the plane)
  std::vector<uint8_t> crop;       // per pixel: 1 crop, 0 weed
};

struct FrameTreatment {
  bool classified = false;  // the grid was tracked, so blobs were classified
  bool map_reset = false;   // the tracker (re)initialised: a new bed frame
  std::vector<classify::BlobDecision> decisions;  // per feature
  std::vector<int> plant_ids;                     // per feature, −1 when not mapped
  std::vector<SplitBlob> split;                   // blobs split (TreatmentOptions::split_merged)
};

// The bed pose at `utime` from the tracker's latest state, dead-reckoned
// from the tracker's time at its ground speed (the wheels past the slip
// guard, times the learnt scale); speed 0 when the odometry is not known.
BedPose TrackerPose(const tracking::GridTracker& tracker, int64_t utime, bool speed_known);

// The segmentation a spray mode wants, from `base`: in spray-weed mode soil
// growth (vision/soil_growth.h) joins no blobs, since a weed against a
// crop's rim would join the crop's blob and be spared with it; spray-crop
// mode keeps the joins, which reunite plants that shade split.
vision::SegmenterOptions SegmenterOptionsFor(SprayMode mode, vision::SegmenterOptions base = {});


class TreatmentSystem {
 public:
  // Throws InvalidOptionsError.
  TreatmentSystem(const geometry::CameraModel& camera, const TreatmentOptions& options,
                  NozzleSink sink = {});

  // A camera frame: `features[i]` came from `blobs[blob_of_feature[i]]`
  // (FeaturesFromBlobs drops blobs whose ray misses the plane). `mask` is
  // the plant mask the blobs were extracted from (CV_8UC1); empty: merged
  // blobs are not split.
  const FrameTreatment& OnFrame(int64_t utime, const tracking::GridTracker& tracker,
                                const tracking::FrameReport& report,
                                std::span<const vision::Blob> blobs,
                                std::span<const tracking::Feature> features,
                                std::span<const int> blob_of_feature,
                                const cv::Mat& mask = cv::Mat());
  // A pose (after the tracker took the odometry sample at utime): the
  // scheduler's ticks until the next pose (SchedulerOptions::TicksPerPose,
  // at utime, utime + tick_s, ...), each led from this pose.
  std::span<const TickResult> OnPose(int64_t utime, const tracking::GridTracker& tracker,
                                     bool odometry_ok, bool camera_ok = true);
  // The same with the pose and health given (a runner that ticks after the
  // tracker has moved on dead-reckons the pose back to the tick). `count`
  // ticks when positive (a pose that comes less often than the odometry's,
  // such as a camera frame's standing in for silent wheels, ticks until the
  // next one is due), else TicksPerPose.
  std::span<const TickResult> TicksFrom(int64_t utime, const BedPose& pose,
                                        const SafetyInputs& safety, int count = 0);
  // One tick.
  TickResult Tick(int64_t utime, const BedPose& pose, const SafetyInputs& safety);
  int64_t last_frame_utime() const { return last_frame_utime_; }
  // Vehicle y of the view's near edge on the ground: the plants leaving the
  // view there are mapped for the last time, and the bar reaches them after
  // the vehicle drives on by this plus the bar's offset.
  double view_near_y_m() const { return view_near_y_m_; }
  // The fail-safe's uncertainty at the bar now (bar_uncertainty.h).
  PlantReach ReachAtBar(const tracking::GridTracker& tracker) const;
  // The bed behind `bed_y_m` is final (the bar has passed it): the map lets
  // its rows go, in steps of 256 rows (3.4 m), once the records standing
  // there have read their counters, and the registry lets those records go.
  void ForgetBehind(double bed_y_m);
  // Writes every plant record's `why`.
  void Explain() { registry_.Explain(map_, options_.scheduler.mode, options_.classifier); }

  const TreatmentMap& map() const { return map_; }
  const PlantRegistry& registry() const { return registry_; }
  // The run ended: the records in the last frame's view are judged on the
  // frames they had (PlantRegistry::FlushInView, against that frame's
  // predicted crops, a record within half the grid's plant spacing of one
  // at it). Returns the ids whose kind or confirmation changed.
  std::vector<int> FlushRecordsInView();
  // Ids of the records sprayed since the last call (for publishing them again).
  std::vector<int> TakeNewlySprayed() { return std::exchange(newly_sprayed_, {}); }
  const TreatmentOptions& options() const { return options_; }
  const classify::CropClassifier& classifier() const { return classifier_; }
  void set_sink(NozzleSink sink) { scheduler_.set_sink(std::move(sink)); }
  // Spray the crop or the weeds from the next tick on (a station command).
  void set_mode(SprayMode mode) {
    scheduler_.set_mode(mode);
    options_.scheduler.mode = mode;
  }
  int map_resets() const { return map_resets_; }

 private:
  // OnFrame's steps. A crop plant's pixels of this frame (image), gathered
  // from its blobs and split parts.
  struct PlantFootprint {
    int m, n;
    double area_px;
    Eigen::Vector2d moment_px;
    cv::Rect box;
  };
  void StartFrame(int64_t utime, const tracking::GridTracker& tracker,
                  const tracking::FrameReport& report, size_t features);
  SizeSample SizeSampleOf(const vision::Blob& blob, const classify::BlobDecision& d) const;
  static void AddToPlant(std::vector<PlantFootprint>& plants, int m, int n, double area_px,
                         const Eigen::Vector2d& moment_px, const cv::Rect& box);
  void MapBlob(int feature, const vision::Blob& blob, const classify::BlobDecision& d,
               const std::vector<classify::PredictedCrop>& crops,
               const tracking::GridTracker& tracker, const cv::Mat& mask, const BedPose& pose,
               std::vector<PlantFootprint>& plants);
  void MapSplitParts(const vision::Blob& blob, const classify::BlobDecision& d,
                     const std::vector<classify::PredictedCrop>& crops, const BedPose& pose,
                     std::vector<PlantFootprint>& plants);
  void PlacePlantFootprints(const std::vector<PlantFootprint>& plants,
                            const tracking::GridTracker& tracker, const BedPose& pose);
  void AddFootprint(const BedPose& pose, const vision::Blob& blob, bool crop);
  // False for a clipped blob covering a predicted crop (clipped_on_crop_votes_weed).
  bool VotesWeed(const classify::BlobDecision& d, const vision::Blob& b,
                 std::span<const classify::PredictedCrop> crops) const;
  // The blob's whole bounding box on the crops' plane (vehicle frame).
  std::optional<Quad> BoxOnCropPlane(const vision::Blob& blob) const;
  // Does the blob's bounding box, projected, hold a predicted crop position?
  bool CoversAPrediction(const vision::Blob& blob,
                         std::span<const classify::PredictedCrop> crops) const;
  // centre_m: where to centre the footprint (vehicle frame), when not on
  // the centroid's own ray.
  void AddFootprint(const BedPose& pose, const Eigen::Vector2d& centroid_px, const cv::Rect& bbox,
                    bool crop, std::optional<Eigen::Vector2d> centre_m = std::nullopt);
  // The footprint AddFootprint marks (bed frame), nullopt when off the plane.
  std::optional<Quad> BedFootprint(const BedPose& pose, const Eigen::Vector2d& centroid_px,
                                   const cv::Rect& bbox, bool crop,
                                   std::optional<Eigen::Vector2d> centre_m) const;
  // Plant `key`'s footprint this frame, `bed_quad`, centred along the bed at
  // `along_bed_m`. When `moves`, its earlier ones move along there with it;
  // else this one joins them where they stand (crop_footprint_follows_plant).
  void PlaceFollowing(std::pair<int, int> key, const Quad& bed_quad, double along_bed_m,
                      bool moves);
  // The blob's pixels in `mask` (its 8-connected component inside its box).
  // False when the component is not found.
  bool BlobPixels(const cv::Mat& mask, const vision::Blob& blob, std::vector<cv::Point>& out);
  // Splits feature `feature`'s blob among the predictions: appends its
  // SplitBlob to the frame and leaves each pixel's part in split_part_ and
  // each part's class in split_part_crop_. False when it has no pixels.
  bool SplitMergedBlob(int feature, const vision::Blob& blob, const classify::BlobDecision& d,
                       std::span<const classify::PredictedCrop> crops,
                       const geometry::Matrix5d& covariance, const cv::Mat& mask);

  // A doubt vote over the blob's whole box on the crops' plane.
  void AddDoubt(const BedPose& pose, const vision::Blob& blob);
  // Votes weed with each 8-connected part of the pixels flagged in `weed`
  // (each standing for pixel_area_m2 of ground) of at least
  // min_weed_part_m2: its own bounding box about its centroid.
  void VoteWeedParts(const BedPose& pose, std::span<const cv::Point> pixels,
                     std::span<const uint8_t> weed, double pixel_area_m2);
  // The 8-connected parts of the pixels flagged in `weed` of at least
  // min_weed_part_m2 (each pixel standing for pixel_area_m2), as blobs
  // (area, centroid, second moments, box; not projected).
  std::vector<vision::Blob> WeedParts(std::span<const cv::Point> pixels, std::span<const uint8_t> weed,
                                      double pixel_area_m2);
  // Weeds merged with crop blob `blob` (outline_limit_sd): each part beyond
  // its outline is observed as a weed; returns how many.
  int ObserveWeedsBeyondOutline(const vision::Blob& blob, const classify::BlobDecision& d,
                                const cv::Mat& mask, const BedPose& pose);

  // Where a crop blob centred at centroid_px stands: the tracker's centroid
  // height there (TrackerOptions::crop_radius_m), else the virtual plane,
  // so that crop footprints and the tracker's predictions agree in scale.
  double CropPlaneHeight(const Eigen::Vector2d& centroid_px) const;

  geometry::CameraModel camera_;
  const geometry::CentroidHeights* heights_ = nullptr;  // the tracker's, set each frame
  std::vector<int> newly_sprayed_;
  std::vector<TickResult> pose_ticks_;  // OnPose's
  TreatmentOptions options_;
  classify::CropClassifier classifier_;
  TreatmentMap map_;
  NozzleScheduler scheduler_;
  PlantRegistry registry_;
  FrameTreatment frame_;
  // Scratch of BlobPixels, SplitMergedBlob and VoteWeedParts.
  cv::Mat components_, stats_, centroids_, parts_;
  std::vector<cv::Point> split_pixels_;
  std::vector<Eigen::Vector2d> split_ground_;
  std::vector<double> split_area_;
  std::vector<int> split_part_;
  std::vector<uint8_t> split_part_crop_;
  std::vector<uint8_t> beyond_;  // per split pixel: beyond every prediction's radius
  std::vector<cv::Point> outline_pixels_;  // ObserveWeedsBeyondOutline's pixels on the crop plane
  int64_t last_frame_utime_ = -1;
  std::optional<Quad> last_view_;  // the last classified frame's view, on the bed
  std::vector<Eigen::Vector2d> last_predicted_bed_;  // ... and its predicted crops
  double last_plant_spacing_m_ = 0.0;
  int map_resets_ = 0;
  // Crop plants whose footprints follow them, by (line counted from the
  // tracker's initialisation, row): their footprints' column spans with the
  // plant's bed y taken off, that bed y now, and the frame that last saw them.
  struct FollowedPlant {
    std::vector<ColumnSpan> spans;
    double along_bed_m = 0.0;
    int64_t last_frame = 0;
  };
  std::map<std::pair<int, int>, FollowedPlant> followed_;
  int64_t frames_ = 0;
  double view_near_y_m_ = 0.0;
};

// Indices of the blobs FeaturesFromBlobs keeps, in its order.
void FeatureBlobIndices(std::span<const vision::Blob> blobs, std::vector<int>& out);

}  // namespace plantscale::treatment
