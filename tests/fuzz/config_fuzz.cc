// Fuzz target: the YAML config loaders (app/config/config_loader.h). The input is
// written to a .yaml file and loaded both as a simulator preset and as a
// camera, with the source tree's config/ as the folder of named presets
// (so `camera: thesis` resolves). Bad input may only throw ConfigError.
#include <cstdint>
#include <cstring>
#include <string_view>

#include "app/config/config_loader.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // `camera: /dev/zero` (any path with a '/') is opened as a camera file:
  // keep the fuzzer away from device and process files, which never end.
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (const char* special : {"/dev", "/proc", "/sys"}) {
    if (text.find(special) != std::string_view::npos) return 0;
  }
  const auto path = plantscale::fuzz::WriteScratch("fuzz.yaml", data, size);
  const std::filesystem::path config_dir = PLANTSCALE_SOURCE_CONFIG_DIR;
  try {
    (void)plantscale::app::LoadSimulatorPreset(path.string(), config_dir);
  } catch (const plantscale::app::ConfigError&) {
  }
  try {
    (void)plantscale::app::LoadCamera(path.string(), config_dir);
  } catch (const plantscale::app::ConfigError&) {
  }
  return 0;
}
