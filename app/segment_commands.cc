#include "app/segment_commands.h"

#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "app/config/config_loader.h"
#include "app/config/photo_segmentation.h"
#include "app/config/profiles.h"
#include "evaluation/segmentation_eval.h"
#include "evaluation/segmentation_writer.h"
#include "evaluation/writer.h"

namespace plantscale::app {
namespace {

struct EvaluateArgs {
  ProfileArgs profiles;  // validated; segmentation uses no profile setting (no camera geometry)
  std::string preset = "C";
  int seeds = 3;
  int frames = 10;
  std::optional<int64_t> seed;
  std::string image;
  bool json = false;
  std::string roc_csv;
  std::string baseline;
  double costs_ratio = 3.644;
  std::string method = "local";
  std::string index;  // colour index for rgb frames (default: the segmenter's)
  double gain = 0.0;
  double smoothing_px = -1.0;
  double fill_holes_max_fraction = -1.0;
  int close_notches_px = -1;
  double hull_gain = -1.0;
  double soil_growth_z = -1.0;
  int soil_growth_join_min_area_px = -1;
  double soil_growth_trim_z = -1.0;
  int soil_growth_reach_px = -1;
  std::string errors_dir;
};

int EvaluateSegmentationCommand(const EvaluateArgs& a, const GlobalOptions& global) {
  SegmentationEvalOptions o;
  o.sim = LoadSimulatorPreset(a.preset, global.ConfigDir());
  if (a.seed) o.sim.seed = static_cast<uint64_t>(*a.seed);
  if (a.image == "rgb") o.sim.render.kind = sim::ImageKind::kRgb;
  if (a.image == "nir") o.sim.render.kind = sim::ImageKind::kNir;
  // The engine's profiles: the segmenter needs none of their settings, but
  // they are read and checked as for every evaluate (bad profiles exit 2).
  const Profiles profiles =
      LoadProfiles(a.profiles.crop, a.profiles.vehicle, o.sim.preset, global.ConfigDir());
  RequireImageSize(profiles.vehicle, o.sim.camera.image_width_px, o.sim.camera.image_height_px);
  o.seeds = a.seeds;
  o.frames_per_seed = a.frames;
  o.costs_ratio = a.costs_ratio;
  o.segmenter.method = *vision::ParseThresholdMethod(a.method);
  if (a.gain > 0) {
    o.segmenter.local.gain = a.gain;
    o.segmenter.adaptive_gain = a.gain;
    o.segmenter.fixed_threshold = a.gain;
  }
  if (a.smoothing_px >= 0) o.segmenter.smoothing_px = a.smoothing_px;
  if (a.fill_holes_max_fraction >= 0) o.segmenter.fill_holes_max_fraction = a.fill_holes_max_fraction;
  if (a.close_notches_px >= 0) o.segmenter.close_notches_px = a.close_notches_px;
  if (a.hull_gain >= 0) o.segmenter.hull_gain = a.hull_gain;
  if (a.soil_growth_z >= 0) o.segmenter.soil_growth.z = a.soil_growth_z;
  if (a.soil_growth_join_min_area_px >= 0) {
    o.segmenter.soil_growth.join_min_area_px = a.soil_growth_join_min_area_px;
  }
  if (a.soil_growth_trim_z >= 0) o.segmenter.soil_growth.trim_z = a.soil_growth_trim_z;
  if (a.soil_growth_reach_px >= 0) o.segmenter.soil_growth.reach_px = a.soil_growth_reach_px;
  o.errors_dir = a.errors_dir;
  if (!a.index.empty()) o.segmenter.colour_index = *vision::ParseColourIndex(a.index);
  o.crop = profiles.crop.name;
  o.vehicle = profiles.vehicle.name;
  o.published_thesis = a.baseline == "thesis";
  const SegmentationEvaluation e = EvaluateSegmentation(o);
  if (!a.roc_csv.empty()) WriteRocCsv(a.roc_csv, e);
  WriteEvaluation(e, a.json, std::cout);
  return 0;
}

int SegmentCommand(const SegmentPhotosRequest& request, bool json) {
  SegmentPhotosResult r;
  try {
    r = SegmentPhotos(request, std::cerr);
  } catch (const DataError& e) {  // the model: nothing was segmented
    std::cerr << "plantscale segment: error: " << e.what() << '\n';
    return 2;
  }
  for (const std::string& e : r.errors) std::cerr << "plantscale segment: error: " << e << '\n';
  const bool print_json = json && !request.model.empty();
  std::ostream& said = print_json ? std::cerr : std::cout;  // with --json, standard output is the JSON alone
  said << "plantscale segment: " << r.images << " image(s) segmented into " << request.out.string() << "/";
  if (r.failed > 0) said << ", " << r.failed << " failed";
  said << '\n';
  if (print_json) {
    nlohmann::json photos = nlohmann::json::array();
    for (const PhotoClassFractions& f : r.fractions) {
      photos.push_back({{"name", f.name}, {"width_px", f.width_px}, {"height_px", f.height_px},
                        {"crop_fraction", f.crop}, {"weed_fraction", f.weed}});
    }
    std::cout << nlohmann::json{{"model", request.model.string()}, {"photographs", photos}}.dump(2) << '\n';
  }
  return r.failed > 0 ? 1 : 0;
}

}  // namespace

CLI::App* EvaluateCommand(CommandRegistry& registry) {
  const auto named = [](CLI::App* c) { return c->get_name() == "evaluate"; };
  for (CLI::App* existing : registry.cli().get_subcommands(named)) return existing;
  CLI::App* evaluate = registry.Add("evaluate", "measure accuracy on simulator presets", nullptr);
  evaluate->require_subcommand(1);
  return evaluate;
}

void AddSegmentCommands(CommandRegistry& registry) {
  const GlobalOptions& global = registry.global();
  SegmentPhotosRequest& seg = registry.Keep(SegmentPhotosRequest{});
  std::string& seg_out = registry.Keep(std::string{});
  std::vector<std::string>& seg_inputs = registry.Keep(std::vector<std::string>{});
  bool& seg_quiet = registry.Keep(false);
  bool& seg_json = registry.Keep(false);
  std::string& seg_model = registry.Keep(std::string{});
  CLI::App* segment = registry.Add(
      "segment", "plant masks and blob lists for photographs (PNG/JPEG, colour or NIR)", [&] {
        seg.inputs.assign(seg_inputs.begin(), seg_inputs.end());
        seg.out = seg_out;
        seg.progress = !seg_quiet;
        seg.model = seg_model;
        return SegmentCommand(seg, seg_json);
      });
  segment->add_option("inputs", seg_inputs, "image files or folders of images")->required();
  segment->add_option("--out", seg_out, "output folder (NAME_mask.png, NAME_blobs.csv; with --model NAME_classes.png, NAME_overlay.png)")
      ->required();
  segment->add_option("--method", seg.method,
                      "auto (colour: exg, grey: nir), exg (excess green + Otsu), nir (local "
                      "soil-level threshold), adaptive (thesis eq. 2.15)")
      ->check(CLI::IsMember({"auto", "exg", "nir", "adaptive"}))
      ->capture_default_str();
  segment->add_option("--index", seg.index, "colour index for colour photographs")
      ->check(CLI::IsMember({"exg", "exgr", "cive"}))
      ->capture_default_str();
  segment->add_option("--min-area-px", seg.min_area_px,
                      "drop smaller blobs (default: 1e-5 of the image, at least 4)")
      ->check(CLI::NonNegativeNumber);
  segment->add_flag("--quiet", seg_quiet, "no progress bar");
  segment->add_option("--model", seg_model,
                      "a learned crop/weed model (MODEL.onnx, its card MODEL.json beside it): writes "
                      "NAME_classes.png (0 soil, 1 crop, 2 weed) and NAME_overlay.png instead");
  segment->add_flag("--json", seg_json, "with --model: print each photograph's crop and weed fractions as JSON");

  EvaluateArgs& ev = registry.Keep(EvaluateArgs{});
  CLI::App* cmd = registry.Add(
      "segmentation", "plant/soil pixel accuracy, ROC and AUC against simulator truth",
      [&ev, &global] { return EvaluateSegmentationCommand(ev, global); },
      EvaluateCommand(registry));
  AddRunOptions(cmd, ev.preset, ev.seeds, ev.seed);
  AddProfileOptions(cmd, ev.profiles, false);
  cmd->add_option("--frames", ev.frames, "non-overlapping frames per seed")
      ->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--image", ev.image, "nir or rgb (default: the preset's)")
      ->check(CLI::IsMember({"nir", "rgb"}));
  cmd->add_option("--costs-ratio", ev.costs_ratio, "Φ of thesis eq. 2.23 for baselines")
      ->capture_default_str();
  cmd->add_flag("--json", ev.json, "print one JSON object");
  cmd->add_option("--method", ev.method, "the method evaluated as ours")
      ->check(CLI::IsMember({"fixed", "otsu", "adaptive", "local"}))
      ->capture_default_str();
  cmd->add_option("--index", ev.index, "colour index of rgb frames (default: exg)")
      ->check(CLI::IsMember({"exg", "exgr", "cive"}));
  cmd->add_option("--gain", ev.gain, "its operating parameter (α, or τ for fixed)");
  cmd->add_option("--smoothing-px", ev.smoothing_px, "its smoothing sigma, pixels");
  cmd->add_option("--fill-holes-max-fraction", ev.fill_holes_max_fraction,
                  "holes up to this fraction of the image are filled (0: none)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--close-notches-px", ev.close_notches_px,
                  "notches narrower than a disk of this radius are closed (0: none)")
      ->check(CLI::Range(0, 30));
  cmd->add_option("--hull-gain", ev.hull_gain,
                  "inside a blob's convex hull, plant at this lower local gain (0: off)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--soil-growth-z", ev.soil_growth_z,
                  "blobs grow into pixels this many soil sds above the soil around them (0: off)")
      ->check(CLI::Range(0.0, 20.0));
  cmd->add_option("--soil-growth-join-min-area-px", ev.soil_growth_join_min_area_px,
                  "soil growth joins blobs only when each has this many pixels (0: any)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--soil-growth-trim-z", ev.soil_growth_trim_z,
                  "soil growth: leave soil samples this many sds above the soil out (0: keep all)")
      ->check(CLI::Range(0.0, 20.0));
  cmd->add_option("--soil-growth-reach-px", ev.soil_growth_reach_px,
                  "soil growth: at most this many pixels from a blob")
      ->check(CLI::Range(1, 50));
  cmd->add_option("--roc-csv", ev.roc_csv, "write the ROC curve to this CSV file");
  cmd->add_option("--errors-dir", ev.errors_dir,
                  "write each frame's errors there as PNG (missed plant red, soil taken blue)");
  cmd->add_option("--baseline", ev.baseline, "also report the thesis's baselines")
      ->check(CLI::IsMember({"thesis"}));
}

}  // namespace plantscale::app
