#include "app/treatment_commands.h"

#include <functional>
#include <iostream>
#include <optional>
#include <string>

#include "app/config/config_loader.h"
#include "app/odometry_fault_options.h"
#include "app/segment_commands.h"
#include "evaluation/treatment_eval.h"
#include "evaluation/treatment_writer.h"
#include "evaluation/writer.h"

namespace plantscale::app {
namespace {

struct TreatmentArgs {
  std::string preset = "field";
  int seeds = 5;
  std::optional<int64_t> seed;
  std::optional<double> length_m;
  std::string mode = "crop";
  std::string baseline;
  std::optional<double> latency_ms;
  std::optional<double> true_latency_ms;
  double frame_lag_ms = 0.0;
  std::optional<double> tick_ms;
  std::optional<double> footprint_scale;
  std::optional<double> weed_footprint_scale;
  std::optional<double> footprint_min_half_mm;
  std::optional<double> weed_height_mm;
  std::optional<double> cell_mm;
  std::optional<double> min_crop_area_m2;
  std::optional<double> crop_size_fraction;
  std::optional<double> assoc_chi2;
  std::optional<double> sure_crop_area_m2;
  std::optional<int> majority;
  std::optional<int> weed_majority;
  std::optional<double> split_radius_m;
  std::optional<double> split_chi2;
  std::optional<double> split_cover_m;
  std::optional<double> split_clipped_reach;
  std::optional<double> fragment_reach;
  std::optional<double> fill_holes_max_fraction;
  std::optional<int> close_notches_px;
  std::optional<double> hull_gain;
  std::optional<double> soil_growth_z;
  std::optional<int> soil_growth_join_min_area_px;
  std::optional<double> soil_growth_trim_z;
  std::optional<double> size_height_sd_mm;
  std::optional<double> size_edge_loss_mm;
  std::optional<double> forward_sd_mm;
  bool no_slip_guard = false;
  OdometryFaultArgs fault;
  bool mrroc = false;
  bool no_split_merged = false;
  bool footprint_per_blob = false;
  bool footprint_at_centroid = false;
  bool footprints_stay = false;
  bool abstain_merged = false;
  bool weed_whole_box = false;
  std::optional<double> min_weed_part_mm2;
  std::optional<double> lone_crop_fraction;
  std::optional<double> own_offset_along;
  std::optional<double> own_offset_across;
  bool clipped_on_crop_votes_weed = false;
  bool uncertainty_fail_safe = true;
  std::optional<double> uncertainty_margin_mm;
  double costs_ratio = 1.0;
  bool json = false;
  ProfileArgs profiles;
};

// The treatment options the command line changes (each flag only when given).
void ApplyTreatmentArgs(const TreatmentArgs& a, treatment::TreatmentOptions& t) {
  treatment::ParseSprayMode(a.mode, t.scheduler.mode);
  if (a.latency_ms) t.scheduler.bar.valve_latency_s = *a.latency_ms / 1000.0;
  if (a.tick_ms) t.scheduler.tick_s = *a.tick_ms / 1000.0;
  if (a.footprint_scale) t.crop_footprint_scale = *a.footprint_scale;
  if (a.weed_footprint_scale) t.weed_footprint_scale = *a.weed_footprint_scale;
  if (a.footprint_min_half_mm) t.crop_footprint_min_half_m = 1e-3 * *a.footprint_min_half_mm;
  if (a.weed_height_mm) t.weed_height_m = 1e-3 * *a.weed_height_mm;
  if (a.cell_mm) t.map.cell_m = *a.cell_mm / 1000.0;
  if (a.majority) t.map.majority_threshold = *a.majority;
  if (a.weed_majority) t.map.weed_majority_threshold = *a.weed_majority;
  if (a.no_split_merged) t.split_merged = false;
  if (a.footprint_per_blob) t.crop_footprint_per_plant = false;
  if (a.footprint_at_centroid) t.crop_footprint_at_tracked_plant = false;
  if (a.footprints_stay) t.crop_footprint_follows_plant = false;
  if (a.abstain_merged) t.abstain_merged = true;
  if (a.weed_whole_box) t.merged_weed_parts_only = false;
  if (a.own_offset_along) t.own_offset_fraction_along = *a.own_offset_along;
  if (a.own_offset_across) t.own_offset_fraction_across = *a.own_offset_across;
  if (a.min_weed_part_mm2) t.min_weed_part_m2 = *a.min_weed_part_mm2 * 1e-6;
  if (a.clipped_on_crop_votes_weed) t.clipped_on_crop_votes_weed = true;
  t.close_on_uncertainty = a.uncertainty_fail_safe;
  if (a.uncertainty_margin_mm) {
    t.uncertainty_margin_across_m = *a.uncertainty_margin_mm * 1e-3;
    t.uncertainty_margin_along_m = *a.uncertainty_margin_mm * 1e-3;
  }
}

void ApplyClassifierArgs(const TreatmentArgs& a, classify::ClassifierOptions& c) {
  if (a.min_crop_area_m2) c.min_crop_area_m2 = *a.min_crop_area_m2;
  if (a.crop_size_fraction) c.crop_size_fraction = *a.crop_size_fraction;
  if (a.assoc_chi2) c.assoc_chi2 = *a.assoc_chi2;
  if (a.sure_crop_area_m2) c.sure_crop_area_m2 = *a.sure_crop_area_m2;
  if (a.split_radius_m) c.split_radius_m = *a.split_radius_m;
  if (a.split_chi2) c.split_assoc_chi2 = *a.split_chi2;
  if (a.split_cover_m) c.split_cover_m = *a.split_cover_m;
  if (a.split_clipped_reach) c.split_clipped_reach = *a.split_clipped_reach;
  if (a.fragment_reach) c.fragment_reach = *a.fragment_reach;
  if (a.lone_crop_fraction) c.lone_crop_fraction = *a.lone_crop_fraction;
}

void ApplySegmenterArgs(const TreatmentArgs& a, vision::SegmenterOptions& s) {
  if (a.fill_holes_max_fraction) s.fill_holes_max_fraction = *a.fill_holes_max_fraction;
  if (a.close_notches_px) s.close_notches_px = *a.close_notches_px;
  if (a.hull_gain) s.hull_gain = *a.hull_gain;
  if (a.soil_growth_z) s.soil_growth.z = *a.soil_growth_z;
  if (a.soil_growth_join_min_area_px) s.soil_growth.join_min_area_px = *a.soil_growth_join_min_area_px;
  if (a.soil_growth_trim_z) s.soil_growth.trim_z = *a.soil_growth_trim_z;
}

// The tracker options the command line changes; empty when it changes none.
std::function<void(tracking::TrackerOptions&)> TrackerAdjustment(const TreatmentArgs& a) {
  if (!(a.size_height_sd_mm || a.size_edge_loss_mm || a.forward_sd_mm || a.no_slip_guard)) return {};
  return [a](tracking::TrackerOptions& t) {
    if (const auto& sd = a.size_height_sd_mm) {
      t.height_from_size = *sd > 0.0;
      if (*sd > 0.0) t.size_height_sd_m = *sd * 1e-3;
    }
    if (a.size_edge_loss_mm) t.size_edge_loss_m = *a.size_edge_loss_mm * 1e-3;
    if (a.no_slip_guard) t.slip_guard.enabled = false;
    if (a.forward_sd_mm) t.forward_sd_per_sqrt_m = *a.forward_sd_mm * 1e-3;
  };
}

TreatmentEvalOptions TreatmentEvalOptionsFrom(const TreatmentArgs& a, const GlobalOptions& global) {
  TreatmentEvalOptions o;
  o.sim = LoadSimulatorPreset(a.preset, global.ConfigDir());
  if (a.seed) o.sim.seed = static_cast<uint64_t>(*a.seed);
  if (a.length_m) o.sim.length_m = *a.length_m;
  o.seeds = a.seeds;
  o.profiles = LoadProfiles(a.profiles.crop, a.profiles.vehicle, o.sim.preset, global.ConfigDir());
  ApplySegmenterModelArg(a.profiles, global.ConfigDir(), *o.profiles);
  PrintProfileWarnings(*o.profiles, std::cerr);
  o.calibration_error = ParseCalibrationError(a.profiles.calibration_error, "--calibration-error");
  o.calibration_error_text = a.profiles.calibration_error;
  o.treatment = ProductTreatmentOptions(*o.profiles);
  o.learned = LearnedPipelineOptions(o.profiles->crop);
  if (o.learned.enabled()) {
    // An evaluation measures with the model it was asked for, or not at all.
    try {
      if (!o.learned.unreadable.empty()) throw DataError(o.learned.unreadable);
      vision::LearnedSegmenter loads(*o.learned.onnx, o.learned.spec);
    } catch (const std::exception& e) {
      throw ConfigError(o.learned.source, "segmenter model", std::string("not loaded: ") + e.what());
    }
  }
  ApplyTreatmentArgs(a, o.treatment);
  ApplyClassifierArgs(a, o.treatment.classifier);
  ApplySegmenterArgs(a, o.segmenter);
  if (a.true_latency_ms) o.true_valve_latency_s = *a.true_latency_ms / 1000.0;
  o.frame_lag_s = a.frame_lag_ms / 1000.0;
  o.baseline_thesis = a.baseline == "thesis";
  o.mrroc = a.mrroc;
  o.adjust_tracker = TrackerAdjustment(a);
  o.costs_ratio = a.costs_ratio;
  o.odometry_fault = ToOdometryFault(a.fault);
  o.visual_motion = a.fault.visual_motion;
  return o;
}

int EvaluateTreatmentCommand(const TreatmentArgs& a, const GlobalOptions& global) {
  WriteEvaluation(EvaluateTreatment(TreatmentEvalOptionsFrom(a, global)), a.json, std::cout);
  return 0;
}

// The defaults evaluate treatment keeps from TreatmentOptions (the crop and
// vehicle profiles set the others), printed in --help from the code.
const treatment::TreatmentOptions kDefaults{};
// ProductTrackerOptions (profiles.cc) leaves these three at the tracker's own.
const tracking::TrackerOptions kTrackerDefaults{};

// The bar: what is sprayed, valve timing and the fail-safe.
void AddSprayingOptions(CLI::App* cmd, TreatmentArgs& args) {
  cmd->option_defaults()->group("Spraying");
  cmd->add_option("--mode", args.mode, "what is sprayed: crop or weed")
      ->check(CLI::IsMember({"crop", "weed"}))->capture_default_str();
  cmd->add_option("--latency-ms", args.latency_ms, "valve latency the scheduler leads by")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--true-latency-ms", args.true_latency_ms,
                  "the simulated valves' latency (default: as scheduled)")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--frame-lag-ms", args.frame_lag_ms,
                  "each frame reaches the pipeline this long after its capture, after the "
                  "odometry up to then (camera and segmentation latency)")
      ->check(CLI::Range(0.0, 150.0))->capture_default_str();
  cmd->add_option("--tick-ms", args.tick_ms,
                  "spray bar command period, at most the 20 ms pose period (default " +
                      HelpNumber(1e3 * kDefaults.scheduler.tick_s) + ")")
      ->check(CLI::Range(1.0, 20.0));
  cmd->add_flag("--uncertainty-fail-safe,!--no-uncertainty-fail-safe", args.uncertainty_fail_safe,
                "the bar closes on the plants' uncertain position at the bar (docs/fail-safe.md; on by default)");
  cmd->add_option("--uncertainty-margin-mm", args.uncertainty_margin_mm,
                  "the fail-safe on uncertainty's margin along and across (default: from the crop footprint)")
      ->check(CLI::NonNegativeNumber);
}

// Where a plant is sprayed: its footprint and the map cells.
void AddFootprintOptions(CLI::App* cmd, TreatmentArgs& args) {
  cmd->option_defaults()->group("Footprints");
  cmd->add_option("--footprint-scale", args.footprint_scale,
                  "crop footprint: bounding box scaled about the centroid (1: thesis)")
      ->check(CLI::Range(0.05, 2.0));
  cmd->add_option("--weed-footprint-scale", args.weed_footprint_scale,
                  "weed footprint: bounding box scaled about the centroid (default " +
                      HelpNumber(kDefaults.weed_footprint_scale) + ")")
      ->check(CLI::Range(0.05, 2.0));
  cmd->add_option("--footprint-min-half-mm", args.footprint_min_half_mm,
                  "crop footprint: stretched to at least this half size along and across")
      ->check(CLI::Range(0.0, 500.0));
  cmd->add_option("--weed-height-mm", args.weed_height_mm,
                  "height at which weed blobs are located (default " + HelpNumber(1e3 * kDefaults.weed_height_m) + ")")
      ->check(CLI::Range(0.0, 500.0));
  cmd->add_option("--cell-mm", args.cell_mm, "treatment map cell size (default " + HelpNumber(1e3 * kDefaults.map.cell_m) + ")")
      ->check(CLI::Range(1.0, 500.0));
  cmd->add_flag("--footprint-per-blob", args.footprint_per_blob,
                "every crop blob its own footprint (not one per predicted plant)");
  cmd->add_flag("--footprint-at-centroid", args.footprint_at_centroid,
                "centre a plant's footprint on this frame's centroid, not where the tracker holds it");
  cmd->add_option("--own-offset-along", args.own_offset_along,
                  "crop footprint: at the plant's grid node plus this fraction of its own offset along the rows (default " +
                      HelpNumber(kDefaults.own_offset_fraction_along) + ")")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--own-offset-across", args.own_offset_across,
                  "... and across the rows (default " + HelpNumber(kDefaults.own_offset_fraction_across) + ")")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--footprints-stay", args.footprints_stay,
                "a plant's footprints stay where each frame put them (not moved along with its latest position)");
}

// Crop or weed: the size filter, association and merged blobs.
void AddClassifierOptions(CLI::App* cmd, TreatmentArgs& args) {
  cmd->option_defaults()->group("Classifier");
  cmd->add_option("--min-crop-area-m2", args.min_crop_area_m2, "classifier size filter")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--crop-size-fraction", args.crop_size_fraction,
                  "size filter at most this fraction of the crops' median area (0: fixed)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--assoc-chi2", args.assoc_chi2, "classifier association region (chi2)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--sure-crop-area-m2", args.sure_crop_area_m2,
                  "blobs this big are crop without association (merged plants)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--weed-majority", args.weed_majority, "votes a weed cell needs (0: as --majority)")
      ->check(CLI::Range(0, 10000));
  cmd->add_option("--majority", args.majority, "votes a map cell needs")
      ->check(CLI::Range(1, 10000));
  cmd->add_option("--split-radius-m", args.split_radius_m,
                  "merged blobs: a pixel joins the nearest predicted crop this close");
  cmd->add_option("--split-chi2", args.split_chi2,
                  "merged blobs: association gate of each part's centroid (chi2)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--split-cover-m", args.split_cover_m,
                  "merged blobs: a part with plant matter this close to its predicted crop is "
                  "that crop (0: the gate alone)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--fragment-reach", args.fragment_reach,
                  "a blob under the size filter within this many crop radii of a crop found in "
                  "the same frame is that crop's leaf (0: off, weed)")
      ->check(CLI::Range(0.0, 5.0));
  cmd->add_option("--split-clipped-reach", args.split_clipped_reach,
                  "merged blobs cut by the image border: a part with plant matter within this "
                  "many crop radii of its predicted crop is that crop (0: as an uncut blob)")
      ->check(CLI::Range(0.0, 5.0));
  cmd->add_flag("--weed-whole-box", args.weed_whole_box,
                "merged blobs vote weed with their whole box (the old way), not only their weed parts");
  cmd->add_option("--lone-crop-fraction", args.lone_crop_fraction,
                  "a blob under the size filter but at least this fraction of it, alone in a predicted crop's region, is that crop (0: off)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--min-weed-part-mm2", args.min_weed_part_mm2,
                  "smallest part of a blob (ground mm^2) that votes weed on its own")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_flag("--abstain-merged", args.abstain_merged,
                "unassociated blobs covering a predicted crop cast no weed votes");
  cmd->add_flag("--clipped-on-crop-votes-weed", args.clipped_on_crop_votes_weed,
                "blobs cut by the image border that cover a predicted crop vote weed (the old way)");
  cmd->add_flag("--no-split-merged", args.no_split_merged,
                "map and label merged blobs whole (no split among predicted crops)");
}

// Plant matter from soil before classification.
void AddSegmentationOptions(CLI::App* cmd, TreatmentArgs& args) {
  cmd->option_defaults()->group("Segmentation");
  cmd->add_option("--fill-holes-max-fraction", args.fill_holes_max_fraction,
                  "segmentation: holes up to this fraction of the image are filled (0: none)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--close-notches-px", args.close_notches_px,
                  "segmentation: notches narrower than a disk of this radius are closed (0: none)")
      ->check(CLI::Range(0, 30));
  cmd->add_option("--hull-gain", args.hull_gain,
                  "segmentation: inside a blob's convex hull, plant at this lower local gain (0: off)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--soil-growth-z", args.soil_growth_z,
                  "segmentation: blobs grow into pixels this many soil sds above the soil around "
                  "them (0: off)")
      ->check(CLI::Range(0.0, 20.0));
  cmd->add_option("--soil-growth-join-min-area-px", args.soil_growth_join_min_area_px,
                  "segmentation: soil growth joins blobs only when each has this many pixels "
                  "(0: any; spray-weed mode joins none)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--soil-growth-trim-z", args.soil_growth_trim_z,
                  "segmentation: soil growth leaves soil samples this many sds above the soil out "
                  "(0: keeps all)")
      ->check(CLI::Range(0.0, 20.0));
}

// The product tracker's options the profiles leave at their defaults.
void AddTrackerOptions(CLI::App* cmd, TreatmentArgs& args) {
  cmd->option_defaults()->group("Tracker");
  cmd->add_option("--size-height-sd-mm", args.size_height_sd_mm,
                  "tracker: sd per frame of a plant's centroid height read from its blob's size (0: not read; default " +
                      HelpNumber(1e3 * kTrackerDefaults.size_height_sd_m) + ")")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--size-edge-loss-mm", args.size_edge_loss_mm,
                  "tracker: the rim a plant's blob loses, for its size (default " +
                      HelpNumber(1e3 * kTrackerDefaults.size_edge_loss_m) + ")")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_flag("--no-slip-guard", args.no_slip_guard,
                "tracker: take the wheels' speeds as they come (no wheel spin or lock read from jumps)");
  cmd->add_option("--forward-sd-mm", args.forward_sd_mm,
                  "tracker: forward process noise, mm per square-root metre driven (default " +
                      HelpNumber(1e3 * kTrackerDefaults.forward_sd_per_sqrt_m) + ")")
      ->check(CLI::Range(0.0, 1000.0));
}
}  // namespace

void AddTreatmentCommands(CommandRegistry& registry) {
  const GlobalOptions& global = registry.global();
  TreatmentArgs& args = registry.Keep(TreatmentArgs{});
  CLI::App* cmd = registry.Add(
      "treatment", "crop/weed classification, treatment map and spraying against truth",
      [&args, &global] { return EvaluateTreatmentCommand(args, global); },
      EvaluateCommand(registry));
  AddRunOptions(cmd, args.preset, args.seeds, args.seed, &args.length_m);
  AddProfileOptions(cmd, args.profiles, true);
  cmd->add_option("--baseline", args.baseline, "also run the thesis's chain")
      ->check(CLI::IsMember({"thesis"}));
  cmd->add_flag("--mrroc", args.mrroc, "sweep the classifier's two parameters (MRROC)");
  cmd->add_option("--costs-ratio", args.costs_ratio, "cost ratio for the MRROC operating point")
      ->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_flag("--json", args.json, "print one JSON object");
  AddSprayingOptions(cmd, args);
  AddFootprintOptions(cmd, args);
  AddClassifierOptions(cmd, args);
  AddSegmentationOptions(cmd, args);
  AddTrackerOptions(cmd, args);
  cmd->option_defaults()->group("Odometry faults");
  AddOdometryFaultOptions(cmd, args.fault);
}

}  // namespace plantscale::app
