#pragma once
// Per-plant record (issue 6): every classified blob is merged, in the bed
// frame, into the nearest plant record within `merge_radius_m` (or starts a
// new one). A blob associated with a predicted crop joins the record of that
// grid plant (its predicted bed position within `merge_radius_m`) wherever
// its centroid lies, so the leaf fragments of one crop plant, whose
// centroids scatter over its canopy, make one record. Each plant carries its votes, size, distance to the predicted
// crop position, the map counters under it and whether a nozzle sprayed it —
// and a sentence saying why, for the map and the station.
//
// A record's size (area_m2) is robust to the view: each frame that saw the
// plant whole (no blob of it cut by the image border) measures the area of
// all its blobs of that frame together, so a crop split into leaves counts
// whole, each crop blob read on its core (the mask before the segmenter's
// hull and soil growth, vision::Blob::core_area_px: growth adds a one-pixel
// ring of soil that the smoothing lit and the shaded flank under the leaf
// tips, neither in the leaf-tip outline) and each weed blob whole (a weed a
// few pixels across keeps about a third of its area in the core of the
// smoothed image's threshold; the growth gives it back), and takes out the stretch of the
// oblique view: the camera looks down at about 45°, so the plant's height
// (the flank under its near leaf tips) lengthens its outline on the ground
// along the line of sight while its extent across that line is kept; the
// area is scaled by the ratio of the two spreads (second moments), which
// a plant of symmetric outline has equal. The size is the median of those
// per-frame areas over the nearer half of the frames (the plant closest to
// the camera, seen most steeply, where what the stretch leaves is least),
// not the largest (which picked the most stretched view and a neighbour
// touching for a frame). A record standing in a predicted crop's place but
// much smaller than the crops around it (below (1 − 3 s)² of their median size, s the
// crop profile's spread of the leaf-tip radius) is a weed where a crop is
// missing, not that crop: it is `undersized` and not a crop().
//
// When the run ends, the records still in the last view have not finished
// their passage under the camera: a plant line far in the view has been
// seen only far away, where blobs are small, often cut into leaves and
// often not associated with their predicted crop, so its crops hold too few
// sightings to be confirmed or are held weeds. FlushInView judges them on
// the frames they had (`judged_at_end`): a crop record seen in at least 3
// frames is confirmed, and a predicted crop of the last frame with no
// confirmed crop record near takes the most seen record near it that is as
// large as a crop (not below the `undersized` line; seen in 3 frames or
// more) as that crop, seen where the grid had not yet associated it
// (`crop_at_end`). Without this the stand of the run ends in a false gap
// at the last lines in view.

#include <Eigen/Core>
#include <limits>
#include <algorithm>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "engine/classify/crop_classifier.h"
#include "engine/treatment/nozzle_scheduler.h"
#include "engine/treatment/treatment_map.h"

namespace plantscale::treatment {

struct PlantRecord {
  int id = 0;
  Eigen::Vector2d bed_m{0.0, 0.0};  // mean of its observations
  int observations = 0;
  int frames_in_view = 0;  // frames whose view held its position (seen or not)
  int crop_votes = 0;
  int weed_votes = 0;
  double area_m2 = 0.0;  // median per-frame size (above); the largest blob until measured
  double largest_m2 = 0.0;  // largest unclipped blob seen (the size filter's test)
  struct FrameSize {
    float distance_m;  // from the camera's ground point
    float area_m2;
  };
  std::vector<FrameSize> sizes;  // per-frame sizes, oldest first
  bool undersized = false;  // in a crop's place, far smaller than the crops (above)
  bool judged_at_end = false;  // in the last view of the run (FlushInView)
  bool crop_at_end = false;    // ... and judged the crop the grid had not associated
  double gamma2 = std::numeric_limits<double>::infinity();  // smallest to a predicted crop
  double distance_m = std::numeric_limits<double>::infinity();
  bool small = false;  // its largest unclipped view failed the size filter
  double size_filter_m2 = 0.0;  // ... the filter that view was held to
  CellCounts counts;   // map counters under its position at the last update
  CellClass map_class = CellClass::kSoil;
  bool counts_final = false;  // read as the map let its row go (TakeFinalCounts)
  bool sprayed = false;
  bool grid_plant = false;  // associated with a predicted crop at grid_bed_m
  // The learned model (BlobDecision::learned_class): in how many of the
  // observations its class decided, and the mean of its confidence over
  // the observations it classified (0 when it classified none).
  int learned_decided = 0;
  int learned_observations = 0;
  double learned_confidence = 0.0;
  Eigen::Vector2d grid_bed_m{0.0, 0.0};
  std::string why;

  bool crop() const { return crop_at_end || (crop_votes >= weed_votes && crop_votes > 0 && !undersized); }
  // A plant rather than a passing detection (a speck, a stone's glint, a leaf
  // cut off for a frame or two): seen in at least 3 frames and in at least
  // 40 % of the (8 or more) frames that looked at its place: crops are seen
  // in nearly every frame that looks at them, passing detections in few. A
  // crop judged at the run's end (FlushInView) needs the 3 frames only.
  bool confirmed() const {
    const bool seen = observations >= 3;
    if (judged_at_end && crop() && seen) return true;
    return seen && frames_in_view >= 8 && observations >= 0.4 * frames_in_view;
  }
};

struct RegistryOptions {
  double merge_radius_m = 0.05;
  // The crop profile's plant-to-plant spread of the leaf-tip radius (sd /
  // mean); 0: no record is held undersized.
  double crop_size_sd_fraction = 0.0;
  // Per-frame sizes a crop record needs before its size counts towards the
  // crops' median (and before it can be held undersized).
  int min_size_frames = 3;

  OptionErrors Validate() const;
};

// One blob's share of its record's size this frame: its ground area, its
// centroid and the covariance of its pixels on the ground, in a frame whose
// origin is under the camera (the vehicle frame), and whether the image
// border cut it.
struct SizeSample {
  double area_m2 = 0.0;
  Eigen::Vector2d ground_m{0.0, 0.0};
  Eigen::Matrix2d covariance_m2 = Eigen::Matrix2d::Zero();
  bool clipped = false;
};

// The area of a plant seen as `samples` (its blobs of one frame), its
// stretch along the line of sight from the camera taken out (above):
// the blobs' joint area times sd across / sd along that line, at most 1.
// `distance_m`, when given, is set to the blobs' joint centroid's distance
// from the camera's ground point.
double UnstretchedArea(std::span<const SizeSample> samples, double* distance_m = nullptr);
// The median area of the nearer half of `sizes` (above).
double NearHalfMedian(std::span<const PlantRecord::FrameSize> sizes);

class PlantRegistry {
 public:
  explicit PlantRegistry(const RegistryOptions& options = {});

  // One classified blob at `bed_m`; `predicted_bed_m`, when the blob is
  // associated, is its predicted crop's bed position. Returns the record's id.
  int Observe(const Eigen::Vector2d& bed_m, const classify::BlobDecision& decision,
              const std::optional<Eigen::Vector2d>& predicted_bed_m = std::nullopt);
  // A nozzle covered this bed strip: records inside it are sprayed. Appends
  // the ids of records that were not sprayed before to `newly` when given.
  void MarkSprayed(const NozzleTarget& strip, std::vector<int>* newly = nullptr);
  // Reads the map under every record (but those whose counts are final) and
  // writes its `why`.
  void Explain(const TreatmentMap& map, SprayMode mode, const classify::ClassifierOptions& c);
  // The map is about to let the rows before `row` go: the records standing
  // there read their counters now, for good.
  void TakeFinalCounts(const TreatmentMap& map, int row);
  // A frame looked at this part of the bed: the records inside it were in view.
  void CountView(const Quad& view);
  // A blob of record `id` this frame, for its size (EndFrame measures it).
  void AddSize(int id, const SizeSample& sample);
  // The frame's blobs are all in: each record seen whole adds its size of
  // this frame, and the crops' median size and who is undersized follow.
  void EndFrame();
  // The run ended with `view` the last frame's view (on the bed) and
  // `predicted` its predicted crops (bed positions): the records inside the
  // view are judged on the frames they had (above); a record is "at" a
  // predicted crop within `reach_m`. Returns the ids of the records whose
  // kind or confirmation changed (to publish them again).
  std::vector<int> FlushInView(const Quad& view, std::span<const Eigen::Vector2d> predicted, double reach_m);
  // The median size of the crop records measured (0: none yet).
  double crop_median_m2() const { return crop_median_m2_; }
  // Lets go of the oldest records whose counts are final (TakeFinalCounts):
  // their place is behind the bar, they were published as they changed, and
  // a day's run would hold hundreds of thousands of them.
  void LetGoFinal();
  // Forgets every record (a new bed frame); ids stay unique over the run.
  void Clear();

  // The records held, oldest first: ids first_id() on.
  const std::vector<PlantRecord>& records() const { return records_; }
  // Record `id`; null when let go (or never made).
  const PlantRecord* Find(int id) const;
  int first_id() const { return first_id_; }
  // Records made since the last Clear, held or let go, and of those the
  // confirmed ones (PlantRecord::confirmed).
  int64_t recorded() const { return first_id_ - cleared_id_ + static_cast<int64_t>(records_.size()); }
  int confirmed() const;

 private:
  // Records are appended as plants come into view: the newest kLookBack are
  // the ones that can still be in view (newest first when reversed).
  static constexpr size_t kLookBack = 400;
  size_t final_from_ = 0;  // records before it all have final counts
  int first_id_ = 0;       // id of records_[0]
  int cleared_id_ = 0;     // first id after the last Clear
  int let_go_confirmed_ = 0;
  std::span<PlantRecord> Recent() {
    const size_t n = std::min(records_.size(), kLookBack);
    return {records_.data() + records_.size() - n, n};
  }

  PlantRecord* Mutable(int id);
  void UpdateUndersized();
  double UndersizedLimitM2() const;  // the area below which a crop-place record is undersized
  bool CropSizedWeed(const PlantRecord& r) const;

  RegistryOptions options_;
  std::vector<std::pair<int, SizeSample>> frame_sizes_;  // this frame's, by record id
  double crop_median_m2_ = 0.0;
  std::vector<PlantRecord> records_;  // bed y increasing, within a merge radius
};

}  // namespace plantscale::treatment
