#pragma once
// Typed failures of maps/ (the app decides exit codes):
//   MapIoError      a file or folder cannot be written or read (unwritable
//                   folder, disk full, GDAL driver failure): names the path.
//   DataError       (engine/common/options.h) the input is corrupt or
//                   malformed: names the file and the place in it.
//   InvalidOptionsError  bad options (EPSG, origin, formats): names the key.

#include <stdexcept>
#include <string>

#include "engine/common/options.h"

namespace plantscale::maps {

class MapIoError : public std::runtime_error {
 public:
  MapIoError(const std::string& path, const std::string& reason)
      : std::runtime_error(path + ": " + reason), path_(path) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace plantscale::maps
