#pragma once
// Writes that never leave a half-written file in place of a good one: every
// file is written under a temporary name in the same folder (same file
// system, so rename(2) is atomic) and renamed into place once complete.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace plantscale::maps {

// One file or folder: write it at temp_path() (beside `path`, with the same
// extension, so encoders chosen by extension still work), then Commit(),
// which replaces `path` (a folder whole) with it. The temporary is removed
// when the object dies uncommitted (an exception on the way).
class StagedFile {
 public:
  explicit StagedFile(const std::filesystem::path& path);  // throws MapIoError
  ~StagedFile();
  StagedFile(const StagedFile&) = delete;
  StagedFile& operator=(const StagedFile&) = delete;

  const std::filesystem::path& temp_path() const { return temp_; }
  void Commit();  // rename temp → path; throws MapIoError

 private:
  std::filesystem::path path_;
  std::filesystem::path temp_;
  bool committed_ = false;
};

// Writes `path` through a StagedFile: write(temp_path), then Commit().
template <typename Write>
void WriteStaged(const std::filesystem::path& path, Write&& write) {
  StagedFile staged(path);
  std::forward<Write>(write)(staged.temp_path());
  staged.Commit();
}

// Several outputs of one export: staged in a hidden folder inside `dir`,
// moved into `dir` one by one by Commit() after all were written. A failure
// before Commit() leaves `dir`'s previous files untouched.
class StagedFolder {
 public:
  explicit StagedFolder(const std::filesystem::path& dir);  // throws MapIoError
  ~StagedFolder();
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;

  // Path of `name` (a file or folder directly inside dir) in the staging area.
  std::filesystem::path Stage(const std::string& name);
  // Moves every staged entry into place; returns their final paths.
  std::vector<std::filesystem::path> Commit();

 private:
  std::filesystem::path dir_;
  std::filesystem::path staging_;
  std::vector<std::string> names_;
  bool committed_ = false;
};

}  // namespace plantscale::maps
