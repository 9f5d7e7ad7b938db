#include "app/learning_commands.h"

#include <iostream>
#include <sstream>

#include "app/segment_commands.h"
#include "app/train_segmenter.h"
#include "engine/common/options.h"
#include "evaluation/class_eval.h"
#include "evaluation/writer.h"

namespace plantscale::app {
namespace {

struct TrainArgs {
  TrainSegmenterRequest request;
  std::string images, labels, out, input_size = "512x384", reference;
  bool quiet = false;
};

std::string Quote(const std::string& s) {
  if (s.find_first_of(" \t'\"$\\") == std::string::npos && !s.empty()) return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

int TrainCommand(TrainArgs& a) {
  TrainSegmenterRequest r = a.request;
  r.images = a.images;
  r.labels = a.labels;
  r.out = a.out;
  r.progress = !a.quiet;
  r.reference = a.reference;
  // The command that makes this model again (every setting spelt out).
  std::ostringstream command;
  command << "plantscale train-segmenter --images " << Quote(a.images) << " --labels " << Quote(a.labels)
          << " --out " << Quote(a.out) << " --epochs " << r.epochs << " --seed " << r.seed << " --input-size "
          << a.input_size << " --validation-fraction " << r.validation_fraction << " --width " << r.width
          << " --output-stride " << r.output_stride << " --max-minutes " << r.max_minutes;
  if (!r.licence.empty()) command << " --licence " << Quote(r.licence);
  if (!r.attribution.empty()) command << " --attribution " << Quote(r.attribution);
  r.command_line = command.str();
  try {
    const cv::Size size = ParseInputSize(a.input_size);
    r.input_width_px = size.width;
    r.input_height_px = size.height;
    TrainSegmenter(r, std::cerr);
  } catch (const MissingPackagesError& e) {
    std::cerr << "plantscale train-segmenter: " << e.what() << '\n';
    return 2;
  } catch (const DataError& e) {
    std::cerr << "plantscale train-segmenter: error: " << e.what() << '\n';
    return 2;
  }
  std::cout << "plantscale train-segmenter: wrote " << r.out.string() << " and "
            << std::filesystem::path(r.out).replace_extension(".json").string() << '\n';
  return 0;
}

struct ClassArgs {
  std::string images, labels, model;
  bool json = false, quiet = false, no_size_rule = false;
};

int ClassesCommand(const ClassArgs& a) {
  ClassEvalRequest r{a.images, a.labels, a.model, !a.no_size_rule, !a.quiet};
  ClassEvaluation e;
  try {
    e = EvaluateClasses(r, std::cerr);
  } catch (const DataError& x) {
    std::cerr << "plantscale evaluate classes: error: " << x.what() << '\n';
    return 2;
  }
  WriteEvaluation(e, a.json, std::cout);
  return 0;
}

}  // namespace

void AddLearningCommands(CommandRegistry& registry) {
  TrainArgs& t = registry.Keep(TrainArgs{});
  CLI::App* train = registry.Add(
      "train-segmenter",
      "a crop/weed/soil model from labelled photographs (CPU, Debian's PyTorch; writes MODEL.onnx and MODEL.json)",
      [&t] { return TrainCommand(t); });
  train->add_option("--images", t.images, "folder of photographs (PNG/JPEG; colour or grey)")->required();
  train->add_option("--labels", t.labels,
                    "folder of labels: NAME.png per photograph NAME, single-channel, 0 soil, 1 crop, 2 weed")
      ->required();
  train->add_option("--out", t.out, "the model to write (MODEL.onnx; its card MODEL.json beside it)")->required();
  train->add_option("--epochs", t.request.epochs, "passes over the training photographs (4 random crops each)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  train->add_option("--seed", t.request.seed, "the split, the initial weights and the crops")->capture_default_str();
  train->add_option("--input-size", t.input_size,
                    "WxH the photographs are resized to, multiples of 16 (the vehicle resizes alike)")
      ->capture_default_str();
  train->add_option("--validation-fraction", t.request.validation_fraction,
                    "share of the photographs held back to choose the best epoch and report its figures")
      ->check(CLI::Range(0.0, 0.9))
      ->capture_default_str();
  train->add_option("--width", t.request.width, "the network's channels at its first scale (x2, x3, x4 deeper)")
      ->check(CLI::Range(4, 64))
      ->capture_default_str();
  train->add_option("--output-stride", t.request.output_stride,
                    "2: logits at half the input's resolution; 1: a last stage at the input's resolution, for "
                    "plants a few pixels across (a quarter more work)")
      ->check(CLI::IsMember({1, 2}))
      ->capture_default_str();
  train->add_option("--threads", t.request.threads, "CPU threads for training (0: every core)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  train->add_option("--max-minutes", t.request.max_minutes,
                    "time budget: when the epochs would not fit, training anneals by time and ends within it (0: none)")
      ->check(CLI::Range(0.0, 100000.0))
      ->capture_default_str();
  train->add_option("--licence", t.request.licence, "the photographs' licence, into the model's card");
  train->add_option("--attribution", t.request.attribution, "the photographs' attribution, into the model's card");
  train->add_option("--reference", t.reference,
                    "also write the trained network's logits on the first validation photograph (.npy; tests)");
  train->add_flag("--quiet", t.quiet, "no progress bar");

  ClassArgs& c = registry.Keep(ClassArgs{});
  CLI::App* classes = registry.Add(
      "classes", "soil, crop and weed IoU of a learned model on labelled photographs, beside the size rule",
      [&c] { return ClassesCommand(c); }, EvaluateCommand(registry));
  classes->add_option("--images", c.images, "folder of photographs")->required();
  classes->add_option("--labels", c.labels, "folder of labels (NAME.png: 0 soil, 1 crop, 2 weed)")->required();
  classes->add_option("--model", c.model, "the model (MODEL.onnx, MODEL.json beside it); none: the size rule only");
  classes->add_flag("--no-size-rule", c.no_size_rule, "leave the size rule out");
  classes->add_flag("--json", c.json, "print one JSON object");
  classes->add_flag("--quiet", c.quiet, "no progress bar");
}

}  // namespace plantscale::app
