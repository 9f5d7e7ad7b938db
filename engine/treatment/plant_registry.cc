#include "engine/treatment/plant_registry.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ranges>
#include <string>

namespace plantscale::treatment {

OptionErrors RegistryOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "merge_radius_m", merge_radius_m, 0.001, 1.0);
  RequireInRange(e, "crop_size_sd_fraction", crop_size_sd_fraction, 0.0, 0.5);
  if (min_size_frames < 1) e.push_back({"min_size_frames", "must be >= 1"});
  return e;
}

PlantRegistry::PlantRegistry(const RegistryOptions& options) : options_(options) {
  ThrowIfInvalid("plant registry", options_.Validate());
}

int PlantRegistry::Observe(const Eigen::Vector2d& bed, const classify::BlobDecision& d,
                           const std::optional<Eigen::Vector2d>& predicted_bed) {
  PlantRecord* best = nullptr;
  const bool grid = d.associated && predicted_bed.has_value();
  if (grid) {
    double best_d = options_.merge_radius_m;
    for (PlantRecord& r : Recent() | std::views::reverse) {
      if (!r.grid_plant) continue;
      const double dist = (r.grid_bed_m - *predicted_bed).norm();
      if (dist <= best_d) {
        best_d = dist;
        best = &r;
      }
    }
  }
  if (!best) {
    double best_d = options_.merge_radius_m;
    for (PlantRecord& r : Recent() | std::views::reverse) {
      if (grid && r.grid_plant) continue;  // another grid plant's record
      const double dist = (r.bed_m - bed).norm();
      if (dist <= best_d) {
        best_d = dist;
        best = &r;
      }
    }
  }
  if (!best) {
    records_.emplace_back();
    best = &records_.back();
    best->id = first_id_ + static_cast<int>(records_.size()) - 1;
  }
  PlantRecord& r = *best;
  if (grid) {
    // The grid plant's predicted position, averaged like the centroid.
    const int n = r.grid_plant ? r.crop_votes : 0;
    r.grid_bed_m = r.grid_plant ? Eigen::Vector2d((r.grid_bed_m * n + *predicted_bed) / (n + 1))
                                : *predicted_bed;
    r.grid_plant = true;
  }
  if (r.observations == 0) r.size_filter_m2 = d.size_filter_m2;
  r.bed_m = (r.bed_m * r.observations + bed) / (r.observations + 1);
  ++r.observations;
  (d.crop ? r.crop_votes : r.weed_votes) += 1;
  if (d.learned_class >= 0) {
    r.learned_confidence = (r.learned_confidence * r.learned_observations + d.learned_confidence) /
                           (r.learned_observations + 1);
    ++r.learned_observations;
    if (d.learned) ++r.learned_decided;
  }
  if (!d.clipped && d.area_m2 > r.largest_m2) {
    r.largest_m2 = d.area_m2;
    if (r.sizes.empty()) r.area_m2 = d.area_m2;
    r.small = d.area_m2 < d.size_filter_m2;
    r.size_filter_m2 = d.size_filter_m2;
  }
  if (d.gamma2 < r.gamma2) {
    r.gamma2 = d.gamma2;
    r.distance_m = d.distance_m;
  }
  return r.id;
}

void PlantRegistry::MarkSprayed(const NozzleTarget& s, std::vector<int>* newly) {
  for (auto it = records_.rbegin(); it != records_.rend() && it - records_.rbegin() < 400; ++it) {
    const Eigen::Vector2d& p = it->bed_m;
    if (p.x() >= s.x0 && p.x() <= s.x1 && p.y() >= s.y0 - 0.01 && p.y() <= s.y1 + 0.01) {
      if (!it->sprayed && newly) newly->push_back(it->id);
      it->sprayed = true;
    }
  }
}

namespace {

// Why a record is what it is, in words (for its `why`).
const char* ReasonOf(const PlantRecord& r) {
  const bool by_model = 2 * r.learned_decided > r.observations;
  return by_model && r.crop() ? "the learned model's crop"
         : by_model           ? "the learned model's weed"
         : r.crop_at_end ? "in the last view when the run ended, as large as a crop at a predicted crop that had no record: that crop, not yet associated"
         : r.undersized ? "in a predicted crop's place, under the crops' size: a weed where a crop is missing"
         : r.crop() && r.small && r.grid_plant
             ? "below the size filter, alone in a predicted crop's region"
         : r.crop() && r.small ? "below the size filter, a leaf of a crop found beside it"
         : r.crop()          ? "associated with a predicted crop"
         : r.small           ? "below the size filter"
                             : "outside every crop association region";
}

}  // namespace

void PlantRegistry::Explain(const TreatmentMap& map, SprayMode mode,
                            const classify::ClassifierOptions& c) {
  for (PlantRecord& r : records_) {
    int column = 0, row = 0;
    if (!r.counts_final && map.CellOf(r.bed_m, column, row)) {
      r.counts = map.Counts(column, row);
      r.map_class = map.ClassOf(column, row);
    }
    char text[448];
    const char* reason = ReasonOf(r);
    std::string learned;
    if (r.learned_observations > 0) {
      char m[96];
      std::snprintf(m, sizeof m, "; learned model decided %d of %d, confidence %.2f",
                    r.learned_decided, r.learned_observations, r.learned_confidence);
      learned = m;
    }
    std::snprintf(text, sizeof text,
                  "%s (%d crop / %d weed votes): %s; area %.4f m2 (filter %.4f), "
                  "gamma2 %.2f (gate %.2f), %.0f mm from the predicted crop; cell counters "
                  "crop %d weed %d doubt %d -> %s; %s (spray-%s mode)%s",
                  r.crop() ? "crop" : "weed", r.crop_votes, r.weed_votes, reason, r.area_m2,
                  r.size_filter_m2, std::isfinite(r.gamma2) ? r.gamma2 : -1.0, c.assoc_chi2,
                  std::isfinite(r.distance_m) ? r.distance_m * 1000.0 : -1.0, r.counts.crop,
                  r.counts.weed, r.counts.doubt, ToString(r.map_class), r.sprayed ? "sprayed" : "not sprayed",
                  ToString(mode), learned.c_str());
    r.why = text;
  }
}

void PlantRegistry::TakeFinalCounts(const TreatmentMap& map, int before_row) {
  for (size_t i = final_from_; i < records_.size(); ++i) {
    PlantRecord& r = records_[i];
    // A record off the map's columns (beyond its width) is final once its
    // row is, with no counts: left waiting, it would hold every record after
    // it for the rest of the run.
    const double row_of_y =
        std::floor((r.bed_m.y() - map.options().start_y_m) / map.options().cell_m);
    if (r.counts_final || (std::isfinite(row_of_y) && row_of_y >= before_row)) continue;
    int column = 0, row = 0;
    if (map.CellOf(r.bed_m, column, row)) {
      r.counts = map.Counts(column, row);
      r.map_class = map.ClassOf(column, row);
    }
    r.counts_final = true;
  }
  while (final_from_ < records_.size() && records_[final_from_].counts_final) ++final_from_;
}

void PlantRegistry::Clear() {
  first_id_ += static_cast<int>(records_.size());
  cleared_id_ = first_id_;
  records_.clear();
  frame_sizes_.clear();
  crop_median_m2_ = 0.0;
  final_from_ = 0;
  let_go_confirmed_ = 0;
}

void PlantRegistry::LetGoFinal() {
  const auto n = static_cast<std::ptrdiff_t>(final_from_);
  for (auto it = records_.begin(); it != records_.begin() + n; ++it) let_go_confirmed_ += it->confirmed();
  records_.erase(records_.begin(), records_.begin() + n);
  first_id_ += static_cast<int>(n);
  final_from_ = 0;
}

const PlantRecord* PlantRegistry::Find(int id) const {
  if (id < first_id_ || id - first_id_ >= static_cast<int>(records_.size())) return nullptr;
  return &records_[static_cast<size_t>(id - first_id_)];
}

int PlantRegistry::confirmed() const {
  int n = let_go_confirmed_;
  for (const PlantRecord& r : records_) n += r.confirmed();
  return n;
}

// A record as large as a crop (not below the undersized line), seen in 3
// frames at least, held a weed and not a crop yet.
bool PlantRegistry::CropSizedWeed(const PlantRecord& r) const {
  const double limit = UndersizedLimitM2();
  const bool sized = r.sizes.size() >= static_cast<size_t>(options_.min_size_frames);
  return !r.crop() && !r.undersized && sized && r.observations >= 3 && limit > 0.0 && r.area_m2 >= limit;
}

std::vector<int> PlantRegistry::FlushInView(const Quad& view, std::span<const Eigen::Vector2d> predicted,
                                            double reach_m) {
  std::vector<PlantRecord*> in_view;
  for (PlantRecord& r : Recent()) {
    if (InsideQuad(view, r.bed_m)) in_view.push_back(&r);
  }
  std::vector<int> changed;
  for (PlantRecord* r : in_view) {
    const bool was = r->confirmed();
    r->judged_at_end = true;
    if (r->confirmed() != was) changed.push_back(r->id);
  }
  // Each predicted crop in view without a confirmed crop record within
  // reach takes the most seen crop-sized weed record within reach.
  const auto near = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& q) { return (p - q).norm() < reach_m; };
  for (const Eigen::Vector2d& p : predicted) {
    if (!InsideQuad(view, p)) continue;
    const bool has_crop = std::ranges::any_of(in_view, [&](const PlantRecord* r) {
      return r->confirmed() && r->crop() && near(r->grid_plant ? r->grid_bed_m : r->bed_m, p);
    });
    if (has_crop) continue;
    PlantRecord* best = nullptr;
    for (PlantRecord* r : in_view) {
      if (CropSizedWeed(*r) && near(r->bed_m, p) && (!best || r->observations > best->observations)) best = r;
    }
    if (!best) continue;
    best->crop_at_end = true;
    changed.push_back(best->id);
  }
  std::sort(changed.begin(), changed.end());
  changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
  return changed;
}

void PlantRegistry::CountView(const Quad& view) {
  for (PlantRecord& r : Recent()) {
    if (InsideQuad(view, r.bed_m)) ++r.frames_in_view;
  }
}

double UnstretchedArea(std::span<const SizeSample> samples, double* distance_m) {
  double area = 0.0;
  Eigen::Vector2d first = Eigen::Vector2d::Zero();
  Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
  for (const SizeSample& s : samples) {
    area += s.area_m2;
    first += s.area_m2 * s.ground_m;
    second += s.area_m2 * (s.covariance_m2 + s.ground_m * s.ground_m.transpose());
  }
  if (!(area > 0.0)) return 0.0;
  const Eigen::Vector2d centre = first / area;
  if (distance_m) *distance_m = centre.norm();
  const Eigen::Matrix2d cov = second / area - centre * centre.transpose();
  if (!(centre.norm() > 0.0)) return area;  // straight under the camera: no stretch
  const Eigen::Vector2d along = centre.normalized();
  const Eigen::Vector2d across(-along.y(), along.x());
  const double var_along = along.dot(cov * along), var_across = across.dot(cov * across);
  if (!(var_along > 0.0) || !(var_across >= 0.0)) return area;
  return area * std::min(1.0, std::sqrt(var_across / var_along));
}

double NearHalfMedian(std::span<const PlantRecord::FrameSize> sizes) {
  if (sizes.empty()) return 0.0;
  std::vector<PlantRecord::FrameSize> v(sizes.begin(), sizes.end());
  std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.distance_m < b.distance_m; });
  std::vector<float> near;
  for (size_t i = 0; i < (v.size() + 1) / 2; ++i) near.push_back(v[i].area_m2);
  std::nth_element(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(near.size() / 2), near.end());
  return near[near.size() / 2];
}

PlantRecord* PlantRegistry::Mutable(int id) {
  if (id < first_id_ || id - first_id_ >= static_cast<int>(records_.size())) return nullptr;
  return &records_[static_cast<size_t>(id - first_id_)];
}

void PlantRegistry::AddSize(int id, const SizeSample& sample) { frame_sizes_.emplace_back(id, sample); }

void PlantRegistry::EndFrame() {
  std::stable_sort(frame_sizes_.begin(), frame_sizes_.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<SizeSample> blobs;
  for (size_t i = 0; i < frame_sizes_.size();) {
    const int id = frame_sizes_[i].first;
    bool clipped = false;
    blobs.clear();
    for (; i < frame_sizes_.size() && frame_sizes_[i].first == id; ++i) {
      clipped = clipped || frame_sizes_[i].second.clipped;
      blobs.push_back(frame_sizes_[i].second);
    }
    PlantRecord* r = Mutable(id);
    if (r == nullptr || clipped) continue;
    double distance = 0.0;
    const double area = UnstretchedArea(blobs, &distance);
    if (!(area > 0.0)) continue;  // all of it grown rim: nothing measured
    r->sizes.push_back({static_cast<float>(distance), static_cast<float>(area)});
    r->area_m2 = NearHalfMedian(r->sizes);
  }
  frame_sizes_.clear();
  UpdateUndersized();
}

// 3σ of the crops' radius below their median, as an area: (1 − 3s)² of the
// median (s = crop_size_sd_fraction).
double PlantRegistry::UndersizedLimitM2() const {
  const double radius_fraction = std::max(0.0, 1.0 - 3.0 * options_.crop_size_sd_fraction);
  return radius_fraction * radius_fraction * crop_median_m2_;
}

// The crops' median size over the records that can still be in view, and
// which records in a crop's place fall far below it.
void PlantRegistry::UpdateUndersized() {
  const double s = options_.crop_size_sd_fraction;
  if (!(s > 0.0)) return;
  const size_t min_frames = static_cast<size_t>(options_.min_size_frames);
  const auto voted_crop = [](const PlantRecord& r) { return r.crop_votes >= r.weed_votes && r.crop_votes > 0; };
  std::vector<double> sizes;
  for (const PlantRecord& r : Recent()) {
    if (voted_crop(r) && r.sizes.size() >= min_frames) sizes.push_back(r.area_m2);
  }
  constexpr size_t kMinCrops = 10;
  if (sizes.size() >= kMinCrops) {
    std::nth_element(sizes.begin(), sizes.begin() + static_cast<std::ptrdiff_t>(sizes.size() / 2), sizes.end());
    crop_median_m2_ = sizes[sizes.size() / 2];
  }
  if (!(crop_median_m2_ > 0.0)) return;
  const double limit = UndersizedLimitM2();
  for (PlantRecord& r : Recent()) {
    if (r.sizes.size() >= min_frames) r.undersized = voted_crop(r) && r.area_m2 < limit;
  }
}

}  // namespace plantscale::treatment
