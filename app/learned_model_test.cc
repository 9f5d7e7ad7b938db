// The learned segmenter end to end: a small model trained by the real
// optimiser (Debian's PyTorch) on simulated frames, its card, its figures on
// frames of another seed against a trivial classifier, and the C++ inference
// (OpenCV dnn) against the Python model's own logits. About a minute.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "app/class_eval.h"
#include "app/config_loader.h"
#include "app/learned_model.h"
#include "app/photo_segmentation.h"
#include "app/sim_output.h"
#include "app/train_segmenter.h"

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

class LearnedSegmentation : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    CheckTrainingPackages();  // the suite's install step puts them there (plantscale.sh)
    train_ = Simulate("train", 21, 6.0);
    held_ = Simulate("held", 22, 3.0);
    dir_ = TempDir("model");
    TrainSegmenterRequest r;
    r.images = train_ / "frames";
    r.labels = train_ / "labels";
    r.out = dir_ / "sim.onnx";
    r.epochs = 12;
    r.seed = 5;
    r.input_width_px = 320;
    r.input_height_px = 240;
    r.validation_fraction = 0.25;
    r.width = 8;
    r.threads = 2;
    r.progress = false;
    r.licence = "test";
    r.reference = dir_ / "reference.npy";
    std::ostringstream log;
    card_ = nlohmann::json::parse(TrainSegmenter(r, log));
  }
  static inline fs::path train_, held_, dir_;
  static inline nlohmann::json card_;
};

TEST_F(LearnedSegmentation, CardSaysWhatTheModelTakesAndWasTrainedOn) {
  ASSERT_TRUE(fs::exists(dir_ / "sim.onnx"));
  ASSERT_TRUE(fs::exists(dir_ / "sim.json"));
  EXPECT_EQ(card_["format"], "plantscale-segmenter");
  EXPECT_EQ(card_["classes"], nlohmann::json({"soil", "crop", "weed"}));
  EXPECT_EQ(card_["input"]["image"], "grey");  // the simulator's near-infrared frames
  EXPECT_EQ(card_["input"]["width_px"], 320);
  const int photographs = card_["training"]["photographs"];
  EXPECT_EQ(card_["training"]["validation"].size(), static_cast<size_t>(std::lround(0.25 * photographs)));
  EXPECT_EQ(card_["training"]["train"].size() + card_["training"]["validation"].size(),
            static_cast<size_t>(photographs));
  EXPECT_EQ(card_["data"]["licence"], "test");
  EXPECT_GT(card_["validation"]["miou"].get<double>(), 0.4);
  // Nothing of the optimiser's working folder is left beside the model.
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++entries;
  EXPECT_EQ(entries, 3);  // sim.onnx, sim.json, reference.npy
}

TEST_F(LearnedSegmentation, BeatsATrivialClassifierOnHeldBackFrames) {
  ClassEvalRequest r{held_ / "frames", held_ / "labels", dir_ / "sim.onnx", false, false};
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

TEST_F(LearnedSegmentation, CppInferenceMatchesThePythonModel) {
  const std::string first = card_["training"]["validation"][0];
  LearnedModel model = ReadLearnedModel(dir_ / "sim.onnx");
  vision::LearnedSegmenter seg = LoadSegmenter(model);
  const cv::Mat image = ReadImage(train_ / "frames" / first);
  const cv::Mat logits = seg.Logits(vision::ResizeForModel(image, model.spec));
  std::vector<int> shape;
  const std::vector<float> ref = ReadNpyF32(dir_ / "reference.npy", shape);
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

TEST_F(LearnedSegmentation, RefusesAModelWhoseCardDoesNotFit) {
  const fs::path other = dir_.parent_path() / ("plantscale_learn_card_" + std::to_string(::getpid()));
  fs::create_directories(other);
  fs::copy_file(dir_ / "sim.onnx", other / "m.onnx", fs::copy_options::overwrite_existing);
  nlohmann::json card = card_;
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
  std::ofstream(other / "m.json") << card_.dump();
  EXPECT_THROW(LoadSegmenter(ReadLearnedModel(other / "m.onnx")), DataError);
  fs::remove_all(other);
}

}  // namespace
}  // namespace plantscale::app
