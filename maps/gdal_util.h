#pragma once
// GDAL plumbing shared by the exporters (maps/ internal; not for app/).

#include <cpl_error.h>

#include <filesystem>
#include <string>

namespace plantscale::maps {

// GDALAllRegister() once per process.
void EnsureGdalRegistered();

// Silences GDAL's default stderr handler for its lifetime and keeps the last
// error message, so failures are reported once, by our exception.
class GdalErrorScope {
 public:
  GdalErrorScope();
  ~GdalErrorScope();
  GdalErrorScope(const GdalErrorScope&) = delete;
  GdalErrorScope& operator=(const GdalErrorScope&) = delete;

  std::string Last() const;    // last GDAL error message, or ""
  std::string Suffix() const;  // " (GDAL: message)" or ""
};

// Throws MapIoError naming `path` with GDAL's last message.
[[noreturn]] void ThrowGdal(const std::filesystem::path& path, const std::string& what);

}  // namespace plantscale::maps
