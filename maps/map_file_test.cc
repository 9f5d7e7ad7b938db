#include "maps/map_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "maps/map_errors.h"
#include "maps/test_maps.h"

namespace plantscale::maps {
namespace {

using testing::SyntheticMap;
using testing::TempDir;

void ExpectSameMap(const CropMap& a, const CropMap& b) {
  EXPECT_EQ(a.grid(), b.grid());
  EXPECT_EQ(a.layers().cls, b.layers().cls);
  EXPECT_EQ(a.layers().crop_count, b.layers().crop_count);
  EXPECT_EQ(a.layers().weed_count, b.layers().weed_count);
  EXPECT_EQ(a.layers().treated, b.layers().treated);
  ASSERT_EQ(a.plants().size(), b.plants().size());
  for (size_t i = 0; i < a.plants().size(); ++i) {
    const MapPlant& p = a.plants()[i];
    const MapPlant& q = b.plants()[i];
    EXPECT_EQ(p.id, q.id);
    EXPECT_EQ(p.position_m, q.position_m);  // bit-exact: CBOR stores doubles
    EXPECT_EQ(p.kind, q.kind);
    EXPECT_EQ(p.confidence, q.confidence);
    EXPECT_EQ(p.radius_m, q.radius_m);
    EXPECT_EQ(p.treated, q.treated);
    EXPECT_EQ(p.why, q.why);
  }
  ASSERT_EQ(a.rows().size(), b.rows().size());
  for (size_t i = 0; i < a.rows().size(); ++i) {
    EXPECT_EQ(a.rows()[i].index, b.rows()[i].index);
    EXPECT_EQ(a.rows()[i].points_m, b.rows()[i].points_m);
  }
  EXPECT_EQ(a.metadata(), b.metadata());
}

std::string Saved(const CropMap& map) {
  std::ostringstream out;
  WriteMap(map, out, "memory");
  return out.str();
}

void ExpectDataError(const std::string& bytes, const std::string& fragment) {
  std::istringstream in(bytes);
  try {
    ReadMap(in, "bad.psmap");
    FAIL() << "expected DataError containing '" << fragment << "'";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.psmap: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(MapFile, SaveThenLoadGivesTheSameMap) {
  TempDir dir;
  const CropMap map = SyntheticMap();
  SaveMap(map, dir.path() / "a.psmap");
  EXPECT_TRUE(LooksLikeMapFile(dir.path() / "a.psmap"));
  ExpectSameMap(map, LoadMap(dir.path() / "a.psmap"));
  // Nothing but the map itself is left in the folder (no temporaries).
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);
}

TEST(MapFile, Crc32MatchesTheStandardCheckValue) {
  const std::string check = "123456789";  // CRC-32/ISO-HDLC check value 0xCBF43926
  EXPECT_EQ(Crc32(reinterpret_cast<const uint8_t*>(check.data()), check.size()), 0xCBF43926u);
}

TEST(MapFile, CorruptInputIsRefusedWithTheReason) {
  const std::string good = Saved(SyntheticMap());
  ExpectDataError("GIF89a garbage", "not a plantscale map file");
  std::string v2 = good;
  v2.replace(v2.find(" 1 "), 3, " 2 ");
  ExpectDataError(v2, "version 2 is not supported");
  ExpectDataError(good.substr(0, good.size() / 2), "truncated");
  std::string flipped = good;
  flipped[flipped.size() - 100] ^= 0x10;
  ExpectDataError(flipped, "CRC-32");
  ExpectDataError("plantscale-map 1\n", "header is malformed");
  // Found by tests/fuzz/map_file_fuzz: a checksum that is not hex threw
  // std::invalid_argument ("stoul"). Seen while fixing it: a size of -1
  // asked for 2^64 bytes.
  ExpectDataError("plantscale-map 1 4 zz\nabcd", "header is malformed");
  ExpectDataError("plantscale-map 1 -1 00000000\nabcd", "header is malformed");
  ExpectDataError("plantscale-map 1 99999999999999 00000000\nabcd", "truncated");
}

TEST(MapFile, WellFormedButIncompleteContentNamesTheField) {
  // A valid header and checksum around CBOR that lacks the layers.
  const std::vector<uint8_t> cbor = nlohmann::json::to_cbor(nlohmann::json{{"grid",
                                                                            {{"resolution_m", 0.02},
                                                                             {"origin_x_m", 0.0},
                                                                             {"origin_y_m", 0.0},
                                                                             {"cols", 2},
                                                                             {"rows", 2}}}});
  char crc[9];
  std::snprintf(crc, sizeof crc, "%08x", Crc32(cbor.data(), cbor.size()));
  const std::string bytes = "plantscale-map 1 " + std::to_string(cbor.size()) + " " + crc + "\n" +
                            std::string(cbor.begin(), cbor.end());
  ExpectDataError(bytes, "missing 'layers'");
}

// Found by tests/fuzz/map_file_fuzz: CBOR that declares an array of 2^64
// items threw nlohmann's out_of_range. Seen while fixing it: a float where
// an int belongs was converted unchecked (undefined for 1e300), and a
// "plants" that is not a list threw type_error.
TEST(MapFile, MalformedCborAndFieldShapesAreDataErrors) {
  const auto wrapped = [](const std::vector<uint8_t>& cbor) {
    char crc[9];
    std::snprintf(crc, sizeof crc, "%08x", Crc32(cbor.data(), cbor.size()));
    return "plantscale-map 1 " + std::to_string(cbor.size()) + " " + crc + "\n" +
           std::string(cbor.begin(), cbor.end());
  };
  // An array head (0x9b) with a 64-bit count of 0xffffd0ffff...
  ExpectDataError(wrapped({0xa1, 0x61, 'g', 0x9b, 0xff, 0xff, 0xd0, 0xff, 0xff, 0xf6, 0x01, 0x00}),
                  "malformed CBOR payload");
  nlohmann::json map = nlohmann::json::from_cbor(
      Saved(SyntheticMap()).substr(Saved(SyntheticMap()).find('\n') + 1));
  nlohmann::json huge_cols = map;
  huge_cols["grid"]["cols"] = 1e300;
  ExpectDataError(wrapped(nlohmann::json::to_cbor(huge_cols)), "'cols' is not an integer");
  nlohmann::json plants_object = map;
  plants_object["plants"] = nlohmann::json{{"a", 1}};
  ExpectDataError(wrapped(nlohmann::json::to_cbor(plants_object)), "'plants' is not a list");
}

TEST(MapFile, FullDiskIsAnIoErrorNamingTheFile) {
  std::ofstream full("/dev/full", std::ios::binary);
  ASSERT_TRUE(full.is_open());
  try {
    WriteMap(SyntheticMap(), full, "/dev/full");
    FAIL() << "expected MapIoError";
  } catch (const MapIoError& e) {
    EXPECT_EQ(e.path(), "/dev/full");
    EXPECT_NE(std::string(e.what()).find("write failed"), std::string::npos);
  }
}

TEST(MapFile, UnwritableFolderIsAnIoErrorAndLeavesTheOldFile) {
  TempDir dir;
  std::ofstream(dir.path() / "plain_file") << "x";
  EXPECT_THROW(SaveMap(SyntheticMap(), dir.path() / "plain_file" / "a.psmap"), MapIoError);
  EXPECT_THROW(LoadMap(dir.path() / "absent.psmap"), MapIoError);
}

}  // namespace
}  // namespace plantscale::maps
