#include "maps/gdal_util.h"

#include <cpl_conv.h>
#include <gdal.h>

#include <cstdint>
#include <mutex>

#include "maps/map_errors.h"

namespace plantscale::maps {

// GDAL's block cache defaults to 5 % of the machine's memory, and a long
// run's rasters fill it with decompressed blocks (1.2 GB on a 24 GB
// station): 64 MB keeps an export's memory to its map plus a bounded cache,
// and rasters written and read line by line gain nothing from more.
// GDAL_CACHEMAX in the environment still wins.
constexpr int64_t kBlockCacheBytes = int64_t{64} << 20;

void EnsureGdalRegistered() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    if (CPLGetConfigOption("GDAL_CACHEMAX", nullptr) == nullptr) GDALSetCacheMax64(kBlockCacheBytes);
  });
}

GdalErrorScope::GdalErrorScope() {
  CPLPushErrorHandler(CPLQuietErrorHandler);
  CPLErrorReset();
}

GdalErrorScope::~GdalErrorScope() { CPLPopErrorHandler(); }

std::string GdalErrorScope::Last() const {
  const char* message = CPLGetLastErrorMsg();
  return message != nullptr ? message : "";
}

std::string GdalErrorScope::Suffix() const {
  const std::string last = Last();
  return last.empty() ? "" : " (GDAL: " + last + ")";
}

void ThrowGdal(const std::filesystem::path& path, const std::string& what) {
  const char* message = CPLGetLastErrorMsg();
  std::string reason = what;
  if (message != nullptr && *message != '\0') reason += " (GDAL: " + std::string(message) + ")";
  throw MapIoError(path.string(), reason);
}

}  // namespace plantscale::maps
