#pragma once
// The archive's connection and schema (maps/ internal; archive.h is the
// public entry): opening a PostgreSQL/PostGIS database or a GeoPackage
// through GDAL, the table definitions, SQL literals and the append lock.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "maps/gdal_dataset.h"

namespace plantscale::maps {

// An exclusive flock on a file beside a GeoPackage (released on destruction).
class FileLock {
 public:
  explicit FileLock(const std::string& path);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

struct ArchiveDb {
  DatasetPtr ds;
  std::string name;  // the target, password redacted
  bool postgres = false;
  std::unique_ptr<FileLock> lock;  // GeoPackage appends only
};

// Opens the archive for reading (create = false; throws MapIoError when it
// does not exist) or for an append (create = true: a missing GeoPackage is
// created, and the GeoPackage is locked before it is opened). Throws
// MapIoError naming the redacted target: refused connection, bad password,
// no PostGIS.
ArchiveDb OpenArchive(const std::string& target, bool create);

// 'text' as an SQL string literal (quotes doubled). Throws
// InvalidOptionsError for text holding a NUL byte.
std::string SqlLiteral(const std::string& text);

// Runs one SQL statement that returns no rows; throws MapIoError.
void ExecuteSql(ArchiveDb& db, const std::string& sql);
// The first column of the first row as an integer (nullopt: no row or NULL).
std::optional<int64_t> QueryInt(ArchiveDb& db, const std::string& sql);

// The archive's table `name` (archive.h), created with its fields and
// indexes when missing. Throws MapIoError.
OGRLayer& EnsureTable(ArchiveDb& db, const std::string& name);
// The table, or nullptr when the archive has none of that name.
OGRLayer* FindTable(ArchiveDb& db, const std::string& name);
// Names of every archive table, in creation order.
const std::vector<std::string>& ArchiveTables();

}  // namespace plantscale::maps
