// The learned segmenter end to end: a small model trained by the real
// optimiser (Debian's PyTorch) on simulated frames, its card, its figures on
// frames of another seed against a trivial classifier, and the C++ inference
// (OpenCV dnn) against the Python model's own logits. About a minute.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "app/config/config_loader.h"
#include "app/config/learned_model.h"
#include "app/config/photo_segmentation.h"
#include "app/sim_output.h"
#include "app/train_segmenter.h"
#include "evaluation/class_eval.h"
#include "evaluation/treatment_eval.h"

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("plantscale_learn_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Frames and labels of a short simulated pass (every 8th frame).
fs::path Simulate(const std::string& name, uint64_t seed, double length_m) {
  const fs::path out = TempDir(name);
  SimulateRequest r;
  r.options = LoadSimulatorPreset("field", DefaultConfigDir());
  r.options.seed = seed;
  r.options.length_m = length_m;
  r.out = out / "pass";
  r.image_every = 8;
  r.progress = false;
  std::ostringstream log;
  RunSimulation(r, log);
  return r.out;
}

// A .npy of float32 (the optimiser's reference logits), as a flat vector.
std::vector<float> ReadNpyF32(const fs::path& path, std::vector<int>& shape) {
  std::ifstream in(path, std::ios::binary);
  char magic[10];
  in.read(magic, 10);
  const int len = static_cast<unsigned char>(magic[8]) | (static_cast<unsigned char>(magic[9]) << 8);
  std::string header(static_cast<size_t>(len), ' ');
  in.read(header.data(), len);
  EXPECT_NE(header.find("'<f4'"), std::string::npos) << header;
  const std::string dims = header.substr(header.find('(') + 1, header.find(')') - header.find('(') - 1);
  std::istringstream ds(dims);
  size_t n = 1;
  for (std::string d; std::getline(ds, d, ',');) {
    if (d.find_first_not_of(' ') == std::string::npos) continue;
    shape.push_back(std::stoi(d));
    n *= static_cast<size_t>(shape.back());
  }
  std::vector<float> v(n);
  in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n * sizeof(float)));
  return v;
}

// A small grey model trained on frames of one seed (the real optimiser, about
// two minutes): every check of the trained model is in the one test below,
// since ctest runs each test in a process of its own.
struct Trained {
  fs::path train, held, dir;
  nlohmann::json card;
};

Trained TrainSmallModel() {
  CheckTrainingPackages();  // the suite's install step puts them there (plantscale.sh)
  Trained t{Simulate("train", 21, 6.0), Simulate("held", 22, 3.0), TempDir("model"), {}};
  TrainSegmenterRequest r;
  r.images = t.train / "frames";
  r.labels = t.train / "labels";
  r.out = t.dir / "sim.onnx";
  r.epochs = 12;
  r.seed = 5;
  r.input_width_px = 320;
  r.input_height_px = 240;
  r.validation_fraction = 0.25;
  r.width = 8;
  r.threads = 2;
  r.max_minutes = 0;  // the same model whatever the machine's load
  r.progress = false;
  r.licence = "test";
  r.reference = t.dir / "reference.npy";
  std::ostringstream log;
  t.card = nlohmann::json::parse(TrainSegmenter(r, log));
  return t;
}

void CardSaysWhatTheModelTakesAndWasTrainedOn(const Trained& t) {
  ASSERT_TRUE(fs::exists(t.dir / "sim.onnx"));
  ASSERT_TRUE(fs::exists(t.dir / "sim.json"));
  EXPECT_EQ(t.card["format"], "plantscale-segmenter");
  EXPECT_EQ(t.card["classes"], nlohmann::json({"soil", "crop", "weed"}));
  EXPECT_EQ(t.card["input"]["image"], "grey");  // the simulator's near-infrared frames
  EXPECT_EQ(t.card["input"]["width_px"], 320);
  const int photographs = t.card["training"]["photographs"];
  EXPECT_EQ(t.card["training"]["validation"].size(), static_cast<size_t>(std::lround(0.25 * photographs)));
  EXPECT_EQ(t.card["training"]["train"].size() + t.card["training"]["validation"].size(),
            static_cast<size_t>(photographs));
  EXPECT_EQ(t.card["data"]["licence"], "test");
  EXPECT_GT(t.card["validation"]["miou"].get<double>(), 0.4);
  // Nothing of the optimiser's working folder is left beside the model.
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(t.dir)) ++entries;
  EXPECT_EQ(entries, 3);  // sim.onnx, sim.json, reference.npy
}

void BeatsATrivialClassifierOnHeldBackFrames(const Trained& t) {
  ClassEvalRequest r{t.held / "frames", t.held / "labels", t.dir / "sim.onnx", false, false};
  std::ostringstream log;
  const ClassEvaluation e = EvaluateClasses(r, log);
  ASSERT_EQ(e.methods.size(), 1u);
  const ClassFigures& m = e.methods[0];
  // The trivial classifier says soil everywhere: soil IoU is the soil share,
  // crop and weed 0.
  const auto& c = m.confusion;
  const double total = static_cast<double>(e.pixels);
  const double soil_share = static_cast<double>(c[0] + c[1] + c[2]) / total;
  const double trivial_miou = soil_share / 3.0;
  EXPECT_GT(m.miou, trivial_miou + 0.25) << "model mIoU " << m.miou << ", trivial " << trivial_miou;
  EXPECT_GT(m.iou[1], 0.6) << "crop IoU";
  EXPECT_GT(m.iou[0], soil_share - 0.02) << "soil IoU";
}

void CppInferenceMatchesThePythonModel(const Trained& t) {
  const std::string first = t.card["training"]["validation"][0];
  LearnedModel model = ReadLearnedModel(t.dir / "sim.onnx");
  vision::LearnedSegmenter seg = LoadSegmenter(model);
  const cv::Mat image = ReadImage(t.train / "frames" / first);
  const cv::Mat logits = seg.Logits(vision::ResizeForModel(image, model.spec));
  std::vector<int> shape;
  const std::vector<float> ref = ReadNpyF32(t.dir / "reference.npy", shape);
  ASSERT_EQ(shape, (std::vector<int>{3, 120, 160}));
  ASSERT_EQ(logits.total(), ref.size());
  const float* ours = logits.ptr<float>();
  double max_diff = 0, max_abs = 0;
  for (size_t i = 0; i < ref.size(); ++i) {
    max_diff = std::max(max_diff, static_cast<double>(std::abs(ours[i] - ref[i])));
    max_abs = std::max(max_abs, static_cast<double>(std::abs(ref[i])));
  }
  EXPECT_GT(max_abs, 0.5);  // real logits, not zeros
  EXPECT_LT(max_diff, 1e-3 * std::max(1.0, max_abs)) << "largest |logit| " << max_abs;
}

TEST(LearnedSegmentation, TrainsOnSimulatedFramesAndRunsInCpp) {
  const Trained t = TrainSmallModel();
  {
    SCOPED_TRACE("the card");
    CardSaysWhatTheModelTakesAndWasTrainedOn(t);
  }
  {
    SCOPED_TRACE("held-back frames");
    BeatsATrivialClassifierOnHeldBackFrames(t);
  }
  {
    SCOPED_TRACE("C++ against Python");
    CppInferenceMatchesThePythonModel(t);
  }
}

// The shipped model's graph with a card that does not fit it, and a graph
// that is no ONNX: refused naming the file.
TEST(LearnedSegmentation, RefusesAModelWhoseCardDoesNotFit) {
  const fs::path shipped = DefaultConfigDir() / "models" / "peanut.onnx";
  const fs::path other = TempDir("card");
  fs::copy_file(shipped, other / "m.onnx", fs::copy_options::overwrite_existing);
  const nlohmann::json good = nlohmann::json::parse(std::ifstream(CardPath(shipped)));
  nlohmann::json card = good;
  card["output_stride"] = 4;  // the graph gives 1/2
  std::ofstream(other / "m.json") << card.dump();
  try {
    LoadSegmenter(ReadLearnedModel(other / "m.onnx"));
    FAIL() << "a card that does not fit its graph was accepted";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("m.onnx"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("output"), std::string::npos) << e.what();
  }
  std::ofstream(other / "m.onnx", std::ios::trunc) << "not a graph";
  std::ofstream(other / "m.json", std::ios::trunc) << good.dump();
  EXPECT_THROW(LoadSegmenter(ReadLearnedModel(other / "m.onnx")), DataError);
  fs::remove_all(other);
}

// The shipped simulated-crop model (config/models/field-grey, trained on
// seeds 101-103) on the vehicle, spraying weeds on a field pass of a seed it
// never saw: weed pixels are labelled weed more often than by the grid's
// rule alone, and more of the weeds touching a crop are hit with that
// crop's root dry, while no crop is hit. Measured on tuning seeds 1-6
// (docs/results/2026-12-07-learned-vehicle.md): weed pixels labelled weed
// 0.389 -> 0.491, touching weeds hit with the crop dry 51.8 -> 66.9 %.
TEST(LearnedSegmentation, TheShippedModelFindsWeedsTouchingCropsOnTheVehicle) {
  const fs::path config = DefaultConfigDir();
  TreatmentEvalOptions o;
  o.sim = LoadSimulatorPreset("field", config);
  o.sim.seed = 3;
  o.sim.length_m = 30.0;
  o.seeds = 1;
  o.profiles = LoadProfiles("", "", "field", config);
  o.treatment = ProductTreatmentOptions(*o.profiles);
  o.treatment.scheduler.mode = treatment::SprayMode::kWeed;
  const TreatmentEvaluation rule = EvaluateTreatment(o);
  o.profiles->crop.segmenter_model = (config / "models" / "field-grey.onnx").string();
  o.learned = LearnedPipelineOptions(o.profiles->crop);
  ASSERT_TRUE(o.learned.onnx) << o.learned.unreadable;
  const TreatmentEvaluation learned = EvaluateTreatment(o);
  EXPECT_EQ(learned.engine.segmenter_model, o.profiles->crop.segmenter_model);
  const TreatmentMetrics& r = rule.ours;
  const TreatmentMetrics& m = learned.ours;
  // Measured: weed pixels labelled weed 0.412 -> 0.540; 35 weeds touching
  // a crop, hit with the crop dry 54.3 -> 68.6 % (19 -> 24 of them); no
  // crop hit either way. Each bound below leaves about half that margin.
  EXPECT_GT(m.weeds_touching, 25);
  EXPECT_GT(m.weed_as_weed, r.weed_as_weed + 0.05);
  EXPECT_GT(m.weed_hit_rate_touching_crop_dry, r.weed_hit_rate_touching_crop_dry + 0.05);  // +2 weeds
  EXPECT_LE(m.crop_hit_rate, 0.02);
  // Spray-crop mode with the model: crops still all hit.
  o.treatment.scheduler.mode = treatment::SprayMode::kCrop;
  EXPECT_GE(EvaluateTreatment(o).ours.crop_hit_rate, 0.99);
}

}  // namespace
}  // namespace plantscale::app
