#include "app/train_segmenter.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <ostream>
#include <random>
#include <sstream>

#include "app/config/learned_model.h"
#include "app/config/photo_segmentation.h"
#include "engine/common/options.h"
#include "engine/vision/learned_segmenter.h"

#ifndef PLANTSCALE_SOURCE_DIR
#define PLANTSCALE_SOURCE_DIR "."
#endif

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

std::string EnvOr(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? std::string(v) : fallback;
}

// Runs argv with standard output and error discarded; its exit status (127
// when it cannot be started).
int RunQuiet(const std::vector<std::string>& argv) {
  const pid_t pid = ::fork();
  if (pid < 0) return 127;
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) {
      ::dup2(null, STDOUT_FILENO);
      ::dup2(null, STDERR_FILENO);
    }
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

struct Dataset {
  std::vector<std::string> names;
  std::vector<cv::Mat> images;  // at the input size, grey or BGR as the model takes
  std::vector<cv::Mat> labels;  // at the input size
  bool colour = false;
  int64_t pixels[vision::kPixelClassCount] = {0, 0, 0};  // of the labels, at full size
};

// Every photograph of `request.images` with its label, checked, resized.
Dataset LoadDataset(const TrainSegmenterRequest& r, std::ostream& log) {
  const std::vector<LabelledPhoto> photos = ListLabelledPhotos(r.images, r.labels);
  Dataset d;
  vision::LearnedModelSpec spec;
  spec.input_width_px = r.input_width_px;
  spec.input_height_px = r.input_height_px;
  const cv::Size size(r.input_width_px, r.input_height_px);
  for (const LabelledPhoto& photo : photos) {
    cv::Mat image, label;
    ReadLabelledPhoto(photo, image, label);
    for (int c = 0; c < vision::kPixelClassCount; ++c) d.pixels[c] += cv::countNonZero(label == c);
    if (image.channels() == 3 && IsGreyInColour(image)) cv::extractChannel(image, image, 0);
    d.colour = d.colour || image.channels() == 3;
    d.names.push_back(photo.image.filename().string());
    spec.channels = image.channels();  // resized as it is; grey made colour below in a colour set
    d.images.push_back(vision::ResizeForModel(image, spec));
    cv::Mat resized;
    cv::resize(label, resized, size, 0, 0, cv::INTER_NEAREST);
    d.labels.push_back(resized);
  }
  for (cv::Mat& image : d.images) {
    if (d.colour && image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
  }
  log << "train-segmenter: " << d.names.size() << " labelled " << (d.colour ? "colour" : "grey")
      << " photograph(s) from " << r.images.string() << ", resized to " << r.input_width_px << "×"
      << r.input_height_px << '\n';
  return d;
}

void WriteArrays(const Dataset& d, const fs::path& dir) {
  const int64_t n = static_cast<int64_t>(d.images.size());
  const int64_t h = d.images.front().rows, w = d.images.front().cols, c = d.images.front().channels();
  std::vector<uint8_t> pix, lab;
  pix.reserve(static_cast<size_t>(n * h * w * c));
  lab.reserve(static_cast<size_t>(n * h * w));
  for (int64_t i = 0; i < n; ++i) {
    const cv::Mat img = d.images[static_cast<size_t>(i)].isContinuous() ? d.images[static_cast<size_t>(i)]
                                                                          : d.images[static_cast<size_t>(i)].clone();
    pix.insert(pix.end(), img.data, img.data + img.total() * img.elemSize());
    const cv::Mat l = d.labels[static_cast<size_t>(i)].clone();
    lab.insert(lab.end(), l.data, l.data + l.total());
  }
  WriteNpyU8(dir / "images.npy", {n, h, w, c}, pix);
  WriteNpyU8(dir / "labels.npy", {n, h, w}, lab);
}

// A seeded split: round(fraction · n) photographs for validation (at least
// one when the fraction is positive and there are two or more).
void Split(size_t n, double fraction, int64_t seed, std::vector<int>& train, std::vector<int>& validation) {
  std::vector<int> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<int>(i);
  std::mt19937_64 rng(static_cast<uint64_t>(seed));
  for (size_t i = n; i > 1; --i) {  // Fisher–Yates, the same on every library
    const size_t j = static_cast<size_t>(rng() % i);
    std::swap(order[i - 1], order[j]);
  }
  size_t v = static_cast<size_t>(std::lround(fraction * static_cast<double>(n)));
  if (fraction > 0 && n >= 2) v = std::max<size_t>(v, 1);
  v = std::min(v, n - 1);
  validation.assign(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(v));
  train.assign(order.begin() + static_cast<std::ptrdiff_t>(v), order.end());
  std::sort(validation.begin(), validation.end());
  std::sort(train.begin(), train.end());
}

std::string Duration(double seconds) {
  const int s = static_cast<int>(seconds + 0.5);
  std::ostringstream o;
  if (s >= 60) o << s / 60 << "m";
  o << std::setw(s >= 60 ? 2 : 1) << std::setfill('0') << s % 60 << "s";
  return o.str();
}

// One epoch line of the optimiser drawn as the progress bar.
void DrawEpoch(const nlohmann::json& e, bool tty, std::ostream& log) {
  const int epoch = e.value("epoch", 0), epochs = std::max(1, e.value("epochs", 1));
  const int filled = 30 * epoch / epochs;
  std::ostringstream line;
  line << std::fixed << std::setprecision(3) << "train-segmenter [" << std::string(static_cast<size_t>(filled), '#')
       << std::string(static_cast<size_t>(30 - filled), ' ') << "] epoch " << epoch << "/" << epochs << "  loss "
       << e.value("loss", 0.0);
  if (e.contains("validation_miou") && e.at("validation_miou").is_number()) {
    line << "  validation mIoU " << e.at("validation_miou").get<double>();
  }
  line << "  best epoch " << e.value("best_epoch", 0) << "  " << Duration(e.value("seconds", 0.0));
  if (tty) log << '\r' << line.str() << "   " << std::flush;
  else log << line.str() << '\n' << std::flush;
}

struct OptimiserResult {
  int status = 0;
  nlohmann::json start, done;
  std::string stderr_tail;
};

// The optimiser's pid while it runs, for the SIGTERM handler.
volatile sig_atomic_t g_optimiser_pid = 0;

// SIGTERM (a service manager, `kill`) is passed on to the optimiser, which
// stops as on Ctrl-C and keeps the best model so far; this process then
// writes that model and removes its work folder (the photographs as arrays,
// hundreds of megabytes) as on any other ending.
void ForwardTerm(int) {
  if (g_optimiser_pid > 0) ::kill(static_cast<pid_t>(g_optimiser_pid), SIGTERM);
}

// glibc returns freed blocks over 128 kB to the kernel at once; PyTorch
// frees and takes back its activations every step, and each fresh page is a
// fault (costly in a virtual machine: half the optimiser's time went to the
// kernel). Kept by the allocator instead, an epoch took 13 s instead of 65 s
// (field-grey's 111 frames, 2 cores); the figures are the same. A caller's
// own MALLOC_* settings win.
std::vector<std::string> OptimiserEnvironment() {
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) env.emplace_back(*e);
  for (const char* setting : {"MALLOC_MMAP_THRESHOLD_=4294967296", "MALLOC_TRIM_THRESHOLD_=17179869184",
                              "MALLOC_TOP_PAD_=268435456"}) {
    const std::string name = std::string(setting).substr(0, std::string(setting).find('=') + 1);
    if (std::none_of(env.begin(), env.end(), [&](const std::string& v) { return v.rfind(name, 0) == 0; })) {
      env.emplace_back(setting);
    }
  }
  return env;
}

// The optimiser as a child writing its events to `out_fd` and its stderr to
// err_file; it stops when this process dies. Returns its pid.
pid_t SpawnOptimiser(const std::vector<std::string>& argv, std::vector<std::string> env,
                     const fs::path& err_file, int out_fd, int close_fd) {
  std::vector<char*> envp;
  for (std::string& v : env) envp.push_back(v.data());
  envp.push_back(nullptr);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  ::signal(SIGINT, SIG_DFL);
  ::signal(SIGTERM, SIG_DFL);
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);  // this process killed: the optimiser stops too
  ::dup2(out_fd, STDOUT_FILENO);
  const int err = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  if (err >= 0) ::dup2(err, STDERR_FILENO);
  ::close(close_fd);
  ::close(out_fd);
  ::execve(args[0], args.data(), envp.data());
  ::_exit(127);
}

// The optimiser's JSON events, one a line, until it closes its end: the
// start and done events kept, each epoch drawn when `progress`.
void ReadOptimiserEvents(int fd, bool progress, OptimiserResult& r, std::ostream& log) {
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  FILE* in = ::fdopen(fd, "r");
  char* buf = nullptr;
  size_t cap = 0;
  bool drawn = false;
  while (in != nullptr && ::getline(&buf, &cap, in) > 0) {
    const nlohmann::json e = nlohmann::json::parse(buf, nullptr, false);
    if (e.is_discarded() || !e.is_object()) continue;
    const std::string kind = e.value("event", "");
    if (kind == "start") r.start = e;
    if (kind == "done") r.done = e;
    if (kind == "epoch" && progress) {
      DrawEpoch(e, tty, log);
      drawn = true;
    }
  }
  std::free(buf);
  if (in != nullptr) std::fclose(in);
  if (drawn && tty) log << '\n';
}

// The last lines of the optimiser's stderr, for the error message.
std::string TailOf(const fs::path& file, size_t count) {
  std::ifstream err(file);
  std::string line, tail;
  std::vector<std::string> lines;
  while (std::getline(err, line)) lines.push_back(line);
  for (size_t i = lines.size() > count ? lines.size() - count : 0; i < lines.size(); ++i) tail += lines[i] + "\n";
  return tail;
}

// Runs the optimiser, drawing its progress; Ctrl-C reaches it (it keeps the
// best model so far) while this process waits for it, and SIGTERM is passed
// on to it (ForwardTerm).
OptimiserResult RunOptimiser(const std::vector<std::string>& argv, const fs::path& err_file, bool progress,
                             std::ostream& log) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("cannot make a pipe for the optimiser");
  struct sigaction ignore {}, old_int{};
  ignore.sa_handler = SIG_IGN;
  ::sigaction(SIGINT, &ignore, &old_int);
  const pid_t pid = SpawnOptimiser(argv, OptimiserEnvironment(), err_file, fds[1], fds[0]);
  if (pid < 0) {
    ::sigaction(SIGINT, &old_int, nullptr);
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error("cannot start the optimiser (fork failed)");
  }
  g_optimiser_pid = pid;
  struct sigaction forward {}, old_term{};
  forward.sa_handler = ForwardTerm;
  forward.sa_flags = SA_RESTART;
  ::sigaction(SIGTERM, &forward, &old_term);
  ::close(fds[1]);
  OptimiserResult r;
  ReadOptimiserEvents(fds[0], progress, r, log);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  ::sigaction(SIGINT, &old_int, nullptr);
  ::sigaction(SIGTERM, &old_term, nullptr);
  g_optimiser_pid = 0;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.stderr_tail = TailOf(err_file, 8);
  return r;
}

std::string NowUtc() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

nlohmann::json IouJson(const nlohmann::json& figures) {
  if (!figures.is_object()) return nullptr;
  const nlohmann::json& iou = figures.at("iou");
  return {{"iou", {{"soil", iou.at(0)}, {"crop", iou.at(1)}, {"weed", iou.at(2)}}},
          {"miou", figures.at("miou")}};
}

nlohmann::json MakeCard(const TrainSegmenterRequest& r, const Dataset& d, const std::vector<int>& train,
                        const std::vector<int>& validation, const OptimiserResult& o) {
  std::vector<std::string> train_names, validation_names;
  for (int i : train) train_names.push_back(d.names[static_cast<size_t>(i)]);
  for (int i : validation) validation_names.push_back(d.names[static_cast<size_t>(i)]);
  const int64_t total = d.pixels[0] + d.pixels[1] + d.pixels[2];
  const auto share = [&](int c) { return total > 0 ? static_cast<double>(d.pixels[c]) / static_cast<double>(total) : 0.0; };
  nlohmann::json card{
      {"format", kModelCardFormat},
      {"version", kModelCardVersion},
      {"classes", {"soil", "crop", "weed"}},
      {"input",
       {{"width_px", r.input_width_px},
        {"height_px", r.input_height_px},
        {"image", d.colour ? "colour" : "grey"},
        {"channel_order", d.colour ? "BGR" : "grey"},
        {"values", "8-bit values as floats (0-255), N×C×H×W; the network normalises them itself"},
        {"resize", "the whole photograph to width_px × height_px (aspect not kept): area averaging when "
                   "shrinking, bilinear when enlarging"},
        {"normalisation", {{"mean", o.done.value("mean", nlohmann::json())}, {"std", o.done.value("std", nlohmann::json())}}}}},
      {"output_stride", r.output_stride},
      {"output", std::string("class logits 1×3×") + (r.output_stride == 1 ? "H×W" : "H/2×W/2") +
                     " (soil, crop, weed), upsampled bilinearly to the photograph"},
      {"network",
       {{"kind", std::string("U-Net of four scales (1/2 to 1/16): 3×3 Conv, BatchNormalization, Relu; nearest "
                             "Resize and Concat on the way up") +
                     (r.output_stride == 1 ? "; a last stage at the input's resolution, of width/2, with a "
                                             "skip from the input"
                                           : "")},
        {"width", r.width},
        {"parameters", o.done.value("parameters", 0)}}},
      {"training",
       {{"images", fs::absolute(r.images).string()},
        {"labels", fs::absolute(r.labels).string()},
        {"photographs", d.names.size()},
        {"label_pixel_share", {{"soil", share(0)}, {"crop", share(1)}, {"weed", share(2)}}},
        {"train", train_names},
        {"validation", validation_names},
        {"epochs", r.epochs},
        {"best_epoch", o.done.value("best_epoch", 0)},
        {"interrupted", o.done.value("interrupted", false)},
        {"epochs_run", o.done.value("epochs_run", 0)},
        {"stopped_for_time", o.done.value("stopped_for_time", false)},
        {"max_minutes", r.max_minutes},
        {"seed", r.seed},
        {"seconds", o.done.value("seconds", 0.0)},
        {"torch", o.start.value("torch", "")}}},
      {"data",
       {{"licence", r.licence.empty() ? "not stated" : r.licence},
        {"attribution", r.attribution.empty() ? "not stated" : r.attribution}}},
      {"validation", IouJson(o.done.value("validation", nlohmann::json()))},
      {"command", r.command_line},
      {"created", NowUtc()}};
  return card;
}

}  // namespace

std::string TrainingPython() { return EnvOr("PLANTSCALE_PYTHON", "/usr/bin/python3"); }

std::string TrainerScript() {
  return EnvOr("PLANTSCALE_TRAINER", std::string(PLANTSCALE_SOURCE_DIR) + "/app/training/train_segmenter.py");
}

void CheckTrainingPackages() {
  const std::string python = TrainingPython();
  if (::access(python.c_str(), X_OK) != 0) {
    throw MissingPackagesError("training needs Python 3 at " + python +
                               " (Debian: apt-get install python3 python3-numpy python3-torch python3-onnx; "
                               "another interpreter: PLANTSCALE_PYTHON)");
  }
  std::vector<std::string> missing;
  for (const auto& [module, package] : {std::pair{"numpy", "python3-numpy"}, std::pair{"torch", "python3-torch"},
                                        std::pair{"onnx", "python3-onnx"}}) {
    if (RunQuiet({python, "-c", std::string("import ") + module}) != 0) missing.push_back(package);
  }
  if (missing.empty()) return;
  std::string list;
  for (const std::string& p : missing) list += (list.empty() ? "" : " ") + p;
  throw MissingPackagesError("training needs Debian's " + list + " for " + python +
                             " (not installed; nothing is installed silently): apt-get install " + list);
}

cv::Size ParseInputSize(const std::string& text) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  std::istringstream in(text);
  if (!(in >> w >> x >> h) || (x != 'x' && x != 'X') || (in >> extra)) {
    throw DataError("--input-size must be WxH, e.g. 512x384 (got '" + text + "')");
  }
  vision::LearnedModelSpec s;
  s.input_width_px = w;
  s.input_height_px = h;
  const OptionErrors errors = s.Validate();
  if (!errors.empty()) throw DataError("--input-size: " + errors.front().key + " " + errors.front().reason);
  return {w, h};
}

void WriteNpyU8(const fs::path& path, const std::vector<int64_t>& shape, const std::vector<uint8_t>& data) {
  std::string dims;
  for (int64_t s : shape) dims += std::to_string(s) + ", ";
  if (shape.size() > 1) dims.erase(dims.size() - 2);
  else dims.erase(dims.size() - 1);
  std::string header = "{'descr': '|u1', 'fortran_order': False, 'shape': (" + dims + "), }";
  const size_t total = 10 + header.size() + 1;
  header += std::string((64 - total % 64) % 64, ' ') + "\n";
  std::ofstream out(path, std::ios::binary);
  out.write("\x93NUMPY\x01\x00", 8);
  const uint16_t len = static_cast<uint16_t>(header.size());
  const char le[2] = {static_cast<char>(len & 0xFF), static_cast<char>(len >> 8)};
  out.write(le, 2);
  out.write(header.data(), static_cast<std::streamsize>(header.size()));
  out.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
  if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
}

std::string TrainSegmenter(const TrainSegmenterRequest& r, std::ostream& log) {
  if (r.out.extension() != ".onnx") throw DataError(r.out.string() + ": the model's name must end in .onnx");
  if (r.epochs < 1) throw DataError("--epochs must be at least 1");
  if (!(r.validation_fraction >= 0 && r.validation_fraction < 1)) {
    throw DataError("--validation-fraction must be in [0, 1)");
  }
  ParseInputSize(std::to_string(r.input_width_px) + "x" + std::to_string(r.input_height_px));
  const Dataset d = LoadDataset(r, log);
  if (d.names.size() < 2) throw DataError(r.images.string() + ": training needs at least two labelled photographs");
  CheckTrainingPackages();
  std::vector<int> train, validation;
  Split(d.names.size(), r.validation_fraction, r.seed, train, validation);

  const fs::path out_dir = fs::absolute(r.out).parent_path();
  fs::create_directories(out_dir);
  std::string pattern = (out_dir / ("." + r.out.stem().string() + ".training-XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot make a folder in " + out_dir.string());
  const fs::path work = pattern;
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{work};
  WriteArrays(d, work);
  {
    std::ofstream split(work / "split.json");
    split << nlohmann::json{{"train", train}, {"validation", validation}}.dump();
  }
  const fs::path onnx = work / "model.onnx";
  std::vector<std::string> argv{TrainingPython(), TrainerScript(), "--data", work.string(), "--out", onnx.string(),
                                "--epochs", std::to_string(r.epochs), "--seed", std::to_string(r.seed),
                                "--width", std::to_string(r.width), "--output-stride", std::to_string(r.output_stride),
                                "--threads", std::to_string(r.threads),
                                "--max-minutes", std::to_string(r.max_minutes)};
  if (!r.reference.empty()) argv.insert(argv.end(), {"--reference", fs::absolute(r.reference).string()});
  log << "train-segmenter: " << train.size() << " to train on, " << validation.size() << " to validate on, "
      << r.epochs << " epoch(s), seed " << r.seed << '\n';
  const OptimiserResult o = RunOptimiser(argv, work / "stderr.txt", r.progress, log);
  std::error_code ec;
  if (!fs::exists(onnx, ec)) {
    throw std::runtime_error("the optimiser (" + TrainerScript() + ") wrote no model (exit " +
                             std::to_string(o.status) + ")" + (o.stderr_tail.empty() ? "" : ":\n" + o.stderr_tail));
  }
  if (o.done.is_null()) {
    throw std::runtime_error("the optimiser stopped before it finished (exit " + std::to_string(o.status) + ")" +
                             (o.stderr_tail.empty() ? "" : ":\n" + o.stderr_tail));
  }
  nlohmann::json card = MakeCard(r, d, train, validation, o);
  // The graph must load and run in OpenCV and fit its card before it is kept.
  LearnedModel m;
  m.onnx_path = onnx;
  {
    std::ifstream in(onnx, std::ios::binary);
    m.onnx.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  m.spec = SpecFromCard(card);
  LoadSegmenter(m);
  const fs::path card_tmp = work / "model.json";
  {
    std::ofstream out(card_tmp);
    out << card.dump(2) << '\n';
    if (!out.flush()) throw std::runtime_error("cannot write " + card_tmp.string());
  }
  fs::rename(onnx, r.out);
  fs::rename(card_tmp, CardPath(r.out));
  if (o.done.value("stopped_for_time", false)) {
    log << "train-segmenter: the time budget (--max-minutes " << r.max_minutes << ") ended training after epoch "
        << o.done.value("epochs_run", 0) << " of " << r.epochs << " (the learning rate annealed by time)\n";
  }
  if (o.done.value("interrupted", false)) {
    log << "train-segmenter: interrupted; kept the best model so far (epoch " << o.done.value("best_epoch", 0)
        << ")\n";
  }
  return card.dump(2);
}

}  // namespace plantscale::app
