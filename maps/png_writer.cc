// PNG picture of a map for people: classes in colour, treated cells tinted
// blue, a legend, a scale bar and, when georeferenced, a north arrow. The
// map is drawn in the field frame with +y (forward, along the rows) up.
#include <cmath>
#include <fstream>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "maps/map_errors.h"
#include "maps/writers.h"

namespace plantscale::maps {
namespace {

constexpr int kMargin = 24;
constexpr int kLegendWidth = 250;
constexpr int kScaleBarHeight = 56;
const cv::Vec3b kSoil{70, 105, 140}, kCrop{60, 170, 40}, kWeed{40, 40, 220},
    kUnknown{150, 150, 150};
const cv::Vec3b kTreated{230, 120, 20};

// Treated cells: the class colour tinted towards blue.
cv::Vec3b Tinted(const cv::Vec3b& colour) { return 0.45 * colour + 0.55 * kTreated; }

cv::Vec3b ColourOf(CellClass c) {
  switch (c) {
    case CellClass::kSoil:
      return kSoil;
    case CellClass::kCrop:
      return kCrop;
    case CellClass::kWeed:
      return kWeed;
    case CellClass::kUnknown:
      return kUnknown;
  }
  return kUnknown;
}

cv::Mat CellImage(const CropMap& map) {
  const MapGrid& g = map.grid();
  cv::Mat image(g.rows(), g.cols(), CV_8UC3);
  for (size_t i = 0; i < g.size(); ++i) {
    const Cell c = g.CellOf(i);
    cv::Vec3b colour = ColourOf(static_cast<CellClass>(map.layers().cls[i]));
    if (map.layers().treated[i] != 0) colour = Tinted(colour);
    image.at<cv::Vec3b>(g.rows() - 1 - c.row, c.col) = colour;  // +y up
  }
  return image;
}

double PixelsPerCell(const MapGrid& g) {
  return std::clamp(std::min(1400.0 / g.rows(), 1000.0 / g.cols()), 0.05, 12.0);
}

// A long run (over ~370 m of 1.33 cm cells) would be a thin line one
// picture high: it is cut along y into panels of equal length drawn side by
// side (panel 0, the run's start, on the left), each at most 1400 px high,
// about 1600 px wide in all.
struct PanelLayout {
  double scale = 1.0;  // pixels per cell
  int panels = 1;
  int panel_rows = 0;  // map rows per panel
  int panel_width = 0, panel_height = 0;
  static constexpr int kGap = 10;  // pixels between panels
  int width() const { return panels * (panel_width + kGap) - kGap; }
};

bool NeedsPanels(const MapGrid& g) { return std::min(1400.0 / g.rows(), 1000.0 / g.cols()) < 0.05; }

PanelLayout PlanPanels(const MapGrid& g) {
  PanelLayout best;
  best.scale = 0.0;
  for (int n = 1; n <= 200; ++n) {
    const int rows = (g.rows() + n - 1) / n;
    const double s = std::min(1400.0 / rows, (1600.0 / n - PanelLayout::kGap) / g.cols());
    if (s > best.scale) best = {s, n, rows, 0, 0};
  }
  best.panel_width = std::max(1, static_cast<int>(std::ceil(g.cols() * best.scale)));
  best.panel_height = std::max(1, static_cast<int>(std::ceil(best.panel_rows * best.scale)));
  return best;
}

// Every cell adds its colour to the panel pixel it falls in; a pixel shows
// the mean (as INTER_AREA would), built without a full-size cell image.
cv::Mat PanelImage(const CropMap& map, const PanelLayout& l) {
  const MapGrid& g = map.grid();
  cv::Mat sum(l.panel_height, l.width(), CV_32FC3, cv::Scalar::all(0));
  cv::Mat count(l.panel_height, l.width(), CV_32F, cv::Scalar(0));
  for (int row = 0; row < g.rows(); ++row) {
    const int p = row / l.panel_rows;
    const int y = std::min(l.panel_height - 1, static_cast<int>((l.panel_rows - 1 - (row - p * l.panel_rows)) * l.scale));
    const size_t row0 = g.Index({0, row});
    for (int col = 0; col < g.cols(); ++col) {
      const size_t i = row0 + static_cast<size_t>(col);
      cv::Vec3b colour = ColourOf(static_cast<CellClass>(map.layers().cls[i]));
      if (map.layers().treated[i] != 0) colour = Tinted(colour);
      const int x = p * (l.panel_width + PanelLayout::kGap) + std::min(l.panel_width - 1, static_cast<int>(col * l.scale));
      sum.at<cv::Vec3f>(y, x) += cv::Vec3f(colour[0], colour[1], colour[2]);
      count.at<float>(y, x) += 1.0f;
    }
  }
  cv::Mat image(sum.size(), CV_8UC3, cv::Scalar::all(255));
  for (int y = 0; y < sum.rows; ++y) {
    for (int x = 0; x < sum.cols; ++x) {
      const float n = count.at<float>(y, x);
      if (n > 0) image.at<cv::Vec3b>(y, x) = sum.at<cv::Vec3f>(y, x) / n;
    }
  }
  return image;
}

void Text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.5) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(20, 20, 20), 1, cv::LINE_AA);
}

std::string Metres(double m) {
  char buf[32];
  if (m < 1.0)
    std::snprintf(buf, sizeof buf, "%.0f cm", m * 100.0);
  else
    std::snprintf(buf, sizeof buf, "%g m", m);
  return buf;
}

void DrawScaleBar(cv::Mat& img, cv::Point left, double px_per_m, int max_px) {
  double length = 0.01;
  for (double c : {0.02, 0.05, 0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0}) {
    if (c * px_per_m <= max_px) length = c;
  }
  const int w = static_cast<int>(std::lround(length * px_per_m));
  const int half = std::max(1, w / 2);
  cv::rectangle(img, left, left + cv::Point(half, 8), cv::Scalar(20, 20, 20), cv::FILLED);
  cv::rectangle(img, left + cv::Point(half, 0), left + cv::Point(w, 8), cv::Scalar(20, 20, 20));
  Text(img, "0", left + cv::Point(-4, 26), 0.45);
  Text(img, Metres(length), left + cv::Point(w - 10, 26), 0.45);
}

void DrawNorthArrow(cv::Mat& img, cv::Point centre, double heading_deg) {
  // North is `heading` anticlockwise from the field +y axis (image up).
  const double a = heading_deg * std::numbers::pi / 180.0;
  const cv::Point2d dir(-std::sin(a), -std::cos(a));  // image coordinates, v down
  const cv::Point tip = centre + cv::Point(cvRound(28 * dir.x), cvRound(28 * dir.y));
  const cv::Point tail = centre - cv::Point(cvRound(28 * dir.x), cvRound(28 * dir.y));
  cv::arrowedLine(img, tail, tip, cv::Scalar(20, 20, 20), 2, cv::LINE_AA, 0, 0.3);
  Text(img, "N", tip + cv::Point(cvRound(14 * dir.x) - 5, cvRound(14 * dir.y) + 5), 0.55);
}

void DrawLegend(cv::Mat& img, int x, const CropMap& map, const Georeference* georef, const std::string& panels) {
  int y = kMargin + 14;
  Text(img, "plantscale crop map", {x, y}, 0.6);
  const std::pair<const char*, cv::Vec3b> keys[] = {{"soil", kSoil},
                                                    {"crop", kCrop},
                                                    {"weed", kWeed},
                                                    {"unknown (not seen)", kUnknown},
                                                    {"weed, treated", Tinted(kWeed)},
                                                    {"crop, treated", Tinted(kCrop)},
                                                    {"soil, treated", Tinted(kSoil)}};
  for (const auto& [name, colour] : keys) {
    y += 28;
    cv::rectangle(img, cv::Rect(x, y - 14, 22, 18), cv::Scalar(colour), cv::FILLED);
    cv::rectangle(img, cv::Rect(x, y - 14, 22, 18), cv::Scalar(20, 20, 20));
    Text(img, name, {x + 32, y});
  }
  int crops = 0, weeds = 0, unknown = 0;
  for (const MapPlant& p : map.plants()) {
    (p.kind == PlantKind::kCrop ? crops : p.kind == PlantKind::kWeed ? weeds : unknown) += 1;
  }
  const auto src = map.metadata().find("source");
  y += 40;
  Text(img,
       std::to_string(crops) + " crops, " + std::to_string(weeds) + " weeds" +
           (unknown > 0 ? ", " + std::to_string(unknown) + " unclassified" : ""),
       {x, y}, 0.45);
  Text(img, "cell " + Metres(map.grid().resolution_m()), {x, y += 22}, 0.45);
  if (src != map.metadata().end()) Text(img, "source: " + src->second, {x, y += 22}, 0.45);
  Text(img, "up = field +y (along rows)", {x, y += 22}, 0.45);
  if (!panels.empty()) Text(img, panels, {x, y += 22}, 0.45);
  if (georef != nullptr) {
    char heading[64];
    std::snprintf(heading, sizeof heading, "heading %.1f deg, EPSG:%d",
                  georef->options().heading_deg, georef->epsg());
    Text(img, heading, {x, y += 22}, 0.45);
    DrawNorthArrow(img, {x + 60, y + 70}, georef->options().heading_deg);
  }
}

}  // namespace

void WritePng(const CropMap& map, const Georeference* georef, const std::filesystem::path& file) {
  const MapGrid& g = map.grid();
  cv::Mat cells;
  double s = PixelsPerCell(g);
  std::string panels_note;
  if (NeedsPanels(g)) {
    const PanelLayout layout = PlanPanels(g);
    cells = PanelImage(map, layout);
    s = layout.scale;
    panels_note = std::to_string(layout.panels) + " panels of " + Metres(std::round(layout.panel_rows * g.resolution_m())) +
                  ", start left";
  } else {
    const cv::Size size(std::max(1, static_cast<int>(std::lround(g.cols() * s))),
                        std::max(1, static_cast<int>(std::lround(g.rows() * s))));
    cv::resize(CellImage(map), cells, size, 0, 0, s >= 1.0 ? cv::INTER_NEAREST : cv::INTER_AREA);
  }
  const cv::Size size = cells.size();
  const int height = std::max(size.height + kScaleBarHeight, panels_note.empty() ? 420 : 460) + 2 * kMargin;
  cv::Mat img(height, size.width + kLegendWidth + 3 * kMargin, CV_8UC3, cv::Scalar(255, 255, 255));
  cells.copyTo(img(cv::Rect(kMargin, kMargin, size.width, size.height)));
  cv::rectangle(img, cv::Rect(kMargin - 1, kMargin - 1, size.width + 2, size.height + 2),
                cv::Scalar(20, 20, 20));
  // Panels: a short bar, not one spanning panels side by side (x there is not along the run).
  const int bar_px = panels_note.empty() ? std::max(size.width, 60) : std::min(size.width, 300);
  DrawScaleBar(img, {kMargin, kMargin + size.height + 18}, s / g.resolution_m(), bar_px);
  DrawLegend(img, size.width + 2 * kMargin, map, georef, panels_note);
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", img, png)) throw MapIoError(file.string(), "cannot encode PNG");
  std::ofstream out(file, std::ios::binary);
  if (!out) throw MapIoError(file.string(), "cannot be created");
  out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  out.close();
  if (!out) throw MapIoError(file.string(), "write failed (disk full?)");
}

}  // namespace plantscale::maps
