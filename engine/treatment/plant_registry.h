#pragma once
// Per-plant record (issue 6): every classified blob is merged, in the bed
// frame, into the nearest plant record within `merge_radius_m` (or starts a
// new one). A blob associated with a predicted crop joins the record of that
// grid plant (its predicted bed position within `merge_radius_m`) wherever
// its centroid lies, so the leaf fragments of one crop plant, whose
// centroids scatter over its canopy, make one record. Each plant carries its votes, size, distance to the predicted
// crop position, the map counters under it and whether a nozzle sprayed it —
// and a sentence saying why, for the map and the station.

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
  double area_m2 = 0.0;  // largest seen
  double gamma2 = std::numeric_limits<double>::infinity();  // smallest to a predicted crop
  double distance_m = std::numeric_limits<double>::infinity();
  bool small = false;  // its largest unclipped view failed the size filter
  double size_filter_m2 = 0.0;  // ... the filter that view was held to
  CellCounts counts;   // map counters under its position at the last update
  CellClass map_class = CellClass::kSoil;
  bool counts_final = false;  // read as the map let its row go (TakeFinalCounts)
  bool sprayed = false;
  bool grid_plant = false;  // associated with a predicted crop at grid_bed_m
  Eigen::Vector2d grid_bed_m{0.0, 0.0};
  std::string why;

  bool crop() const { return crop_votes >= weed_votes && crop_votes > 0; }
  // A plant rather than a passing detection (a speck, a stone's glint, a leaf
  // cut off for a frame or two): seen in at least 3 frames and in at least
  // 40 % of the (8 or more) frames that looked at its place: crops are seen
  // in nearly every frame that looks at them, passing detections in few.
  bool confirmed() const {
    return observations >= 3 && frames_in_view >= 8 && observations >= 0.4 * frames_in_view;
  }
};

struct RegistryOptions {
  double merge_radius_m = 0.05;

  OptionErrors Validate() const;
};

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

  RegistryOptions options_;
  std::vector<PlantRecord> records_;  // bed y increasing, within a merge radius
};

}  // namespace plantscale::treatment
