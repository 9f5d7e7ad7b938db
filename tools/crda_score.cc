// crda_score: scores `plantscale detect-rows` output (NAME_rows.csv,
// NAME_rows.json) against label images of crop-row centre lines (white
// lines on black, any scale, JPEG or PNG: thresholded at 128), with the
// CRDA measure of Vidović, Cupec and Hocenski (Pattern Recognition 2016)
// as issue 34 states it: per labelled image row, each of the three central
// true rows scores max(0, 1 − ((u − u_true)/(0.1·d))²), d the true spacing
// there (half the distance between the outer two), and the image row scores
// the mean of the three. An image scores the mean over its labelled image
// rows (rows with fewer than three label lines are not scored); "no rows"
// scores 0 on every labelled image row.
//
// Two matchings of detected to true rows, both printed:
//   ordered  the detected row nearest the central true row is matched to
//            it, its left and right neighbours to the true left and right
//            rows (a missing neighbour scores 0);
//   nearest  each true row is matched to the detected row nearest it.
//
// usage: crda_score --labels DIR --rows DIR [--categories FILE | --shape] [--per-image] [--snap F] [--by-spacing] [--errors]
//   --shape: categories "curved" and "straight" from the labels themselves
//   (the central label line departs from a straight line by more than 5 %
//   of the spacing somewhere, or not).
//   --snap F: the centring ceiling; each detected row within F × the label
//   spacing of a label line is scored as if it lay on it.
//   --by-spacing: the ordered CRDA over all labelled image rows by the
//   label spacing there (pixels of the photograph).
//   --errors: the signed centring error (u_detected − u_label) / spacing of
//   the ordered matching by row (n = −1, 0, +1) and height in the image.
//   DIR of labels: NAME.{jpg,png}; DIR of rows: NAME_rows.csv, NAME_rows.json.
//   --categories: lines "NAME,category"; otherwise the category is the
//   file name up to its first digit ("" → "all").
// Exit 0 when at least one image was scored, 2 otherwise.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "engine/rows/label_lines.h"

namespace fs = std::filesystem;

namespace {

double Crda(double u, double u_true, double d) {
  const double e = (u - u_true) / (0.1 * d);
  return std::max(0.0, 1.0 - e * e);
}

struct Detected {
  int width = 0, height = 0;
  bool found = false;
  // per image row v: u of each detected row (indexed by row number; NaN where absent)
  std::map<int, std::vector<double>> u;
};

// Reads one integer/float JSON field without a JSON library ("key": value).
double JsonNumber(const std::string& text, const std::string& key, double fallback) {
  const auto p = text.find("\"" + key + "\"");
  if (p == std::string::npos) return fallback;
  const auto colon = text.find(':', p);
  if (colon == std::string::npos) return fallback;
  try {
    return std::stod(text.substr(colon + 1, 40));
  } catch (...) {
    return fallback;
  }
}

bool ReadDetected(const fs::path& csv, const fs::path& json, Detected& d, std::string& error) {
  std::ifstream j(json);
  if (!j) {
    error = "cannot read " + json.string();
    return false;
  }
  std::stringstream ss;
  ss << j.rdbuf();
  const std::string text = ss.str();
  d.width = static_cast<int>(JsonNumber(text, "width", 0));
  d.height = static_cast<int>(JsonNumber(text, "height", 0));
  d.found = JsonNumber(text, "confidence", 0.0) > 0.0;
  std::ifstream c(csv);
  if (!c) {
    error = "cannot read " + csv.string();
    return false;
  }
  std::string line;
  std::getline(c, line);
  if (line.rfind("row,v,u", 0) != 0) {
    error = csv.string() + ": header is not row,v,u";
    return false;
  }
  while (std::getline(c, line)) {
    int row = 0, v = 0;
    double u = 0;
    char c1 = 0, c2 = 0;
    std::istringstream ls(line);
    if (!(ls >> row >> c1 >> v >> c2 >> u) || row < 0) continue;
    auto& us = d.u[v];
    if (static_cast<int>(us.size()) <= row) us.resize(static_cast<size_t>(row) + 1, std::nan(""));
    us[static_cast<size_t>(row)] = u;
  }
  return true;
}

// Label spacing classes of --by-spacing (upper bounds, pixels of the photograph).
constexpr std::array<double, 4> kSpacingClasses = {40.0, 80.0, 160.0, 1e9};

// --errors: the signed centring error (u_detected − u_label) / d of the
// ordered matching, by which row (n = −1, 0, +1) and by the image row's
// height in the photograph (kErrorBins bins, bottom first), over matches
// within half a spacing; and the detected spacing over the label's.
constexpr int kErrorBins = 5;
struct ErrorStats {
  std::array<std::array<std::vector<double>, kErrorBins>, 3> e;  // [n + 1][bin]
  std::array<std::vector<double>, kErrorBins> spacing_ratio;
  std::array<double, 3> se{}, ss{}, ee{};  // Σ slope·e, Σ slope², Σ e² by n
  std::array<std::vector<double>, 3> image_e;            // the current image's errors by n
  std::array<std::vector<double>, 3> row_means, row_residuals;  // by n, over images
  // The current image's errors into each row's mean and residuals about it.
  void EndImage() {
    for (size_t n = 0; n < 3; ++n) {
      if (image_e[n].size() >= 10) {
        double m = 0.0;
        for (const double x : image_e[n]) m += x;
        m /= static_cast<double>(image_e[n].size());
        row_means[n].push_back(m);
        for (const double x : image_e[n]) row_residuals[n].push_back(x - m);
      }
      image_e[n].clear();
    }
  }
};

struct Score {
  double ordered = 0.0, nearest = 0.0;
  int rows = 0;
  std::array<double, 4> by_spacing{}, rows_by_spacing{};  // ordered CRDA summed, image rows
};

size_t SpacingClass(double d) {
  size_t i = 0;
  while (i + 1 < kSpacingClasses.size() && d > kSpacingClasses[i]) ++i;
  return i;
}

// The central line: nearest the image's centre column, with a neighbour
// each side (centres has at least 3).
size_t CentralLine(const std::vector<double>& centres, double width) {
  size_t c = 1;
  for (size_t i = 1; i + 1 < centres.size(); ++i) {
    if (std::abs(centres[i] - 0.5 * width) < std::abs(centres[c] - 0.5 * width)) c = i;
  }
  return c;
}

// The detected rows' columns at image row v, sorted (NaN: none there).
std::vector<double> DetectedAt(const Detected& det, int v) {
  std::vector<double> us;
  if (const auto it = det.u.find(v); it != det.u.end()) {
    for (const double u : it->second) {
      if (!std::isnan(u)) us.push_back(u);
    }
  }
  std::sort(us.begin(), us.end());
  return us;
}

// One image row's CRDA summed over the central line and its neighbours:
// ordered (the detection nearest the central line and its neighbours in
// order) and nearest (each label line's nearest detection).
std::pair<double, double> ScoreRow(const std::vector<double>& us,
                                   const std::vector<double>& centres, size_t c, double d) {
  double ordered = 0.0, nearest = 0.0;
  if (us.empty()) return {ordered, nearest};
  size_t j = 0;
  for (size_t i = 0; i < us.size(); ++i) {
    if (std::abs(us[i] - centres[c]) < std::abs(us[j] - centres[c])) j = i;
  }
  ordered += Crda(us[j], centres[c], d);
  if (j > 0) ordered += Crda(us[j - 1], centres[c - 1], d);
  if (j + 1 < us.size()) ordered += Crda(us[j + 1], centres[c + 1], d);
  for (size_t k = c - 1; k <= c + 1; ++k) {
    double best = us[0];
    for (const double u : us) {
      if (std::abs(u - centres[k]) < std::abs(best - centres[k])) best = u;
    }
    nearest += Crda(best, centres[k], d);
  }
  return {ordered, nearest};
}

// The centring ceiling (--snap F): every detected row within F × the
// label spacing of a label line is moved onto it, as a detector that found
// the same rows but centred them perfectly would place them.
void SnapToLabels(std::vector<double>& us, const std::vector<double>& centres, double d, double f) {
  for (double& u : us) {
    size_t k = 0;
    for (size_t i = 1; i < centres.size(); ++i) {
      if (std::abs(centres[i] - u) < std::abs(centres[k] - u)) k = i;
    }
    if (std::abs(centres[k] - u) <= f * d) u = centres[k];
  }
}

// The ordered matching's signed errors of one image row into `stats`.
void AddErrors(const std::vector<double>& us, const std::vector<double>& above, const std::vector<double>& centres,
               size_t c, double d, double height_fraction, ErrorStats& stats) {
  if (us.empty()) return;
  size_t j = 0;
  for (size_t i = 0; i < us.size(); ++i) {
    if (std::abs(us[i] - centres[c]) < std::abs(us[j] - centres[c])) j = i;
  }
  const int bin = std::clamp(static_cast<int>((1.0 - height_fraction) * kErrorBins), 0, kErrorBins - 1);
  for (int n = -1; n <= 1; ++n) {
    if ((n < 0 && j == 0) || (n > 0 && j + 1 >= us.size())) continue;
    const auto at = [n](size_t i) { return static_cast<size_t>(static_cast<std::ptrdiff_t>(i) + n); };
    const double e = (us[at(j)] - centres[at(c)]) / d;
    if (std::abs(e) > 0.5) continue;
    stats.e[static_cast<size_t>(n + 1)][static_cast<size_t>(bin)].push_back(e);
    stats.image_e[static_cast<size_t>(n + 1)].push_back(e);
    if (above.size() == us.size()) {
      const double slope = (above[at(j)] - us[at(j)]) / 4.0;  // du per pixel upwards
      stats.se[static_cast<size_t>(n + 1)] += slope * e;
      stats.ss[static_cast<size_t>(n + 1)] += slope * slope;
      stats.ee[static_cast<size_t>(n + 1)] += e * e;
    }
  }
  if (j > 0 && j + 1 < us.size()) {
    stats.spacing_ratio[static_cast<size_t>(bin)].push_back(0.5 * (us[j + 1] - us[j - 1]) / d);
  }
}

Score ScoreImage(const cv::Mat& label, const Detected& det, double snap, ErrorStats* stats) {
  Score s;
  const double sx = static_cast<double>(det.width) / label.cols;
  const double sy = static_cast<double>(det.height) / label.rows;
  for (int y = 0; y < label.rows; ++y) {
    const std::vector<double> centres = plantscale::rows::LabelLineCentres(label.ptr<uint8_t>(y), label.cols, sx);
    if (centres.size() < 3) continue;
    const size_t c = CentralLine(centres, det.width);
    const double d = 0.5 * (centres[c + 1] - centres[c - 1]);
    const int v = std::clamp(static_cast<int>(std::floor((y + 0.5) * sy)), 0, det.height - 1);
    std::vector<double> us = DetectedAt(det, v);
    if (snap > 0.0) SnapToLabels(us, centres, d, snap);
    const auto [ordered, nearest] = ScoreRow(us, centres, c, d);
    if (stats != nullptr) {
      std::vector<double> above = DetectedAt(det, std::max(0, v - 4));
      if (snap > 0.0) above.clear();
      AddErrors(us, above, centres, c, d, (y + 0.5) / label.rows, *stats);
    }
    s.ordered += ordered / 3.0;
    s.nearest += nearest / 3.0;
    ++s.rows;
    s.by_spacing[SpacingClass(d)] += ordered / 3.0;
    s.rows_by_spacing[SpacingClass(d)] += 1.0;
  }
  if (s.rows > 0) {
    s.ordered /= s.rows;
    s.nearest /= s.rows;
  }
  return s;
}

// "curved" when the label's central line bends: the centres of the label
// line nearest the image's centre column, followed from the bottom up, depart
// from their least-squares straight line by more than `tolerance` × the
// label spacing somewhere; else "straight".
std::string LabelShape(const cv::Mat& label, double tolerance) {
  std::vector<double> vs, us;
  double spacing_sum = 0.0;
  int spacing_n = 0;
  double prev = 0.5 * label.cols;
  for (int y = label.rows - 1; y >= 0; --y) {
    const std::vector<double> centres = plantscale::rows::LabelLineCentres(label.ptr<uint8_t>(y), label.cols);
    if (centres.size() < 2) continue;
    size_t c = 0;
    for (size_t i = 1; i < centres.size(); ++i) {
      if (std::abs(centres[i] - prev) < std::abs(centres[c] - prev)) c = i;
    }
    if (!vs.empty() && std::abs(centres[c] - prev) > 8.0) break;  // lost the line
    prev = centres[c];
    vs.push_back(y);
    us.push_back(centres[c]);
    const double gap = c + 1 < centres.size() ? centres[c + 1] - centres[c] : centres[c] - centres[c - 1];
    spacing_sum += gap;
    ++spacing_n;
  }
  if (vs.size() < 10) return "unknown";
  double sv = 0, su = 0, svv = 0, svu = 0;
  const double n = static_cast<double>(vs.size());
  for (size_t i = 0; i < vs.size(); ++i) {
    sv += vs[i];
    su += us[i];
    svv += vs[i] * vs[i];
    svu += vs[i] * us[i];
  }
  const double b = (n * svu - sv * su) / (n * svv - sv * sv);
  const double a = (su - b * sv) / n;
  double worst = 0.0;
  for (size_t i = 0; i < vs.size(); ++i) worst = std::max(worst, std::abs(us[i] - a - b * vs[i]));
  return worst > tolerance * spacing_sum / spacing_n ? "curved" : "straight";
}

struct Tally {
  int images = 0, found = 0;
  double ordered = 0.0, nearest = 0.0;
  std::array<double, 4> by_spacing{}, rows_by_spacing{};
};

// "NAME,category" lines; empty without a file.
std::map<std::string, std::string> ReadCategories(const fs::path& file) {
  std::map<std::string, std::string> category_of;
  if (file.empty()) return category_of;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    const auto comma = line.find(',');
    if (comma != std::string::npos) category_of[line.substr(0, comma)] = line.substr(comma + 1);
  }
  return category_of;
}

// The category file's, else the name up to its first digit, else "all".
std::string CategoryOf(const std::string& name, const std::map<std::string, std::string>& category_of) {
  if (const auto it = category_of.find(name); it != category_of.end()) return it->second;
  const std::string category = name.substr(0, name.find_first_of("0123456789"));
  return category.empty() ? "all" : category;
}

// The label images of a folder (JPEG, PNG), sorted.
std::vector<fs::path> LabelFiles(const fs::path& folder) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(folder)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".jpg" || ext == ".png" || ext == ".jpeg" || ext == ".JPG" || ext == ".PNG") {
      files.push_back(e.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

void PrintTally(const std::string& label, const Tally& t) {
  std::cout << std::left << std::setw(16) << label << std::right << " images " << std::setw(4)
            << t.images << "  found " << std::setw(5) << (t.images ? 100.0 * t.found / t.images : 0.0)
            << " %  crda_ordered " << (t.images ? t.ordered / t.images : 0.0) << "  crda_nearest "
            << (t.images ? t.nearest / t.images : 0.0) << '\n';
}

void AddBySpacing(Tally& t, const Score& s) {
  for (size_t i = 0; i < kSpacingClasses.size(); ++i) {
    t.by_spacing[i] += s.by_spacing[i];
    t.rows_by_spacing[i] += s.rows_by_spacing[i];
  }
}

// Ordered CRDA over all labelled image rows by the label spacing there.
void PrintBySpacing(const Tally& t) {
  double lo = 0.0;
  for (size_t i = 0; i < kSpacingClasses.size(); ++i) {
    const double n = t.rows_by_spacing[i];
    std::cout << "spacing " << std::setw(4) << lo << "-" << std::setw(4)
              << (i + 1 < kSpacingClasses.size() ? kSpacingClasses[i] : 9999.0) << " px  image rows "
              << std::setw(7) << n << "  crda_ordered " << (n > 0 ? t.by_spacing[i] / n : 0.0) << '\n';
    lo = kSpacingClasses[i];
  }
}

double Quantile(std::vector<double> x, double q) {
  if (x.empty()) return std::nan("");
  const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(x.size() - 1));
  std::nth_element(x.begin(), x.begin() + k, x.end());
  return x[static_cast<size_t>(k)];
}

double Mean(const std::vector<double>& x) {
  double sum = 0.0;
  for (const double v : x) sum += v;
  return x.empty() ? std::nan("") : sum / static_cast<double>(x.size());
}

// The mean CRDA of errors e (in spacings).
double MeanCrda(const std::vector<double>& e) {
  double sum = 0.0;
  for (const double x : e) sum += Crda(x, 0.0, 1.0);
  return e.empty() ? std::nan("") : sum / static_cast<double>(e.size());
}

void PrintErrors(const ErrorStats& stats) {
  std::cout << "signed error (u_detected - u_label) / spacing, matches within 0.5 spacing\n";
  for (int b = 0; b < kErrorBins; ++b) {
    std::cout << "height " << static_cast<double>(b) / kErrorBins << "-" << static_cast<double>(b + 1) / kErrorBins
              << " (from bottom)";
    for (int n = -1; n <= 1; ++n) {
      const std::vector<double>& e = stats.e[static_cast<size_t>(n + 1)][static_cast<size_t>(b)];
      std::vector<double> a(e.size());
      std::transform(e.begin(), e.end(), a.begin(), [](double x) { return std::abs(x); });
      std::cout << "  n=" << std::showpos << n << std::noshowpos << " N " << e.size() << " mean " << std::showpos
                << Mean(e) << " median " << Quantile(e, 0.5) << std::noshowpos << " |e| median "
                << Quantile(a, 0.5) << " q90 " << Quantile(a, 0.9) << " crda " << MeanCrda(e);
    }
    const auto& r = stats.spacing_ratio[static_cast<size_t>(b)];
    std::cout << "  spacing ratio median " << Quantile(r, 0.5) << " mean " << Mean(r) << '\n';
  }
  for (int n = -1; n <= 1; ++n) {
    const auto& m = stats.row_means[static_cast<size_t>(n + 1)];
    const auto& r = stats.row_residuals[static_cast<size_t>(n + 1)];
    std::vector<double> am(m.size()), ar(r.size());
    std::transform(m.begin(), m.end(), am.begin(), [](double x) { return std::abs(x); });
    std::transform(r.begin(), r.end(), ar.begin(), [](double x) { return std::abs(x); });
    const size_t i = static_cast<size_t>(n + 1);
    std::cout << "n=" << std::showpos << n << std::noshowpos << " e ~ b * du/dv(up): b " << stats.se[i] / stats.ss[i]
              << " variance explained " << stats.se[i] * stats.se[i] / stats.ss[i] / stats.ee[i] << '\n';
    std::cout << "n=" << std::showpos << n << std::noshowpos << " rows " << m.size() << ": |row mean error| median "
              << Quantile(am, 0.5) << " q90 " << Quantile(am, 0.9) << "; |error - row mean| median "
              << Quantile(ar, 0.5) << " q90 " << Quantile(ar, 0.9) << '\n';
  }
}

struct Args {
  fs::path labels, rows, categories_file;
  bool per_image = false, shape = false, by_spacing = false, errors = false;
  double snap = 0.0;
};

// The command line; false (after a message) when it is not usable.
bool ParseArgs(int argc, char** argv, Args& a) {
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    const bool value = i + 1 < argc;
    if (s == "--labels" && value) a.labels = argv[++i];
    else if (s == "--rows" && value) a.rows = argv[++i];
    else if (s == "--categories" && value) a.categories_file = argv[++i];
    else if (s == "--per-image") a.per_image = true;
    else if (s == "--shape") a.shape = true;
    else if (s == "--by-spacing") a.by_spacing = true;
    else if (s == "--errors") a.errors = true;
    else if (s == "--snap" && value) a.snap = std::stod(argv[++i]);
    else {
      std::cerr << "usage: crda_score --labels DIR --rows DIR [--categories FILE | --shape] [--per-image] [--snap F] [--by-spacing] [--errors]\n";
      return false;
    }
  }
  if (a.labels.empty() || a.rows.empty() || !fs::is_directory(a.labels) || !fs::is_directory(a.rows)) {
    std::cerr << "crda_score: --labels and --rows must be folders\n";
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  if (!ParseArgs(argc, argv, args)) return 2;
  const auto& [labels, rows, categories_file, per_image, shape, by_spacing, errors_wanted, snap] = args;
  ErrorStats error_stats;
  const std::map<std::string, std::string> category_of = ReadCategories(categories_file);
  const std::vector<fs::path> files = LabelFiles(labels);
  std::map<std::string, Tally> tallies;
  Tally all;
  int errors = 0;
  std::cout << std::fixed << std::setprecision(3);
  for (const fs::path& file : files) {
    const std::string name = file.stem().string();
    cv::Mat label = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
    Detected det;
    std::string error;
    if (label.empty()) error = "cannot read label " + file.string();
    else ReadDetected(rows / (name + "_rows.csv"), rows / (name + "_rows.json"), det, error);
    if (error.empty() && (det.width <= 0 || det.height <= 0)) error = name + ": no image size in JSON";
    if (!error.empty()) {
      std::cerr << "crda_score: error: " << error << '\n';
      ++errors;
      continue;
    }
    const Score s = ScoreImage(label, det, snap, errors_wanted ? &error_stats : nullptr);
    error_stats.EndImage();
    if (s.rows == 0) continue;  // nothing labelled with three rows
    const std::string category = shape ? LabelShape(label, 0.05) : CategoryOf(name, category_of);
    for (Tally* t : {&tallies[category], &all}) {
      ++t->images;
      t->found += det.found ? 1 : 0;
      t->ordered += s.ordered;
      t->nearest += s.nearest;
      AddBySpacing(*t, s);
    }
    if (per_image) {
      std::cout << "image " << name << " crda_ordered " << s.ordered << " crda_nearest " << s.nearest
                << " found " << det.found << '\n';
    }
  }
  if (tallies.size() > 1) {
    for (const auto& [category, t] : tallies) PrintTally(category, t);
  }
  PrintTally("overall", all);
  if (by_spacing) PrintBySpacing(all);
  if (errors_wanted) PrintErrors(error_stats);
  if (errors > 0) std::cout << errors << " error(s)\n";
  return all.images > 0 ? 0 : 2;
}
