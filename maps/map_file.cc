#include "maps/map_file.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "maps/map_errors.h"
#include "maps/staged_output.h"

namespace plantscale::maps {
namespace {

using Json = nlohmann::json;
using Bytes = std::vector<uint8_t>;

Bytes U16Bytes(const std::vector<uint16_t>& v) {
  Bytes out(v.size() * 2);
  for (size_t i = 0; i < v.size(); ++i) {
    out[2 * i] = static_cast<uint8_t>(v[i] & 0xff);
    out[2 * i + 1] = static_cast<uint8_t>(v[i] >> 8);
  }
  return out;
}

std::vector<uint16_t> FromU16Bytes(const Bytes& b) {
  std::vector<uint16_t> out(b.size() / 2);
  for (size_t i = 0; i < out.size(); ++i) {
    out[i] = static_cast<uint16_t>(b[2 * i] | (b[2 * i + 1] << 8));
  }
  return out;
}

Json PlantJson(const MapPlant& p) {
  return {{"id", p.id},
          {"x_m", p.position_m.x()},
          {"y_m", p.position_m.y()},
          {"class", ToString(p.kind)},
          {"confidence", p.confidence},
          {"radius_m", p.radius_m},
          {"treated", p.treated},
          {"why", p.why}};
}

Json RowJson(const MapRow& r) {
  Json x = Json::array();
  Json y = Json::array();
  for (const Eigen::Vector2d& p : r.points_m) {
    x.push_back(p.x());
    y.push_back(p.y());
  }
  return {{"index", r.index}, {"x_m", x}, {"y_m", y}};
}

Json MapJson(const CropMap& map) {
  const MapGrid& g = map.grid();
  const MapLayers& l = map.layers();
  Json plants = Json::array();
  for (const MapPlant& p : map.plants()) plants.push_back(PlantJson(p));
  Json rows = Json::array();
  for (const MapRow& r : map.rows()) rows.push_back(RowJson(r));
  return {{"grid",
           {{"resolution_m", g.resolution_m()},
            {"origin_x_m", g.origin_m().x()},
            {"origin_y_m", g.origin_m().y()},
            {"cols", g.cols()},
            {"rows", g.rows()}}},
          {"layers",
           {{"class", Json::binary(l.cls)},
            {"crop_count", Json::binary(U16Bytes(l.crop_count))},
            {"weed_count", Json::binary(U16Bytes(l.weed_count))},
            {"treated", Json::binary(l.treated)}}},
          {"plants", plants},
          {"rows", rows},
          {"metadata", map.metadata()}};
}

// --- reading -------------------------------------------------------------

template <typename T>
T Get(const Json& j, const char* key, const std::string& where) {
  if (!j.is_object() || !j.contains(key)) throw DataError(where + ": missing '" + key + "'");
  const Json& v = j.at(key);
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    // An integer that fits: get<int>() converts a float such as 1e300 (or
    // an integer beyond int) without a check, undefined for the float.
    using Limits = std::numeric_limits<T>;
    if (v.is_number_unsigned() && v.get<uint64_t>() <= static_cast<uint64_t>(Limits::max())) {
      return static_cast<T>(v.get<uint64_t>());
    }
    if (v.is_number_integer() && !v.is_number_unsigned() && v.get<int64_t>() >= Limits::min() &&
        v.get<int64_t>() <= Limits::max()) {
      return static_cast<T>(v.get<int64_t>());
    }
    throw DataError(where + ": '" + key + "' is not an integer in range");
  } else {
    try {
      return v.get<T>();
    } catch (const Json::exception&) {
      throw DataError(where + ": '" + key + "' has the wrong type");
    }
  }
}

// A list field ("plants", "rows").
Json GetList(const Json& j, const char* key, const std::string& where) {
  Json list = Get<Json>(j, key, where);
  if (!list.is_array()) throw DataError(where + ": '" + key + "' is not a list");
  return list;
}

Bytes Layer(const Json& layers, const char* key, size_t size, const std::string& where) {
  const Json& b = layers.contains(key) ? layers.at(key) : Json();
  if (!b.is_binary()) throw DataError(where + ": layer '" + key + "' missing or not bytes");
  if (b.get_binary().size() != size) {
    throw DataError(where + ": layer '" + key + "' has " + std::to_string(b.get_binary().size()) +
                    " bytes, the grid needs " + std::to_string(size));
  }
  return b.get_binary();
}

MapGrid GridFrom(const Json& j, const std::string& where) {
  MapGridOptions o;
  o.resolution_m = Get<double>(j, "resolution_m", where);
  o.origin_m = {Get<double>(j, "origin_x_m", where), Get<double>(j, "origin_y_m", where)};
  o.cols = Get<int>(j, "cols", where);
  o.rows = Get<int>(j, "rows", where);
  const OptionErrors errors = o.Validate();
  if (!errors.empty()) throw DataError(where + "." + errors[0].key + ": " + errors[0].reason);
  return MapGrid(o);
}

MapPlant PlantFrom(const Json& j, const std::string& where) {
  MapPlant p;
  p.id = Get<int64_t>(j, "id", where);
  p.position_m = {Get<double>(j, "x_m", where), Get<double>(j, "y_m", where)};
  p.kind = ParsePlantKind(Get<std::string>(j, "class", where), where);
  p.confidence = Get<double>(j, "confidence", where);
  p.radius_m = Get<double>(j, "radius_m", where);
  p.treated = Get<bool>(j, "treated", where);
  p.why = Get<std::string>(j, "why", where);
  return p;
}

MapRow RowFrom(const Json& j, const std::string& where) {
  MapRow r;
  r.index = Get<int>(j, "index", where);
  const auto x = Get<std::vector<double>>(j, "x_m", where);
  const auto y = Get<std::vector<double>>(j, "y_m", where);
  if (x.size() != y.size()) throw DataError(where + ": x_m and y_m differ in length");
  for (size_t i = 0; i < x.size(); ++i) r.points_m.emplace_back(x[i], y[i]);
  return r;
}

CropMap MapFrom(const Json& j, const std::string& name) {
  CropMap map(GridFrom(Get<Json>(j, "grid", name), name + ": grid"));
  const size_t n = map.grid().size();
  const Json layers = Get<Json>(j, "layers", name);
  const std::string lw = name + ": layers";
  map.SetLayers(
      {Layer(layers, "class", n, lw), FromU16Bytes(Layer(layers, "crop_count", 2 * n, lw)),
       FromU16Bytes(Layer(layers, "weed_count", 2 * n, lw)), Layer(layers, "treated", n, lw)});
  std::vector<MapPlant> plants;
  const Json list = GetList(j, "plants", name);
  for (size_t i = 0; i < list.size(); ++i) {
    plants.push_back(PlantFrom(list[i], name + ": plants[" + std::to_string(i) + "]"));
  }
  map.SetPlants(std::move(plants));
  const Json rows = GetList(j, "rows", name);
  for (size_t i = 0; i < rows.size(); ++i) {
    map.AddRow(RowFrom(rows[i], name + ": rows[" + std::to_string(i) + "]"));
  }
  for (const auto& [k, v] : Get<std::map<std::string, std::string>>(j, "metadata", name)) {
    map.SetMetadata(k, v);
  }
  return map;
}

struct Header {
  int version = 0;
  size_t bytes = 0;
  uint32_t crc = 0;
};

Header ParseHeader(std::istream& in, const std::string& name) {
  std::string line;
  if (!std::getline(in, line) || line.rfind(kMapFileMagic, 0) != 0) {
    throw DataError(name + ": not a plantscale map file (no '" + kMapFileMagic + "' header)");
  }
  std::istringstream fields(line.substr(std::strlen(kMapFileMagic)));
  Header h;
  std::string crc_hex;
  if (!(fields >> h.version)) throw DataError(name + ": header has no version");
  if (h.version != kMapFileVersion) {
    throw DataError(name + ": map file version " + std::to_string(h.version) +
                    " is not supported (this build reads version " +
                    std::to_string(kMapFileVersion) + ")");
  }
  std::string bytes;
  if (!(fields >> bytes >> crc_hex)) throw DataError(name + ": header is malformed: " + line);
  // Digits only: istream would read "-1" as a huge size_t, and stoul throws
  // std::invalid_argument on a non-hex checksum.
  const auto whole = [](const std::string& text, auto& value, int base) {
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, value, base);
    return ec == std::errc() && ptr == end && !text.empty() && text[0] != '-';
  };
  if (!whole(bytes, h.bytes, 10) || !whole(crc_hex, h.crc, 16)) {
    throw DataError(name + ": header is malformed: " + line);
  }
  return h;
}

}  // namespace

uint32_t Crc32(const uint8_t* data, size_t size) {
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

void WriteMap(const CropMap& map, std::ostream& out, const std::string& name) {
  const Bytes payload = Json::to_cbor(MapJson(map));
  char crc[9];
  std::snprintf(crc, sizeof crc, "%08x", Crc32(payload.data(), payload.size()));
  out << kMapFileMagic << ' ' << kMapFileVersion << ' ' << payload.size() << ' ' << crc << '\n';
  out.write(reinterpret_cast<const char*>(payload.data()),
            static_cast<std::streamsize>(payload.size()));
  out.flush();
  if (!out) throw MapIoError(name, "write failed (disk full?)");
}

CropMap ReadMap(std::istream& in, const std::string& name) {
  const Header h = ParseHeader(in, name);
  // Read in pieces: the header's size is not trusted with an allocation
  // larger than what the file holds.
  Bytes payload;
  while (payload.size() < h.bytes && in) {
    const size_t piece = std::min<size_t>(h.bytes - payload.size(), size_t{1} << 20);
    const size_t at = payload.size();
    payload.resize(at + piece);
    in.read(reinterpret_cast<char*>(payload.data() + at), static_cast<std::streamsize>(piece));
    payload.resize(at + static_cast<size_t>(in.gcount()));
  }
  if (payload.size() != h.bytes) {
    throw DataError(name + ": truncated: header promises " + std::to_string(h.bytes) +
                    " bytes, file holds " + std::to_string(payload.size()));
  }
  if (Crc32(payload.data(), payload.size()) != h.crc) {
    throw DataError(name + ": corrupt: CRC-32 of the payload does not match the header");
  }
  Json j;
  try {
    j = Json::from_cbor(payload);
  } catch (const Json::parse_error& e) {
    throw DataError(name + ": malformed CBOR payload at byte " + std::to_string(e.byte));
  } catch (const Json::exception& e) {  // e.g. an array longer than any memory (found by fuzzing)
    throw DataError(name + ": malformed CBOR payload: " + e.what());
  }
  try {
    return MapFrom(j, name);
  } catch (const Json::exception& e) {  // a field of an unexpected shape that no check names
    throw DataError(name + ": malformed map content: " + e.what());
  }
}

void SaveMap(const CropMap& map, const std::filesystem::path& path) {
  StagedFile file(path);
  std::ofstream out(file.temp_path(), std::ios::binary);
  if (!out) throw MapIoError(file.temp_path().string(), "cannot be created");
  WriteMap(map, out, file.temp_path().string());
  out.close();
  if (!out) throw MapIoError(file.temp_path().string(), "write failed (disk full?)");
  file.Commit();
}

CropMap LoadMap(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapIoError(path.string(), "cannot be opened for reading");
  return ReadMap(in, path.string());
}

bool LooksLikeMapFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string start(std::strlen(kMapFileMagic), '\0');
  in.read(start.data(), static_cast<std::streamsize>(start.size()));
  return in && start == kMapFileMagic;
}

}  // namespace plantscale::maps
