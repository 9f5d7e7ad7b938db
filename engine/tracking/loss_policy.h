#pragma once
// When the grid is lost, and what carries across a loss. Lost: the
// filter's state is not finite, σ(t_x) beyond lost_offset_sd_m, or no
// update for max_coast_s. Across a loss and the fresh start that follows
// (initialiser.h), the distance driven stays continuous: the plant lines
// passed while lost are bridged by the dead-reckoned distance (§4.1.3's
// distance is the l̄ increments of the reference shifts plus the change of
// Y). The filter keeps the wheels' scale and the calibration across it
// (GridFilter::Restart); its plants go (GridFilter::Lose).

#include <cstdint>
#include <string>

#include "engine/tracking/kalman_filter.h"
#include "engine/tracking/tracker_options.h"

namespace plantscale::tracking {

class LossPolicy {
 public:
  explicit LossPolicy(const TrackerOptions& options);

  // Before initialisation; Y's nominal value is `forward_m`.
  void Reset(double forward_m);
  // Why the grid held by `filter` is lost at utime; empty when it is not.
  std::string Check(const GridFilter& filter, int64_t utime) const;
  // The grid is lost, `forward_distance_m` driven so far (NaN: unknown).
  void Lost(double forward_distance_m);
  // Tracking (re)starts at utime with Y = forward_m.
  void Start(int64_t utime, double forward_m);
  // An update at utime.
  void Updated(int64_t utime) { last_update_utime_ = utime; }
  // Dead-reckoned while not tracking (signed, measured).
  void Coast(double distance_m) { dr_since_loss_m_ += distance_m; }
  // The reference moved by k lines of spacing l.
  void Shifted(int k, double l) {
    passed_m_ += k * l;
    lines_passed_ += k;
  }
  // Distance driven along the rows since initialisation, the state's Y
  // being `forward_m`.
  double forward_distance_m(double forward_m) const { return passed_m_ + initial_forward_m_ - forward_m; }
  int lines_passed() const { return lines_passed_; }

 private:
  double lost_offset_sd_m_;
  double max_coast_s_;
  int64_t last_update_utime_ = -1;
  int lines_passed_ = 0;
  double passed_m_ = 0.0;
  double initial_forward_m_ = 0.0;
  bool was_lost_ = false;
  double distance_at_loss_m_ = 0.0;
  double dr_since_loss_m_ = 0.0;  // dead-reckoned while not tracking
};

}  // namespace plantscale::tracking
