#include "maps/staged_output.h"

#include <unistd.h>

#include "maps/map_errors.h"

namespace plantscale::maps {
namespace fs = std::filesystem;
namespace {

std::string Suffix() { return ".partial-" + std::to_string(::getpid()); }

void MakeFolder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    throw MapIoError(dir.string(),
                     "cannot create folder: " + (ec ? ec.message() : std::string("not a folder")));
  }
}

void Replace(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  if (fs::is_directory(to) && !fs::is_directory(from)) {
    throw MapIoError(to.string(), "is a folder; will not replace it with a file");
  }
  const fs::path old = to.parent_path() / ("." + to.filename().string() + ".old" + Suffix());
  const bool had_folder = fs::is_directory(to);
  if (had_folder) fs::rename(to, old, ec);  // rename(2) cannot replace a non-empty folder
  if (!ec) fs::rename(from, to, ec);
  if (ec) throw MapIoError(to.string(), "cannot move into place: " + ec.message());
  if (had_folder) fs::remove_all(old, ec);
}

}  // namespace

StagedFile::StagedFile(const fs::path& path) : path_(fs::absolute(path)) {
  MakeFolder(path_.parent_path());
  temp_ = path_.parent_path() /
          ("." + path_.stem().string() + Suffix() + path_.extension().string());
  std::error_code ec;
  fs::remove_all(temp_, ec);  // left by an earlier process of the same id
}

StagedFile::~StagedFile() {
  std::error_code ec;
  if (!committed_) fs::remove_all(temp_, ec);
}

void StagedFile::Commit() {
  Replace(temp_, path_);
  committed_ = true;
}

StagedFolder::StagedFolder(const fs::path& dir) : dir_(fs::absolute(dir)) {
  MakeFolder(dir_);
  staging_ = dir_ / (".export" + Suffix());
  std::error_code ec;
  fs::remove_all(staging_, ec);
  MakeFolder(staging_);
}

StagedFolder::~StagedFolder() {
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

fs::path StagedFolder::Stage(const std::string& name) {
  names_.push_back(name);
  return staging_ / name;
}

std::vector<fs::path> StagedFolder::Commit() {
  std::vector<fs::path> done;
  for (const std::string& name : names_) {
    Replace(staging_ / name, dir_ / name);
    done.push_back(dir_ / name);
  }
  committed_ = true;
  return done;
}

}  // namespace plantscale::maps
