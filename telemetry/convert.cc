#include "telemetry/convert.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/common/options.h"
#include "telemetry/rle.h"

namespace plantscale::telemetry {
namespace {

template <typename Range>
void RequireFiniteAll(const Range& values, const char* type, const char* field) {
  for (double v : values) {
    if (!std::isfinite(v)) {
      throw DataError(std::string(type) + "." + field + ": not finite (" + std::to_string(v) + ")");
    }
  }
}

template <int R, int C>
void CopyMatrix(const Eigen::Matrix<double, R, C>& m, double* out) {
  for (int r = 0; r < R; ++r)
    for (int c = 0; c < C; ++c) out[r * C + c] = m(r, c);
}

template <int R, int C>
Eigen::Matrix<double, R, C> ReadMatrix(const double* in) {
  Eigen::Matrix<double, R, C> m;
  for (int r = 0; r < R; ++r)
    for (int c = 0; c < C; ++c) m(r, c) = in[r * C + c];
  return m;
}

FilterMode ModeFromLcm(int8_t mode) {
  if (mode < 0 || mode > static_cast<int8_t>(FilterMode::kTruth)) {
    throw DataError("plantscale_grid_state_t.filter_mode: unknown value " + std::to_string(mode));
  }
  return static_cast<FilterMode>(mode);
}

}  // namespace

plantscale_grid_state_t ToLcm(const GridEstimate& e) {
  plantscale_grid_state_t m{};
  m.utime = e.utime;
  m.frame_index = e.frame_index;
  const geometry::Vector5d x = e.state.AsVector();
  std::copy(x.data(), x.data() + 5, m.state);
  CopyMatrix<5, 5>(e.covariance, m.covariance);
  m.filter_mode = static_cast<int8_t>(e.mode);
  m.num_lines = static_cast<int16_t>(e.lines_in_view.size());
  m.lines_in_view.assign(e.lines_in_view.begin(), e.lines_in_view.end());
  m.observations = e.observations;
  m.validated = e.validated;
  m.innovation_nis = e.innovation_nis;
  m.innovation_rms_px = e.innovation_rms_px;
  return m;
}

GridEstimate FromLcm(const plantscale_grid_state_t& m) {
  RequireFiniteAll(m.state, "plantscale_grid_state_t", "state");
  RequireFiniteAll(m.covariance, "plantscale_grid_state_t", "covariance");
  GridEstimate e;
  e.utime = m.utime;
  e.frame_index = m.frame_index;
  e.state = geometry::GridState::FromVector(Eigen::Map<const geometry::Vector5d>(m.state));
  e.covariance = ReadMatrix<5, 5>(m.covariance);
  e.mode = ModeFromLcm(m.filter_mode);
  e.lines_in_view.assign(m.lines_in_view.begin(), m.lines_in_view.end());
  e.observations = m.observations;
  e.validated = m.validated;
  e.innovation_nis = m.innovation_nis;
  e.innovation_rms_px = m.innovation_rms_px;
  return e;
}

plantscale_grid_state_t TruthToLcm(const geometry::GridState& truth, int64_t utime,
                                   int frame_index) {
  GridEstimate e;
  e.utime = utime;
  e.frame_index = frame_index;
  e.state = truth;
  e.mode = FilterMode::kTruth;
  return ToLcm(e);
}

plantscale_plant_t ToLcm(const PlantObservation& p) {
  plantscale_plant_t m{};
  m.id = p.id;
  m.cls = static_cast<int8_t>(p.kind);
  m.position_m[0] = p.position_m.x();
  m.position_m[1] = p.position_m.y();
  CopyMatrix<2, 2>(p.covariance, m.covariance);
  m.size_m2 = p.size_m2;
  m.sprayed = p.sprayed ? 1 : 0;
  m.why = static_cast<int8_t>(p.why);
  m.distance_to_crop_m = p.distance_to_crop_m;
  return m;
}

PlantObservation FromLcm(const plantscale_plant_t& m) {
  RequireFiniteAll(m.position_m, "plantscale_plant_t", "position_m");
  RequireFiniteAll(m.covariance, "plantscale_plant_t", "covariance");
  if (m.cls < 0 || m.cls > 2)
    throw DataError("plantscale_plant_t.cls: unknown value " + std::to_string(m.cls));
  PlantObservation p;
  p.id = m.id;
  p.kind = static_cast<PlantKind>(m.cls);
  p.position_m = {m.position_m[0], m.position_m[1]};
  p.covariance = ReadMatrix<2, 2>(m.covariance);
  p.size_m2 = m.size_m2;
  p.sprayed = m.sprayed != 0;
  p.why = m.why;
  p.distance_to_crop_m = m.distance_to_crop_m;
  return p;
}

plantscale_plant_list_t ToLcm(const std::vector<PlantObservation>& plants, int64_t utime,
                              int frame_index) {
  plantscale_plant_list_t m{};
  m.utime = utime;
  m.frame_index = frame_index;
  m.num_plants = static_cast<int32_t>(plants.size());
  for (const PlantObservation& p : plants) m.plants.push_back(ToLcm(p));
  return m;
}

plantscale_map_tile_t ToLcm(const MapTileDelta& t, int64_t utime) {
  plantscale_map_tile_t m{};
  m.utime = utime;
  m.tile_x = t.tile_x;
  m.tile_y = t.tile_y;
  m.revision = t.revision;
  m.origin_m[0] = t.origin_m.x();
  m.origin_m[1] = t.origin_m.y();
  m.resolution_m = t.resolution_m;
  m.width = static_cast<int16_t>(t.width);
  m.height = static_cast<int16_t>(t.height);
  m.encoding = plantscale_map_tile_t::ENC_RLE;
  m.cells = RleEncode(t.cells);
  m.num_bytes = static_cast<int32_t>(m.cells.size());
  return m;
}

MapTileDelta FromLcm(const plantscale_map_tile_t& m) {
  if (m.width <= 0 || m.height <= 0) throw DataError("plantscale_map_tile_t: empty tile size");
  RequireFiniteAll(m.origin_m, "plantscale_map_tile_t", "origin_m");
  MapTileDelta t;
  t.tile_x = m.tile_x;
  t.tile_y = m.tile_y;
  t.revision = m.revision;
  t.origin_m = {m.origin_m[0], m.origin_m[1]};
  t.resolution_m = m.resolution_m;
  t.width = m.width;
  t.height = m.height;
  const size_t n = static_cast<size_t>(m.width) * static_cast<size_t>(m.height);
  if (m.encoding == plantscale_map_tile_t::ENC_RLE) {
    t.cells = RleDecode(m.cells, n);
  } else if (m.encoding == plantscale_map_tile_t::ENC_RAW && m.cells.size() == n) {
    t.cells = m.cells;
  } else {
    throw DataError("plantscale_map_tile_t: bad encoding " + std::to_string(m.encoding) +
                    " or cell count");
  }
  return t;
}

plantscale_nozzles_t ToLcm(const NozzleBar& bar, int64_t utime) {
  plantscale_nozzles_t m{};
  m.utime = utime;
  m.num_nozzles = static_cast<int16_t>(bar.open.size());
  for (bool o : bar.open) m.open.push_back(o ? 1 : 0);
  m.fault.assign(bar.open.size(), 0);
  for (size_t i = 0; i < bar.fault.size() && i < bar.open.size(); ++i)
    m.fault[i] = static_cast<int8_t>(bar.fault[i]);
  m.failsafe = bar.failsafe ? 1 : 0;
  m.num_shots = static_cast<int16_t>(bar.shots.size());
  for (const NozzleShot& s : bar.shots) {
    m.shots.push_back({static_cast<int16_t>(s.nozzle),
                       s.open_utime,
                       s.close_utime,
                       {s.position_m.x(), s.position_m.y()},
                       s.plant_id});
  }
  return m;
}

NozzleBar FromLcm(const plantscale_nozzles_t& m) {
  NozzleBar bar;
  for (int8_t o : m.open) bar.open.push_back(o != 0);
  bar.fault.assign(m.fault.begin(), m.fault.end());
  bar.failsafe = m.failsafe != 0;
  for (const plantscale_shot_t& s : m.shots) {
    RequireFiniteAll(s.position_m, "plantscale_shot_t", "position_m");
    bar.shots.push_back(
        {s.nozzle, s.open_utime, s.close_utime, {s.position_m[0], s.position_m[1]}, s.plant_id});
  }
  return bar;
}

plantscale_pose_t ToLcm(const Pose& p, int64_t utime) {
  plantscale_pose_t m{};
  m.utime = utime;
  m.x_m = p.x_m;
  m.y_m = p.y_m;
  m.heading_rad = p.heading_rad;
  CopyMatrix<3, 3>(p.covariance, m.covariance);
  return m;
}

Pose FromLcm(const plantscale_pose_t& m) {
  RequireFiniteAll(std::vector<double>{m.x_m, m.y_m, m.heading_rad}, "plantscale_pose_t", "pose");
  RequireFiniteAll(m.covariance, "plantscale_pose_t", "covariance");
  return {m.x_m, m.y_m, m.heading_rad, ReadMatrix<3, 3>(m.covariance)};
}

plantscale_health_t ToLcm(const Health& h, int64_t utime) {
  plantscale_health_t m{};
  m.utime = utime;
  m.protocol_version = plantscale_health_t::PROTOCOL_VERSION;
  m.boot_utime = h.boot_utime;
  m.source = h.source;
  m.frame_rate_hz = h.frame_rate_hz;
  m.frames = h.frames;
  m.dropped_frames = h.dropped_frames;
  m.distance_m = h.distance_m;
  m.failsafe = h.failsafe ? 1 : 0;
  m.num_faults = static_cast<int16_t>(h.faults.size());
  m.faults = h.faults;
  m.telemetry_dropped = h.telemetry_dropped;
  return m;
}

Health FromLcm(const plantscale_health_t& m) {
  Health h;
  h.source = m.source;
  h.boot_utime = m.boot_utime;
  h.frame_rate_hz = m.frame_rate_hz;
  h.frames = m.frames;
  h.dropped_frames = m.dropped_frames;
  h.distance_m = m.distance_m;
  h.failsafe = m.failsafe != 0;
  h.faults = m.faults;
  h.telemetry_dropped = m.telemetry_dropped;
  return h;
}

}  // namespace plantscale::telemetry
