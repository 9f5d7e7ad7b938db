#include "telemetry/convert.h"

#include <gtest/gtest.h>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>

#include <cmath>
#include <limits>

#include "engine/common/options.h"
#include "telemetry/codec.h"

namespace plantscale::telemetry {
namespace {

GridEstimate SomeEstimate() {
  GridEstimate e;
  e.utime = 1'700'000'000'123'456;
  e.frame_index = 42;
  e.state = {0.012, 0.31, -0.02, 0.48, 0.44};
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 5; ++c) e.covariance(r, c) = 1e-4 * (r + 1) + 1e-6 * (c + 1) * (r + 2);
  e.mode = FilterMode::kTracking;
  e.lines_in_view = {0, 1, 2, 3};
  e.observations = 17;
  e.validated = 15;
  e.innovation_nis = 4.25;
  e.innovation_rms_px = 1.5;
  return e;
}

TEST(Convert, GridStateRoundTripsThroughBytesExactly) {
  const GridEstimate e = SomeEstimate();
  const Bytes bytes = Encode(ToLcm(e));
  const auto m = Decode<plantscale_grid_state_t>("PLANTSCALE_GRID", bytes.data(), bytes.size());
  ASSERT_TRUE(m.has_value());
  const GridEstimate back = FromLcm(*m);
  // Doubles travel bit for bit: tolerance 0.
  EXPECT_EQ((back.state.AsVector() - e.state.AsVector()).norm(), 0.0);
  EXPECT_EQ((back.covariance - e.covariance).norm(), 0.0);
  EXPECT_EQ(back.covariance(1, 3), e.covariance(1, 3));  // row-major, not transposed
  EXPECT_EQ(back.mode, FilterMode::kTracking);
  EXPECT_EQ(back.lines_in_view, e.lines_in_view);
  EXPECT_EQ(back.validated, 15);
  EXPECT_EQ(back.utime, e.utime);
  EXPECT_DOUBLE_EQ(back.innovation_nis, 4.25);
}

TEST(Convert, TruthIsMarkedAsTruthWithZeroCovariance) {
  geometry::GridState truth{0.05, 0.2, 0.01, 0.475, 0.45};
  const GridEstimate e = FromLcm(TruthToLcm(truth, 80'000, 1));
  EXPECT_EQ(e.mode, FilterMode::kTruth);
  EXPECT_EQ(e.covariance.norm(), 0.0);
  EXPECT_DOUBLE_EQ(e.state.offset_m, 0.05);
}

TEST(Convert, NanInGridStateIsRejectedNamingTheField) {
  plantscale_grid_state_t m = ToLcm(SomeEstimate());
  m.covariance[7] = std::numeric_limits<double>::quiet_NaN();
  try {
    FromLcm(m);
    FAIL() << "expected DataError";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("covariance"), std::string::npos) << e.what();
  }
  m = ToLcm(SomeEstimate());
  m.filter_mode = 9;
  EXPECT_THROW(FromLcm(m), DataError);
}

TEST(Convert, PlantsRoundTrip) {
  PlantObservation p;
  p.id = 7;
  p.kind = PlantKind::kWeed;
  p.position_m = {1.5, 12.25};
  p.covariance << 1e-4, 2e-5, 2e-5, 3e-4;
  p.size_m2 = 0.004;
  p.sprayed = true;
  p.why = plantscale_plant_t::WHY_OUTSIDE_REGION;
  p.distance_to_crop_m = 0.12;
  const Bytes bytes = Encode(ToLcm({p, p}, 5, 3));
  const auto m = Decode<plantscale_plant_list_t>("P", bytes.data(), bytes.size());
  ASSERT_TRUE(m.has_value());
  ASSERT_EQ(m->plants.size(), 2u);
  const PlantObservation back = FromLcm(m->plants[1]);
  EXPECT_EQ(back.kind, PlantKind::kWeed);
  EXPECT_EQ((back.position_m - p.position_m).norm(), 0.0);
  EXPECT_EQ(back.covariance(0, 1), 2e-5);
  EXPECT_TRUE(back.sprayed);
  EXPECT_EQ(back.why, int{plantscale_plant_t::WHY_OUTSIDE_REGION});
}

TEST(Convert, MapTileRoundTripsCompressed) {
  MapTileDelta t;
  t.tile_x = 3;
  t.tile_y = -2;
  t.revision = 5;
  t.width = 64;
  t.height = 64;
  t.cells.assign(64 * 64, plantscale_map_tile_t::CELL_SOIL);
  for (int i = 100; i < 140; ++i)
    t.cells[static_cast<size_t>(i)] = plantscale_map_tile_t::CELL_CROP;
  const plantscale_map_tile_t m = ToLcm(t, 1);
  EXPECT_LT(m.cells.size(), t.cells.size() / 20);  // mostly soil: > 20x smaller
  const MapTileDelta back = FromLcm(m);
  EXPECT_EQ(back.cells, t.cells);
  EXPECT_EQ(back.tile_y, -2);
  EXPECT_EQ(back.revision, 5);
}

TEST(Convert, NozzlesAndHealthRoundTrip) {
  NozzleBar bar;
  bar.open = {true, false, true};
  bar.fault = {0, plantscale_nozzles_t::FAULT_STUCK, 0};
  bar.failsafe = false;
  bar.shots.push_back({2, 100, 180, {0.3, 4.0}, 11});
  const NozzleBar b = FromLcm(ToLcm(bar, 1));
  EXPECT_EQ(b.open, bar.open);
  EXPECT_EQ(b.fault, bar.fault);
  ASSERT_EQ(b.shots.size(), 1u);
  EXPECT_EQ(b.shots[0].close_utime, 180);
  EXPECT_DOUBLE_EQ(b.shots[0].position_m.y(), 4.0);

  Health h;
  h.source = "simulate";
  h.frames = 120;
  h.dropped_frames = 2;
  h.faults = {"camera: no frame for 0.3 s"};
  const plantscale_health_t hm = ToLcm(h, 5);
  EXPECT_EQ(hm.protocol_version, int32_t{plantscale_health_t::PROTOCOL_VERSION});
  const Health back = FromLcm(hm);
  EXPECT_EQ(back.faults, h.faults);
  EXPECT_EQ(back.dropped_frames, 2);
}

// Found by tests/fuzz/lcm_fuzz: lcm-gen's decode() resized the array to a
// 32-bit length field before checking the bytes, so a few corrupt bytes
// asked for gigabytes. Decode refuses such lengths before decode() runs.
void SetInt32(Bytes& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
}

TEST(Codec, LengthFieldsBeyondTheBytesAreRefusedBeforeAllocating) {
  MapTileDelta tile;
  tile.width = 4;
  tile.height = 2;
  tile.cells.assign(8, 1);
  Bytes b = Encode(ToLcm(tile, 1));
  ASSERT_TRUE(Decode<plantscale_map_tile_t>("T", b.data(), b.size()));
  SetInt32(b, b.size() - 2 - 4, 0x7FFFFFFF);  // num_bytes (the RLE cells are 2 bytes)
  std::string error;
  EXPECT_FALSE(Decode<plantscale_map_tile_t>("T", b.data(), b.size(), &error));
  EXPECT_NE(error.find("plantscale_map_tile_t"), std::string::npos) << error;

  Bytes list = Encode(ToLcm(std::vector<PlantObservation>(2), 1, 1));
  ASSERT_TRUE(Decode<plantscale_plant_list_t>("P", list.data(), list.size()));
  const size_t plant = static_cast<size_t>(plantscale_plant_t{}._getEncodedSizeNoHash());
  SetInt32(list, list.size() - 2 * plant - 4, 30'000'000);  // num_plants: 2.6 GB of plants
  EXPECT_FALSE(Decode<plantscale_plant_list_t>("P", list.data(), list.size()));

  plantscale_thumbnail_t t{};
  t.jpeg = {1, 2, 3};
  t.jpeg_size = 3;
  t.blobs.resize(1);
  t.num_blobs = 1;
  Bytes thumb = Encode(t);
  ASSERT_TRUE(Decode<plantscale_thumbnail_t>("J", thumb.data(), thumb.size()));
  const size_t blob = static_cast<size_t>(plantscale_blob_t{}._getEncodedSizeNoHash());
  Bytes blobs = thumb;
  SetInt32(blobs, blobs.size() - blob - 4, 0x7FFFFFFF);  // num_blobs
  EXPECT_FALSE(Decode<plantscale_thumbnail_t>("J", blobs.data(), blobs.size()));
  SetInt32(thumb, thumb.size() - blob - 4 - 3 - 4, 0x7FFFFFFF);  // jpeg_size
  EXPECT_FALSE(Decode<plantscale_thumbnail_t>("J", thumb.data(), thumb.size()));
  // ... also when the message ends right after it.
  const size_t cut = thumb.size() - blob - 4 - 3;
  EXPECT_FALSE(Decode<plantscale_thumbnail_t>("J", thumb.data(), cut));
}

// Found by tests/fuzz/lcm_fuzz (UBSan): a string length of INT32_MIN made
// lcm-gen's `length - 1` overflow into a 2 GB read past the message, and 0
// threw length_error; lcm_gen_fix.cmake refuses lengths below 1.
TEST(Codec, StringLengthsBelowOneAreRefused) {
  plantscale_event_t e{};
  e.kind = "k";
  e.text = "text";
  Bytes b = Encode(e);
  ASSERT_TRUE(Decode<plantscale_event_t>("E", b.data(), b.size()));
  const size_t kind_length_at = 8 + 8 + 8 + 1;  // fingerprint, utime, seq, severity
  for (uint32_t length : {0x80000000u, 0u, 0xFFFFFFFFu}) {
    SetInt32(b, kind_length_at, length);
    std::string error;
    EXPECT_FALSE(Decode<plantscale_event_t>("E", b.data(), b.size(), &error)) << length;
    EXPECT_NE(error.find("plantscale_event_t"), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace plantscale::telemetry
