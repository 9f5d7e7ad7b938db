#pragma once
// `plantscale train-segmenter`: a crop/weed/soil model from labelled
// photographs. This side reads and checks the photographs and labels, resizes
// them as the vehicle's inference will (vision::ResizeForModel), hands them
// to the optimiser (app/training/train_segmenter.py, Debian's PyTorch: CPU,
// training only) as NumPy arrays, draws its progress, and writes MODEL.onnx
// and its card MODEL.json once OpenCV has loaded the graph and checked it
// against the card. Nothing is half-written: both files are made beside
// their place and renamed into it.

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace plantscale::app {

struct TrainSegmenterRequest {
  std::filesystem::path images;  // photographs (PNG/JPEG), colour or grey
  std::filesystem::path labels;  // NAME.png per photograph NAME.*: 0 soil, 1 crop, 2 weed
  std::filesystem::path out;     // MODEL.onnx (MODEL.json beside it)
  int epochs = 150;
  int64_t seed = 1;
  int input_width_px = 512;  // photographs are resized to this (multiples of 16)
  int input_height_px = 384;
  double validation_fraction = 0.15;
  int width = 16;            // the network's channels at its first scale
  int output_stride = 2;     // logits at 1/output_stride of the input: 2, or 1 (a full-resolution stage)
  int threads = 0;           // 0: every core
  // A time budget for the optimiser (0: none): when the epochs would not
  // fit, the learning rate anneals by time and training ends within it.
  double max_minutes = 14.0;
  std::string licence;       // of the photographs (into the card)
  std::string attribution;   // of the photographs (into the card)
  std::string command_line;  // how this was run (into the card)
  bool progress = true;
  std::filesystem::path reference;  // tests: the Python model's logits on the first validation photograph
};

// Thrown for a training environment that lacks a package (exit 2).
class MissingPackagesError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The Python interpreter with Debian's PyTorch (PLANTSCALE_PYTHON, default
// /usr/bin/python3) and the optimiser script (PLANTSCALE_TRAINER, default
// the source tree's app/training/train_segmenter.py).
std::string TrainingPython();
std::string TrainerScript();

// Throws MissingPackagesError naming the missing Debian packages and how to
// install them.
void CheckTrainingPackages();

// "512x384" -> (512, 384); throws DataError.
cv::Size ParseInputSize(const std::string& text);

// Trains and writes the model; returns the card written. Bad data throws
// DataError naming the file (checked before anything else), a missing
// package MissingPackagesError; a failed optimiser throws
// std::runtime_error with its last words.
std::string TrainSegmenter(const TrainSegmenterRequest& request, std::ostream& log);

// A NumPy .npy file of uint8 with the given shape (tests and the optimiser).
void WriteNpyU8(const std::filesystem::path& path, const std::vector<int64_t>& shape,
                const std::vector<uint8_t>& data);

}  // namespace plantscale::app
