#pragma once
// Nozzle scheduling (thesis §8.2): a bar of N nozzles a known distance
// behind the camera's ground point passes over the treatment map; a nozzle
// opens when the strip of ground it will cover during the next tick holds a
// cell of the treated class (a strip narrower than a cell: the cell its
// middle is in). "Will": the valve opens `valve_latency_s` after
// the command, so the strip is where the nozzle will be then, led by the
// forward speed from the 50 Hz pose over the latency and the time since the
// pose (ticks run at 200 Hz, four per pose). Fail-safe: every nozzle closed when the
// pose is stale, the camera is lost, odometry is invalid, the tracker has
// lost the grid or holds it too loosely to hit a plant (bar_uncertainty.h);
// each reason is reported.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "engine/common/options.h"
#include "engine/treatment/bed_frame.h"
#include "engine/treatment/treatment_map.h"

namespace plantscale::treatment {

enum class SprayMode { kCrop, kWeed };  // fertiliser/protectant on the crop, or herbicide
const char* ToString(SprayMode mode);
bool ParseSprayMode(const std::string& name, SprayMode& mode);

struct SprayBarOptions {
  int nozzles = 64;                // at most 64 (one bit each in the open mask)
  double nozzle_spacing_m = 0.0225;  // and the width each nozzle covers
  double bar_offset_m = 0.6;       // behind the camera's ground point (vehicle y = −offset)
  double centre_x_m = 0.0;         // vehicle x of the bar's centre
  double valve_latency_s = 0.04;   // command to spray on the ground

  OptionErrors Validate() const;
  // Vehicle-frame ground position of nozzle i (0: leftmost).
  Eigen::Vector2d Nozzle(int i) const;
};

struct FailSafeOptions {
  double max_pose_age_s = 0.1;   // issue: pose stale beyond 100 ms
  double max_frame_age_s = 0.5;  // no camera frame for this long: camera lost
  // Fail-safe on uncertainty: the bar closes while the 95 % ellipse of where
  // the plants reaching the bar stand (SafetyInputs::reach_*) reaches further
  // than this from them, across or along the rows: the margin by which the
  // sprayed footprint exceeds the plant's target. The treatment sets them
  // from its footprint (TreatmentOptions::UncertaintyMargin); infinite: never.
  double max_reach_across_m = std::numeric_limits<double>::infinity();
  double max_reach_along_m = std::numeric_limits<double>::infinity();

  OptionErrors Validate() const;
};

struct SchedulerOptions {
  SprayBarOptions bar;
  SprayMode mode = SprayMode::kCrop;
  FailSafeOptions fail_safe;
  // The command period. A nozzle opens and closes on ticks only, so each
  // end of its spray falls anywhere within one tick's travel of the map's
  // edge: at 50 Hz and 0.7 m/s that is 14 mm, and the sprayed patch's
  // centre moves by sd 2.9 mm. Commands run at 200 Hz (3.5 mm, sd 0.7 mm),
  // four per 50 Hz pose, each led from the pose by the time since it.
  // On the CAN bus, 64 nozzles at 200 Hz are 400 commands and 400
  // acknowledgements a second, about 42 % of a 250 kbit/s bus.
  double tick_s = 0.005;
  double pose_period_s = 0.02;  // the 50 Hz pose each group of ticks starts from

  OptionErrors Validate() const;
  // Ticks per pose: pose_period_s / tick_s, at least 1.
  int TicksPerPose() const;
};

// What the vehicle knows about its own health at a tick.
struct SafetyInputs {
  int64_t pose_utime = -1;        // time of the pose used (−1: none)
  int64_t last_frame_utime = -1;  // last camera frame received (−1: none)
  bool camera_ok = true;          // the camera source reports no fault
  bool odometry_valid = true;     // the last odometry sample was accepted
  bool tracking = false;          // the tracker holds the grid
  bool held = false;              // the operator paused spraying or switched it off
  // Half extents of the 95 % ellipse of the plants' position at the bar
  // (bar_uncertainty.h: PlantReachAtBar); 0 when not known.
  double reach_across_m = 0.0;
  double reach_along_m = 0.0;
};

enum FailReason : uint32_t {
  kPoseStale = 1u << 0,
  kCameraLost = 1u << 1,
  kOdometryInvalid = 1u << 2,
  kTrackerLost = 1u << 3,
  kOperatorHold = 1u << 4,
  kPositionUncertain = 1u << 5,
};
// "pose stale (130 ms > 100 ms)", ...: one message per reason set in `reasons`.
std::vector<std::string> FailReasonMessages(uint32_t reasons);

// Fail-safe check alone: reasons bitmask, 0 when safe to spray.
uint32_t CheckFailSafe(int64_t now_utime, const SafetyInputs& in, const FailSafeOptions& o,
                       std::vector<std::string>* messages = nullptr);

struct NozzleTarget {
  int nozzle = 0;
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // bed strip the nozzle covers next tick
};

struct TickResult {
  int64_t utime = 0;
  uint64_t open_mask = 0;
  uint32_t fail_reasons = 0;
  std::vector<std::string> messages;  // why the bar is closed, when it is
  std::vector<NozzleTarget> opened;   // strips of the nozzles opened
};

// Called on every tick with the open mask (all zero on fail-safe).
using NozzleSink = std::function<void(int64_t utime, uint64_t open_mask)>;

class NozzleScheduler {
 public:
  // Throws InvalidOptionsError.
  explicit NozzleScheduler(const SchedulerOptions& options, NozzleSink sink = {});

  TickResult Tick(int64_t now_utime, const BedPose& pose, const TreatmentMap& map,
                  const SafetyInputs& safety);
  // The bed strip nozzle i covers during the tick starting at `now_utime`
  // plus the valve latency: the pose is dead-reckoned forward to then at
  // its speed (a tick later than its pose leads by the time since it).
  NozzleTarget Target(int i, const BedPose& pose, int64_t now_utime) const;

  const SchedulerOptions& options() const { return options_; }
  void set_sink(NozzleSink sink) { sink_ = std::move(sink); }
  void set_mode(SprayMode mode) { options_.mode = mode; }

 private:
  SchedulerOptions options_;
  NozzleSink sink_;
};

}  // namespace plantscale::treatment
