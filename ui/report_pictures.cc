#include "ui/report_pictures.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_t.hpp>

#include "ui/palette.h"

namespace plantscale::ui {
namespace {

namespace tm = plantscale::telemetry;

cv::Scalar Bgr(Rgb c) { return {c.b * 255.0, c.g * 255.0, c.r * 255.0}; }
const cv::Scalar kWhite{255, 255, 255}, kBlack{0, 0, 0}, kGrey{120, 120, 120}, kInk{40, 40, 40};

std::string Fixed(double v, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << v;
  return out.str();
}

void Text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.45, cv::Scalar colour = kInk,
          int thickness = 1) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, thickness, cv::LINE_AA);
}

int TextWidth(const std::string& s, double scale = 0.45) {
  int base = 0;
  return cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base).width;
}

// A legend: colour swatch and words, left to right from `at`.
void Legend(cv::Mat& img, cv::Point at, const std::vector<std::pair<cv::Scalar, std::string>>& entries) {
  for (const auto& [colour, words] : entries) {
    cv::rectangle(img, {at.x, at.y - 11, 14, 14}, colour, cv::FILLED);
    cv::rectangle(img, {at.x, at.y - 11, 14, 14}, kInk, 1);
    Text(img, words, {at.x + 19, at.y});
    at.x += 19 + TextWidth(words) + 18;
  }
}

// A scale bar of `metres` at `ppm` pixels per metre, its left end at `at`.
void ScaleBar(cv::Mat& img, cv::Point at, double ppm, double metres, const std::string& label) {
  const int len = static_cast<int>(std::lround(metres * ppm));
  cv::rectangle(img, {at.x, at.y - 5, len, 5}, kBlack, cv::FILLED);
  cv::line(img, {at.x, at.y - 9}, {at.x, at.y}, kBlack, 1);
  cv::line(img, {at.x + len, at.y - 9}, {at.x + len, at.y}, kBlack, 1);
  Text(img, label, {at.x + len + 6, at.y});
}

cv::Scalar CellColour(uint8_t c) {
  switch (c) {
    case plantscale_map_tile_t::CELL_SOIL: return Bgr(palette::kSoil);
    case plantscale_map_tile_t::CELL_CROP: return Bgr(palette::kCrop);
    case plantscale_map_tile_t::CELL_WEED: return Bgr(palette::kWeed);
    case plantscale_map_tile_t::CELL_TREATED: return Bgr(palette::kTreated);
    default: return Bgr(palette::kUnknownCell);
  }
}

// Field → picture for one window: the run goes left to right (field y),
// across the bed top to bottom (field x).
struct Window {
  double y0_m = 0.0, x0_m = 0.0, ppm = 100.0;
  cv::Point origin;  // pixel of (x0, y0)
  cv::Size size;     // window size in pixels
  cv::Point2d At(double x, double y) const {
    return {origin.x + (y - y0_m) * ppm, origin.y + (x - x0_m) * ppm};
  }
};

void PaintTile(cv::Mat& img, const tm::MapTileDelta& t, const Window& w) {
  const size_t n = std::min(t.cells.size(), static_cast<size_t>(t.width) * static_cast<size_t>(t.height));
  const cv::Rect clip(w.origin, w.size);
  for (int j = 0; j < t.height; ++j) {
    const double y = t.origin_m.y() + j * t.resolution_m;
    const int u0 = static_cast<int>(std::floor(w.origin.x + (y - w.y0_m) * w.ppm));
    const int u1 = static_cast<int>(std::floor(w.origin.x + (y + t.resolution_m - w.y0_m) * w.ppm));
    if (u1 < clip.x || u0 >= clip.x + clip.width) continue;
    for (int i = 0; i < t.width; ++i) {
      const size_t k = static_cast<size_t>(j) * static_cast<size_t>(t.width) + static_cast<size_t>(i);
      const uint8_t c = k < n ? t.cells[k] : 0;
      if (c == plantscale_map_tile_t::CELL_UNKNOWN) continue;
      const double x = t.origin_m.x() + i * t.resolution_m;
      const int v0 = static_cast<int>(std::floor(w.origin.y + (x - w.x0_m) * w.ppm));
      const int v1 = static_cast<int>(std::floor(w.origin.y + (x + t.resolution_m - w.x0_m) * w.ppm));
      const cv::Rect r = cv::Rect(u0, v0, std::max(1, u1 - u0), std::max(1, v1 - v0)) & clip;
      if (r.area() > 0) img(r).setTo(CellColour(c));
    }
  }
}

bool TileInWindow(const tm::MapTileDelta& t, double y0, double y1) {
  return t.origin_m.y() + t.height * t.resolution_m >= y0 && t.origin_m.y() <= y1;
}

cv::Scalar PlantColour(const tm::PlantObservation& p) {
  return p.kind == tm::PlantKind::kCrop   ? Bgr(palette::kCrop)
         : p.kind == tm::PlantKind::kWeed ? Bgr(palette::kWeed)
                                          : Bgr(palette::kUnknownPlant);
}

// A plant marker's radius: the disc of the plant's area, at least 2 px.
int MarkerRadiusPx(const tm::PlantObservation& p, const Window& w) {
  return std::max(2, static_cast<int>(std::lround(std::sqrt(p.size_m2 / M_PI) * w.ppm)));
}

// Plant marker: a disc of the plant's area (at least 2 px), ringed blue when sprayed.
void DrawPlant(cv::Mat& img, const tm::PlantObservation& p, const Window& w) {
  const cv::Point2d c = w.At(p.position_m.x(), p.position_m.y());
  const int r = MarkerRadiusPx(p, w);
  cv::circle(img, c, r, PlantColour(p), cv::FILLED, cv::LINE_AA);
  cv::circle(img, c, r + (p.sprayed ? 1 : 0), p.sprayed ? Bgr(palette::kTreated) : kBlack, p.sprayed && r > 4 ? 2 : 1,
             cv::LINE_AA);
}

// A weed record that the summary takes for a crop (agronomy.h: a far view,
// or a crop in a gap's place): a ring of the crop colour, the record's size.
void DrawCropSeenAsWeed(cv::Mat& img, const tm::PlantObservation& p, const Window& w) {
  cv::circle(img, w.At(p.position_m.x(), p.position_m.y()), MarkerRadiusPx(p, w), Bgr(palette::kCrop), 2,
             cv::LINE_AA);
}

// The ellipse of covariance `c` (field x, y) at `centre`, `k` Mahalanobis
// radii, magnified `mag` times about its centre.
void DrawEllipse(cv::Mat& img, const cv::Point2d& centre, const Eigen::Matrix2d& c, double k, double mag,
                 double ppm, cv::Scalar colour, int thickness) {
  // In the picture u is field y and v is field x: swap the axes.
  Eigen::Matrix2d uv;
  uv << c(1, 1), c(1, 0), c(0, 1), c(0, 0);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(uv);
  const Eigen::Vector2d l = eig.eigenvalues().cwiseMax(0.0);
  const Eigen::Vector2d major = eig.eigenvectors().col(1);
  const double a = k * std::sqrt(l(1)) * mag * ppm, b = k * std::sqrt(l(0)) * mag * ppm;
  const double angle = std::atan2(major.y(), major.x()) * 180.0 / M_PI;
  cv::ellipse(img, cv::RotatedRect(cv::Point2f(static_cast<float>(centre.x), static_cast<float>(centre.y)),
                                   cv::Size2f(static_cast<float>(std::max(2.0, 2 * a)),
                                              static_cast<float>(std::max(2.0, 2 * b))),
                                   static_cast<float>(angle)),
              colour, thickness, cv::LINE_AA);
}

// Ticks every `step` metres along the top edge of a window, labelled.
void DistanceTicks(cv::Mat& img, const Window& w, double y0, double y1, double step, int label_every) {
  const int first = static_cast<int>(std::ceil(y0 / step - 1e-9));
  for (int i = first; i * step <= y1 + 1e-9; ++i) {
    const int u = static_cast<int>(std::lround(w.origin.x + (i * step - w.y0_m) * w.ppm));
    const bool labelled = i % label_every == 0;
    cv::line(img, {u, w.origin.y - (labelled ? 7 : 4)}, {u, w.origin.y - 1}, kInk, 1);
    if (labelled) {
      const std::string s = Fixed(i * step, step * label_every < 1.0 - 1e-9 ? 1 : 0) + " m";
      Text(img, s, {std::clamp(u - TextWidth(s, 0.4) / 2, 0, img.cols - TextWidth(s, 0.4)), w.origin.y - 9}, 0.4);
    }
  }
}

// Colour maps of the overview: stand 0 (red) → 1 (green) of the full stand;
// weed pressure 0 (pale) → max (dark red).
cv::Scalar StandColour(double f) {
  f = std::clamp(f, 0.0, 1.0);
  const double r = f < 0.5 ? 220.0 : 220.0 * (1.0 - f) * 2.0 + 30.0 * (f - 0.5) * 2.0;
  const double g = f < 0.5 ? 60.0 + 2.0 * f * 160.0 : 220.0 - 60.0 * (f - 0.5) * 2.0;
  return {40.0, g, r};
}
cv::Scalar PressureColour(double f) {
  f = std::clamp(f, 0.0, 1.0);
  return {235.0 - 215.0 * f, 235.0 - 215.0 * f, 245.0 - 95.0 * f};
}

double NiceStep(double span, int ticks) {
  const double raw = span / std::max(1, ticks);
  const double p = std::pow(10.0, std::floor(std::log10(std::max(raw, 1e-9))));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10.0 * p;
}

}  // namespace

CloseupSnapshot TakeCloseup(const review::RunModel& model, double y_m, double half_length_m, std::string reason) {
  CloseupSnapshot s;
  s.reason = std::move(reason);
  s.distance_m = model.distance_m();
  s.y_m = y_m;
  s.pose = model.pose();
  s.grid = model.grid() ? model.grid() : model.truth();
  const double y0 = y_m - half_length_m - 0.3, y1 = y_m + half_length_m + 0.3;
  for (const auto& [id, r] : model.plants()) {
    if (r.plant.position_m.y() >= y0 && r.plant.position_m.y() <= y1) s.plants.push_back(r.plant);
  }
  for (const auto& [key, t] : model.tiles()) {
    if (TileInWindow(t, y0, y1)) s.tiles.push_back(t);
  }
  return s;
}

cv::Mat DrawOverview(const review::AgronomySummary& a, const PictureOptions& o) {
  const double length = std::max(1.0, a.cells_along * a.cell_length_m);
  // Metres per line: 50, 100, 200, 500, … so that at most max_overview_lines.
  double per_line = 50.0;
  while (length / per_line > o.max_overview_lines) per_line *= per_line == 50.0 || per_line == 500.0 ? 2.0 : 2.5;
  per_line = std::min(per_line, std::max(50.0, std::ceil(length / 10.0) * 10.0));
  const int lines = static_cast<int>(std::ceil(length / per_line - 1e-9));
  const int rows = std::max<int>(1, static_cast<int>(a.rows.size()));
  const int band = 11, left = 90, top = 54;
  const double ppm = o.overview_width_px / per_line;
  const int line_h = 2 * rows * band + 4 + 26;
  cv::Mat img(top + lines * line_h + 60, left + o.overview_width_px + 30, CV_8UC3, kWhite);
  Text(img, "Overview: crop stand (top band of each line, one band per row) and weed pressure (bottom), per " +
                Fixed(a.cell_length_m, 0) + " m x row cell; " + Fixed(per_line, 0) + " m per line",
       {10, 20}, 0.5);
  // Full stand: one plant per spacing; pressure scale: the 95th percentile of weeds per m².
  double spacing = 0.0;
  for (const review::RowAgronomy& r : a.rows) spacing += r.plant_spacing_m / std::max<size_t>(1, a.rows.size());
  const double full = spacing > 0.0 ? a.cell_length_m / spacing : 1.0;
  std::vector<double> density;
  const double cell_area = a.cell_length_m * a.row_spacing_m;
  for (const review::HeatCell& c : a.cells) density.push_back(c.weeds / std::max(1e-9, cell_area));
  std::sort(density.begin(), density.end());
  double pressure_max = density.empty() ? 1.0 : density[static_cast<size_t>(0.95 * (density.size() - 1))];
  pressure_max = std::max(pressure_max, 5.0);
  for (int line = 0; line < lines; ++line) {
    const int y_top = top + line * line_h;
    const double m0 = line * per_line;
    Text(img, Fixed(m0, 0) + " m", {10, y_top + rows * band + 4}, 0.45);
    for (double m = 0.0; m <= per_line + 1e-9; m += NiceStep(per_line, 10)) {
      if (m0 + m > length + 1e-9) break;
      const int u = left + static_cast<int>(std::lround(m * ppm));
      cv::line(img, {u, y_top - 4}, {u, y_top - 1}, kInk, 1);
      if (m > 0.0) Text(img, Fixed(m0 + m, 0), {u - 10, y_top - 6}, 0.35, kGrey);
    }
    for (size_t ri = 0; ri < a.rows.size(); ++ri) {
      for (int c = static_cast<int>(m0 / a.cell_length_m);
           c < a.cells_along && c * a.cell_length_m < m0 + per_line - 1e-9; ++c) {
        const review::HeatCell& h = a.cells[ri * static_cast<size_t>(a.cells_along) + static_cast<size_t>(c)];
        const int u0 = left + static_cast<int>(std::lround((c * a.cell_length_m - m0) * ppm));
        const int u1 = left + static_cast<int>(std::lround(((c + 1) * a.cell_length_m - m0) * ppm));
        const cv::Rect stand(u0, y_top + static_cast<int>(ri) * band, std::max(1, u1 - u0), band - 1);
        cv::rectangle(img, stand, StandColour(h.crop / full), cv::FILLED);
        const cv::Rect weed(u0, y_top + rows * band + 4 + static_cast<int>(ri) * band, std::max(1, u1 - u0),
                            band - 1);
        cv::rectangle(img, weed, PressureColour(h.weeds / cell_area / pressure_max), cv::FILLED);
      }
    }
  }
  // Legend: two colour ramps.
  const int ly = top + lines * line_h + 16;
  Text(img, "stand:", {10, ly + 10});
  for (int i = 0; i < 100; ++i) cv::line(img, {left + i, ly}, {left + i, ly + 12}, StandColour(i / 99.0));
  Text(img, "0", {left - 2, ly + 26}, 0.4);
  Text(img, Fixed(full, 1) + " plants/" + Fixed(a.cell_length_m, 0) + " m (full)", {left + 80, ly + 26}, 0.4);
  const int lx = left + 330;
  Text(img, "weeds:", {lx - 60, ly + 10});
  for (int i = 0; i < 100; ++i) cv::line(img, {lx + i, ly}, {lx + i, ly + 12}, PressureColour(i / 99.0));
  Text(img, "0", {lx - 2, ly + 26}, 0.4);
  Text(img, Fixed(pressure_max, 0) + "+ /m2", {lx + 85, ly + 26}, 0.4);
  Text(img, "rows top to bottom: " + (a.rows.empty() ? std::string("none")
                                                       : std::to_string(a.rows.front().row) + " .. " +
                                                             std::to_string(a.rows.back().row)),
       {lx + 200, ly + 10}, 0.4);
  return img;
}

cv::Mat DrawStrips(const review::RunModel& model, const review::AgronomySummary& a, const std::vector<double>& starts,
                   double x_lo, double x_hi, const PictureOptions& o) {
  const int left = 16, top = 34, label_h = 24, gap = 10;
  const double ppm = (o.strip_width_px - 2 * left) / o.strip_length_m;
  const int strip_h = static_cast<int>(std::lround((x_hi - x_lo) * ppm));
  const int n = static_cast<int>(starts.size());
  const int key_h = a.weed_records_taken_as_crops.empty() ? 0 : 22;  // their key's line
  cv::Mat img(top + n * (strip_h + label_h + gap) + 40 + key_h, o.strip_width_px, CV_8UC3, kWhite);
  Text(img, "Bed, " + Fixed(o.strip_length_m, 0) + " m per strip, the run left to right; y along the bed", {left, 20},
       0.5);
  for (int s = 0; s < n; ++s) {
    Window w;
    w.y0_m = starts[static_cast<size_t>(s)];
    w.x0_m = x_lo;
    w.ppm = ppm;
    w.origin = {left, top + s * (strip_h + label_h + gap) + label_h};
    w.size = {static_cast<int>(std::lround(o.strip_length_m * ppm)), strip_h};
    const cv::Rect frame(w.origin, w.size);
    img(frame).setTo(Bgr(palette::kUnknownCell));
    const double y1 = w.y0_m + o.strip_length_m;
    for (const auto& [key, t] : model.tiles()) {
      if (TileInWindow(t, w.y0_m, y1)) PaintTile(img, t, w);
    }
    cv::Mat roi = img(frame);
    Window local = w;
    local.origin = {0, 0};
    for (const auto& [id, r] : model.plants()) {
      const double y = r.plant.position_m.y();
      if (y < w.y0_m - 0.2 || y > y1 + 0.2) continue;
      if (a.weed_records_taken_as_crops.count(r.plant.id)) {
        DrawCropSeenAsWeed(roi, r.plant, local);
      } else {
        DrawPlant(roi, r.plant, local);
      }
    }
    cv::rectangle(img, frame, kInk, 1);
    DistanceTicks(img, w, w.y0_m, y1, 0.5, 2);
  }
  const int by = static_cast<int>(img.rows) - 14;
  ScaleBar(img, {left, by}, ppm, 1.0, "1 m");
  Legend(img, {left + static_cast<int>(ppm) + 60, by},
         {{Bgr(palette::kCrop), "crop"},
          {Bgr(palette::kWeed), "weed"},
          {Bgr(palette::kTreated), "treated (cells; ring: plant sprayed)"},
          {Bgr(palette::kSoil), "soil"},
          {Bgr(palette::kUnknownCell), "not mapped"}});
  if (!a.weed_records_taken_as_crops.empty()) {  // their key, on a line of its own
    const cv::Point at{left, by - 22};
    cv::circle(img, {at.x + 7, at.y - 4}, 6, Bgr(palette::kCrop), 2, cv::LINE_AA);
    Text(img, "weed record taken for a crop (a far view, or in a gap's place), not counted as a weed",
         {at.x + 19, at.y});
  }
  return img;
}

cv::Mat DrawCloseup(const CloseupSnapshot& s, double x_lo, double x_hi, const PictureOptions& o) {
  const int left = 12, top = 56;
  // The plants in view and, when it is near (the camera looks ahead), the vehicle.
  double y_lo = s.y_m - 0.5 * o.closeup_length_m, y_hi = s.y_m + 0.5 * o.closeup_length_m;
  if (s.pose && s.pose->y_m < y_lo && s.pose->y_m > y_lo - o.closeup_length_m) y_lo = s.pose->y_m - 0.3;
  const double length = y_hi - y_lo;
  const double ppm = (o.closeup_width_px - 2 * left) / length;
  Window w;
  w.y0_m = y_lo;
  w.x0_m = x_lo;
  w.ppm = ppm;
  w.origin = {left, top};
  w.size = {static_cast<int>(std::lround(length * ppm)), static_cast<int>(std::lround((x_hi - x_lo) * ppm))};
  cv::Mat img(top + w.size.height + 84, o.closeup_width_px, CV_8UC3, kWhite);
  Text(img, s.reason, {left, 18}, 0.5);
  Text(img, "at " + Fixed(s.distance_m, 1) + " m driven; " + Fixed(100.0 * o.ellipse_confidence, 0) +
                " % ellipses MAGNIFIED x" + Fixed(o.ellipse_magnification, 0),
       {left, 36}, 0.5, {0, 0, 160});
  const cv::Rect frame(w.origin, w.size);
  img(frame).setTo(Bgr(palette::kUnknownCell));
  for (const tm::MapTileDelta& t : s.tiles) PaintTile(img, t, w);
  cv::Mat roi = img(frame);
  Window local = w;
  local.origin = {0, 0};
  const double k = std::sqrt(review::EllipseScale2d(o.ellipse_confidence));
  bool plant_covariance = false;
  for (const tm::PlantObservation& p : s.plants) plant_covariance |= p.covariance.trace() > 0.0;
  for (const tm::PlantObservation& p : s.plants) {
    DrawPlant(roi, p, local);
    DrawEllipse(roi, local.At(p.position_m.x(), p.position_m.y()), p.covariance, k, o.ellipse_magnification,
                ppm, Bgr(palette::kPlantEllipse), 2);
  }
  // The vehicle's ellipse: its pose covariance, else (a log without it) the
  // tracker's covariance of offset and forward position.
  bool pose_covariance = false, grid_ellipse = false;
  if (s.pose) {
    const cv::Point2d c = local.At(s.pose->x_m, s.pose->y_m);
    cv::drawMarker(roi, c, Bgr(palette::kVehicle), cv::MARKER_CROSS, 16, 2);
    Eigen::Matrix2d cov = s.pose->covariance.topLeftCorner<2, 2>();
    pose_covariance = cov.trace() > 0.0;
    if (!pose_covariance && s.grid) {
      cov << s.grid->covariance(0, 0), s.grid->covariance(0, 1), s.grid->covariance(1, 0), s.grid->covariance(1, 1);
      grid_ellipse = cov.trace() > 0.0;
    }
    DrawEllipse(roi, c, cov, k, o.ellipse_magnification, ppm, Bgr(palette::kVehicle), 2);
  }
  cv::rectangle(img, frame, kInk, 1);
  DistanceTicks(img, w, w.y0_m, w.y0_m + length, 0.1, 5);
  const int by = top + w.size.height + 24;
  ScaleBar(img, {left, by}, ppm, 0.5, "0.5 m");
  Legend(img, {left + static_cast<int>(0.5 * ppm) + 60, by},
         {{Bgr(palette::kPlantEllipse), "plant ellipse"}, {Bgr(palette::kVehicle), "vehicle + ellipse"}});
  std::string note;
  if (s.grid) {
    note = "tracker sd: offset " + Fixed(1e3 * std::sqrt(std::max(0.0, s.grid->covariance(0, 0))), 1) +
           " mm, forward " + Fixed(1e3 * std::sqrt(std::max(0.0, s.grid->covariance(1, 1))), 1) + " mm";
  }
  if (s.pose && pose_covariance) {
    note += (note.empty() ? "" : "; ") + std::string("vehicle sd x ") +
            Fixed(1e3 * std::sqrt(std::max(0.0, s.pose->covariance(0, 0))), 1) + " mm, y " +
            Fixed(1e3 * std::sqrt(std::max(0.0, s.pose->covariance(1, 1))), 1) + " mm";
  }
  Text(img, note, {left, by + 22}, 0.45);
  std::string note2;
  if (grid_ellipse) note2 = "vehicle ellipse: tracker offset/forward covariance";
  if (!plant_covariance && !s.plants.empty()) {
    note2 += (note2.empty() ? "" : "; ") + std::string("no plant covariances in the log");
  }
  Text(img, note2, {left, by + 42}, 0.4);
  return img;
}

cv::Mat DrawOffsetTrace(const review::RunModel& model, const PictureOptions& o) {
  const std::vector<review::TraceSample>& est = !model.trace().empty() ? model.trace() : model.truth_trace();
  const bool has_truth = !model.trace().empty() && !model.truth_trace().empty();
  const int left = 70, right = 20, top = 34, bottom = 46;
  cv::Mat img(o.trace_height_px, o.trace_width_px, CV_8UC3, kWhite);
  const int pw = o.trace_width_px - left - right, ph = o.trace_height_px - top - bottom;
  Text(img, std::string("Lateral offset against distance: ") +
                (model.trace().empty() ? "simulator truth" : "tracker") + " (blue), +-2 sd band" +
                (has_truth ? ", truth (black)" : "") + "; one column per pixel",
       {10, 20}, 0.5);
  cv::rectangle(img, {left, top, pw, ph}, kInk, 1);
  if (est.empty()) {
    Text(img, "no grid estimates in the log", {left + 20, top + ph / 2});
    return img;
  }
  const double d0 = 0.0, d1 = std::max(1.0, est.back().distance_m);
  // Per column: mean offset, mean sd, truth mean.
  std::vector<double> sum(pw, 0.0), sd(pw, 0.0), tsum(pw, 0.0);
  std::vector<int> cnt(pw, 0), tcnt(pw, 0);
  const auto col = [&](double d) { return std::clamp(static_cast<int>((d - d0) / (d1 - d0) * pw), 0, pw - 1); };
  for (const review::TraceSample& t : est) {
    const int c = col(t.distance_m);
    sum[c] += t.offset_m, sd[c] += t.offset_sigma_m, ++cnt[c];
  }
  if (has_truth) {
    for (const review::TraceSample& t : model.truth_trace()) {
      const int c = col(t.distance_m);
      tsum[c] += t.offset_m, ++tcnt[c];
    }
  }
  double lim = 0.01;
  for (int c = 0; c < pw; ++c) {
    if (cnt[c] == 0) continue;
    lim = std::max(lim, std::abs(sum[c] / cnt[c]) + 2.0 * sd[c] / cnt[c]);
  }
  lim = std::min(lim * 1.1, 0.5);
  const auto v = [&](double off) {
    return top + static_cast<int>(std::lround((0.5 - 0.5 * std::clamp(off / lim, -1.0, 1.0)) * ph));
  };
  const double tick = NiceStep(2e3 * lim, 6);
  for (double mm = -std::floor(1e3 * lim / tick) * tick; mm <= 1e3 * lim + 1e-9; mm += tick) {
    const int y = v(mm * 1e-3);
    cv::line(img, {left, y}, {left + pw, y}, {225, 225, 225}, 1);
    Text(img, Fixed(mm, 0), {left - 8 - TextWidth(Fixed(mm, 0), 0.4), y + 4}, 0.4);
  }
  Text(img, "mm", {8, top + ph / 2}, 0.45);
  const double dtick = NiceStep(d1 - d0, 10);
  for (double d = 0.0; d <= d1 + 1e-9; d += dtick) {
    const int x = left + static_cast<int>(std::lround(d / d1 * pw));
    cv::line(img, {x, top + ph}, {x, top + ph + 5}, kInk, 1);
    Text(img, Fixed(d, 0), {x - TextWidth(Fixed(d, 0), 0.4) / 2, top + ph + 19}, 0.4);
  }
  Text(img, "distance driven, m", {left + pw / 2 - 60, top + ph + 38}, 0.45);
  std::optional<cv::Point> prev, tprev;
  std::optional<std::pair<cv::Point, cv::Point>> band;  // previous column's low and high
  for (int c = 0; c < pw; ++c) {
    if (cnt[c] == 0) continue;
    const double m = sum[c] / cnt[c], s2 = 2.0 * sd[c] / cnt[c];
    const cv::Point lo(left + c, v(m - s2)), hi(left + c, v(m + s2));
    if (band) {
      const std::vector<cv::Point> quad{band->first, band->second, hi, lo};
      cv::fillConvexPoly(img, quad, {250, 210, 170});
    }
    cv::line(img, lo, hi, {250, 210, 170}, 1);
    band = std::make_pair(lo, hi);
  }
  for (int c = 0; c < pw; ++c) {
    if (cnt[c] > 0) {
      const cv::Point p(left + c, v(sum[c] / cnt[c]));
      if (prev) cv::line(img, *prev, p, {200, 90, 20}, 1, cv::LINE_AA);
      prev = p;
    }
    if (tcnt[c] > 0) {
      const cv::Point p(left + c, v(tsum[c] / tcnt[c]));
      if (tprev) cv::line(img, *tprev, p, kBlack, 1, cv::LINE_AA);
      tprev = p;
    }
  }
  return img;
}

cv::Mat DrawSizeHistograms(const review::AgronomySummary& a) {
  const int w = 520, h = 260, left = 50, top = 36, pw = 440, ph = 170;
  cv::Mat img(h, 2 * w, CV_8UC3, kWhite);
  const auto panel = [&](int x0, const review::SizeStats& s, const std::string& title, cv::Scalar colour) {
    Text(img, title, {x0 + 10, 20}, 0.5);
    cv::rectangle(img, {x0 + left, top, pw, ph}, kInk, 1);
    const int bins = static_cast<int>(s.histogram.size());
    if (bins == 0 || s.count == 0) {
      Text(img, "none", {x0 + left + 20, top + ph / 2});
      return;
    }
    const int peak = std::max(1, *std::max_element(s.histogram.begin(), s.histogram.end()));
    const double bw = static_cast<double>(pw) / bins;
    for (int b = 0; b < bins; ++b) {
      const int bh = static_cast<int>(std::lround(static_cast<double>(s.histogram[b]) / peak * (ph - 10)));
      cv::rectangle(img,
                    cv::Rect(x0 + left + static_cast<int>(b * bw) + 1, top + ph - bh, std::max(1, static_cast<int>(bw) - 2), bh),
                    colour, cv::FILLED);
    }
    Text(img, std::to_string(peak), {x0 + left - 8 - TextWidth(std::to_string(peak), 0.4), top + 14}, 0.4);
    Text(img, "0", {x0 + left - 16, top + ph}, 0.4);
    for (int b = 0; b <= bins; b += 5) {
      const int x = x0 + left + static_cast<int>(b * bw);
      cv::line(img, {x, top + ph}, {x, top + ph + 4}, kInk, 1);
      const std::string label = Fixed(100.0 * b * s.bin_m, 0) + (b == bins ? "+" : "");
      Text(img, label, {x - TextWidth(label, 0.4) / 2, top + ph + 17}, 0.4);
    }
    for (const double q : {s.q1_m, s.median_m, s.q3_m}) {
      const int x = x0 + left + static_cast<int>(std::lround(q / s.bin_m * bw));
      if (x > x0 + left + pw) continue;
      cv::line(img, {x, top}, {x, top + ph}, kBlack, 1);
    }
    Text(img, "radius, cm; n " + std::to_string(s.count) + ", median " + Fixed(100 * s.median_m, 1) + " (Q1 " +
                  Fixed(100 * s.q1_m, 1) + ", Q3 " + Fixed(100 * s.q3_m, 1) + ")",
         {x0 + left, top + ph + 40}, 0.42);
  };
  panel(0, a.crop_size, "Crop leaf-tip radius", Bgr(palette::kCrop));
  panel(w, a.weed_size, "Weed radius (disc of equal area)", Bgr(palette::kWeed));
  return img;
}

}  // namespace plantscale::ui
