#include "app/config/run_config.h"

#include <nlohmann/json.hpp>

#include "app/config/config_loader.h"

namespace plantscale::app {

SimRunConfig SimRunConfigOf(const std::string& preset, const std::filesystem::path& config_dir,
                            const sim::SimulatorOptions& options) {
  SimRunConfig r;
  r.preset = preset;
  r.seed = options.seed;
  r.length_m = options.length_m;
  r.image = options.render.kind == sim::ImageKind::kRgb ? "rgb" : "nir";
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(config_dir, ec);
  r.config_dir = (ec ? config_dir : absolute).lexically_normal().string();
  return r;
}

std::string RunConfigJson(const SimRunConfig& run) {
  const nlohmann::json j = {{"preset", run.preset},
                            {"seed", run.seed},
                            {"length_m", run.length_m},
                            {"image", run.image},
                            {"config_dir", run.config_dir},
                            {"crop", run.crop},
                            {"vehicle", run.vehicle}};
  return j.dump();
}

SimRunConfig ParseRunConfig(const std::string& json, const std::string& where) {
  const std::string key = "run_config";
  const nlohmann::json j = nlohmann::json::parse(json, nullptr, false);
  if (!j.is_object()) throw ConfigError(where, key, "not a JSON object: " + json);
  SimRunConfig r;
  const auto field = [&](const char* name, auto& out, bool (nlohmann::json::*is)() const noexcept) {
    const auto it = j.find(name);
    if (it == j.end()) throw ConfigError(where, key + "." + name, "missing");
    if (!((*it).*is)()) throw ConfigError(where, key + "." + name, "wrong type: " + it->dump());
    out = it->get<std::remove_reference_t<decltype(out)>>();
  };
  field("preset", r.preset, &nlohmann::json::is_string);
  field("seed", r.seed, &nlohmann::json::is_number_unsigned);
  field("length_m", r.length_m, &nlohmann::json::is_number);
  field("config_dir", r.config_dir, &nlohmann::json::is_string);
  if (j.contains("image")) field("image", r.image, &nlohmann::json::is_string);
  if (j.contains("crop")) field("crop", r.crop, &nlohmann::json::is_string);
  if (j.contains("vehicle")) field("vehicle", r.vehicle, &nlohmann::json::is_string);
  if (r.image != "nir" && r.image != "rgb") {
    throw ConfigError(where, key + ".image", "'" + r.image + "' is neither nir nor rgb");
  }
  return r;
}

sim::SimulatorOptions SimulatorOptionsOf(const SimRunConfig& run,
                                         const std::filesystem::path& config_dir) {
  sim::SimulatorOptions o = LoadSimulatorPreset(run.preset, config_dir);
  o.seed = run.seed;
  o.length_m = run.length_m;
  o.render.kind = run.image == "rgb" ? sim::ImageKind::kRgb : sim::ImageKind::kNir;
  ThrowIfInvalid("run_config (preset '" + run.preset + "')", o.Validate());
  return o;
}

}  // namespace plantscale::app
