#include "engine/tracking/loss_policy.h"

#include <algorithm>
#include <cmath>

#include "engine/geometry/grid_model.h"
#include "engine/tracking/grid_tracker_internal.h"

namespace plantscale::tracking {

LossPolicy::LossPolicy(const TrackerOptions& options)
    : lost_offset_sd_m_(options.lost_offset_sd_m), max_coast_s_(options.max_coast_s) {}

void LossPolicy::Reset(double forward_m) {
  lines_passed_ = 0;
  passed_m_ = 0.0;
  initial_forward_m_ = forward_m;
  dr_since_loss_m_ = 0.0;
  distance_at_loss_m_ = 0.0;
  was_lost_ = false;
}

std::string LossPolicy::Check(const GridFilter& filter, int64_t utime) const {
  using geometry::GridState;
  const double sd = std::sqrt(std::max(0.0, filter.p()(GridState::kOffset, GridState::kOffset)));
  if (!std::isfinite(sd) || !filter.x().allFinite()) return "the filter state is not finite";
  if (sd > lost_offset_sd_m_) return "σ(t_x) grew to " + std::to_string(sd) + " m";
  if ((utime - last_update_utime_) * 1e-6 > max_coast_s_) {
    return "no update for " + Seconds((utime - last_update_utime_) * 1e-6);
  }
  return "";
}

void LossPolicy::Lost(double forward_distance_m) {
  distance_at_loss_m_ = std::isfinite(forward_distance_m) ? forward_distance_m : 0.0;
  dr_since_loss_m_ = 0.0;
  was_lost_ = true;
}

void LossPolicy::Start(int64_t utime, double forward_m) {
  // Keep the distance driven continuous across a loss of lock: the lines
  // passed while lost are bridged by dead reckoning.
  const double distance_before = was_lost_ ? distance_at_loss_m_ + dr_since_loss_m_ : 0.0;
  last_update_utime_ = utime;
  initial_forward_m_ = forward_m;
  passed_m_ = distance_before;
  dr_since_loss_m_ = 0.0;
  was_lost_ = false;
}

}  // namespace plantscale::tracking
