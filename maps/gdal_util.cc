#include "maps/gdal_util.h"

#include <gdal.h>

#include <mutex>

#include "maps/map_errors.h"

namespace plantscale::maps {

void EnsureGdalRegistered() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
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
