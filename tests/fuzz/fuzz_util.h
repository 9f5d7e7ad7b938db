#pragma once
// Helpers shared by the fuzz targets (docs/fuzzing.md): a scratch file for
// the readers that take a path, and the rule every target follows — the
// error type that the code documents for bad input is the expected outcome;
// any other exception escapes and libFuzzer reports it as a crash.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace plantscale::fuzz {

// A folder of its own under $TMPDIR for this process, removed at exit.
inline const std::filesystem::path& ScratchDir() {
  static const std::filesystem::path dir = [] {
    std::filesystem::path d = std::filesystem::temp_directory_path() /
                              ("plantscale-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(ScratchDir(), ec);
    });
    return d;
  }();
  return dir;
}

// Writes `size` bytes to ScratchDir()/name and returns the path.
inline std::filesystem::path WriteScratch(const std::string& name, const uint8_t* data, size_t size) {
  const std::filesystem::path path = ScratchDir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

// An invariant of the code under test does not hold: a crash for libFuzzer.
[[noreturn]] inline void Fail(const char* what) {
  std::fprintf(stderr, "fuzz: invariant violated: %s\n", what);
  std::abort();
}

}  // namespace plantscale::fuzz
