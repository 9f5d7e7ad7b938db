#include "engine/sim/simulator.h"

#include <cmath>

namespace plantscale::sim {
namespace {

constexpr double kViewReachM = 12.0;  // field generated this far beyond the pass

Pose2 Interpolate(const Pose2& a, const Pose2& b, double t) {
  return {a.x_m + t * (b.x_m - a.x_m), a.y_m + t * (b.y_m - a.y_m),
          a.heading_rad + t * (b.heading_rad - a.heading_rad)};
}

}  // namespace

OptionErrors SimulatorOptions::Validate() const {
  OptionErrors e;
  const auto add = [&e](OptionErrors more) { e.insert(e.end(), more.begin(), more.end()); };
  add(Prefixed("camera", camera.Validate()));
  add(Prefixed("grid", grid.Validate()));
  add(Prefixed("field", field.Validate()));
  add(Prefixed("vehicle", vehicle.Validate()));
  add(Prefixed("render", render.Validate()));
  RequireInRange(e, "length_m", length_m, 0.0, 10000.0, false, true);
  return e;
}

Simulator::Simulator(const SimulatorOptions& options)
    : options_((ThrowIfInvalid("simulator preset '" + options.preset + "'", options.Validate()),
                options)),
      camera_(options.camera),
      field_(options.field, -kViewReachM, options.length_m + kViewReachM, options.seed),
      vehicle_(options.vehicle, options.seed),
      renderer_(options.render, options.seed),
      timing_rng_(Rng::Derived(options.seed, 0x71e)) {}

int Simulator::expected_frames() const {
  return static_cast<int>(options_.length_m / options_.vehicle.speed_m_s *
                          options_.vehicle.frame_rate_hz);
}

geometry::CameraModel Simulator::CameraFor(const CameraBounce& bounce) const {
  geometry::CameraOptions o = options_.camera;
  o.tilt_rad = std::min(o.tilt_rad + bounce.pitch_rad, 1.5707963267948966);
  o.roll_rad += bounce.roll_rad;
  o.height_m += bounce.height_m;
  return geometry::CameraModel(o);
}

bool Simulator::Next(SimFrame& frame, bool render) {
  const VehicleOptions& vo = options_.vehicle;
  frame.odometry.clear();  // refilled with every sample since the last delivered frame
  for (;;) {
    if (vehicle_.distance_m() >= options_.length_m) return false;
    const double due_s =
        (frame_index_ + 1) / vo.frame_rate_hz + timing_rng_.Normal(0.0, vo.frame_jitter_s);
    const bool dropped = timing_rng_.Bernoulli(vo.dropped_frame_fraction);
    ++frame_index_;
    // Drive until the capture time, keeping the odometry in between.
    Pose2 before = vehicle_.pose();
    int64_t before_utime = vehicle_.utime();
    double before_distance = vehicle_.distance_m();
    const auto due_utime = static_cast<int64_t>(std::llround(due_s * 1e6));
    while (vehicle_.utime() < due_utime) {
      before = vehicle_.pose();
      before_utime = vehicle_.utime();
      before_distance = vehicle_.distance_m();
      frame.odometry.push_back(vehicle_.Step());
    }
    if (dropped) {
      ++dropped_;
      continue;  // odometry carries over to the next delivered frame
    }
    const double span = static_cast<double>(vehicle_.utime() - before_utime);
    const double t = span > 0.0 ? static_cast<double>(due_utime - before_utime) / span : 1.0;
    FrameTruth& truth = frame.truth;
    truth.index = emitted_++;
    truth.utime = due_utime;
    truth.pose = Interpolate(before, vehicle_.pose(), t);
    truth.bounce = vehicle_.bounce();
    truth.distance_m = before_distance + t * (vehicle_.distance_m() - before_distance);
    FillGridTruth(truth);
    truth.plants.clear();
    if (!render) {
      frame.rendered = RenderedFrame{};
      return true;
    }
    const geometry::CameraModel camera = CameraFor(truth.bounce);
    renderer_.Render(field_, camera, truth.pose, vo.speed_m_s, vo.exposure_s,
                     options_.seed * 1000003ULL + static_cast<uint64_t>(frame_index_),
                     frame.rendered);
    FillPlantTruth(camera, frame.rendered, truth);
    return true;
  }
}

void Simulator::FillGridTruth(FrameTruth& truth) const {
  // The planted grid seen from the nominal camera: line 0 is the first line
  // whose central-row plant is not below the image (thesis §4.1.3).
  const Pose2& p = truth.pose;
  const double c = std::cos(p.heading_rad);
  const double s = std::sin(p.heading_rad);
  const double plane = options_.camera.virtual_plane_height_m;
  const auto image_v = [&](double y) -> std::optional<double> {
    const Eigen::Vector2d v = FieldToVehicle(p, {0.0, y});
    const auto uv = camera_.Project({v.x(), v.y(), plane});
    return uv ? std::optional<double>(uv->y()) : std::nullopt;
  };
  const std::vector<double>& lines = field_.line_y_m();
  size_t first = 0;
  while (first < lines.size()) {
    const auto v = image_v(lines[first]);
    if (v && *v <= camera_.height()) break;
    ++first;
  }
  size_t last = first;
  while (last + 1 < lines.size()) {
    const auto v = image_v(lines[last + 1]);
    if (!v || *v < 0.0) break;
    ++last;
  }
  geometry::GridState& g = truth.grid;
  truth.line0 = first < lines.size() ? static_cast<int>(first) : -1;
  const double y0 = first < lines.size() ? lines[first] : p.y_m;
  g.offset_m = -p.x_m / c;
  g.forward_m = (y0 - p.y_m) + p.x_m * s / c;
  g.bearing_rad = p.heading_rad;
  const double mid_y = 0.5 * (y0 + (last < lines.size() ? lines[last] : y0));
  g.row_spacing_m = field_.RowSpacingAt(mid_y);
  g.plant_spacing_m = last > first && last < lines.size()
                          ? (lines[last] - lines[first]) / static_cast<double>(last - first)
                          : field_.PlantSpacingAt(y0);
}

void Simulator::FillPlantTruth(const geometry::CameraModel& camera, const RenderedFrame& rendered,
                               FrameTruth& truth) const {
  truth.plants.clear();
  for (size_t k = 0; k < rendered.plants.size(); ++k) {
    const RenderedPlant& r = rendered.plants[k];
    if (r.area_px == 0) continue;  // fully hidden or outside the image
    const Plant& plant = field_.plants()[static_cast<size_t>(r.plant_index)];
    PlantTruth t;
    t.instance = static_cast<int>(k) + 1;
    t.plant_id = plant.id;
    t.cls = plant.cls;
    t.row = plant.row;
    t.line = plant.line;
    t.field_m = plant.position_m;
    t.vehicle_m = FieldToVehicle(truth.pose, plant.position_m);
    t.radius_m = plant.radius_m;
    t.height_m = plant.height_m;
    t.root_px = camera.Project({t.vehicle_m.x(), t.vehicle_m.y(), 0.0});
    t.area_px = r.area_px;
    t.centroid_px = r.centroid_px;
    truth.plants.push_back(t);
  }
}

}  // namespace plantscale::sim
