#include "evaluation/treatment_score.h"

#include <opencv2/imgproc.hpp>
#include <cmath>
#include <limits>

namespace plantscale::app {

namespace {

struct Raster {
  double x0, y0, cell;
  cv::Mat mask;  // CV_8UC1, 255 sprayed; row = along y

  cv::Point2d ToPixel(const Eigen::Vector2d& p) const {  // pixel centres at integers
    return {(p.x() - x0) / cell - 0.5, (p.y() - y0) / cell - 0.5};
  }
  bool At(const Eigen::Vector2d& p, int& col, int& row) const {
    col = static_cast<int>(std::floor((p.x() - x0) / cell));
    row = static_cast<int>(std::floor((p.y() - y0) / cell));
    return col >= 0 && row >= 0 && col < mask.cols && row < mask.rows;
  }
};

constexpr int kShift = 4;  // sub-pixel bits for cv::fillConvexPoly

void Paint(Raster& r, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double width) {
  Eigen::Vector2d d = b - a;
  const double len = d.norm();
  d = len > 1e-9 ? Eigen::Vector2d(d / len) : Eigen::Vector2d(0.0, 1.0);
  const Eigen::Vector2d n(-d.y() * 0.5 * width, d.x() * 0.5 * width);
  const Eigen::Vector2d corners[4] = {a + n, b + n, b - n, a - n};
  cv::Point pts[4];
  for (int i = 0; i < 4; ++i) {
    const cv::Point2d p = r.ToPixel(corners[i]);
    pts[i] = cv::Point(static_cast<int>(std::lround(p.x * (1 << kShift))),
                       static_cast<int>(std::lround(p.y * (1 << kShift))));
  }
  cv::fillConvexPoly(r.mask, pts, 4, cv::Scalar(255), cv::LINE_8, kShift);
}

// The crop whose leaf-tip outline comes nearest a weed's root, and that
// root's distance beyond the outline (≤ 0: the weed is under the crop's
// leaves); null and ∞ when no crop stands within half a metre along.
struct NearestOutline {
  const sim::Plant* crop = nullptr;
  double gap_m = std::numeric_limits<double>::infinity();
};
NearestOutline NearestCropOutline(const sim::Field& field, const sim::Plant& weed) {
  const auto [b, e] = field.PlantsBetween(weed.position_m.y() - 0.5, weed.position_m.y() + 0.5);
  NearestOutline nearest;
  for (size_t i = b; i < e; ++i) {
    const sim::Plant& p = field.plants()[i];
    if (p.cls != sim::PlantClass::kCrop) continue;
    const double gap = (weed.position_m - (p.position_m + p.lean_m)).norm() - p.radius_m;
    if (gap < nearest.gap_m) nearest = {&p, gap};
  }
  return nearest;
}

// Whether the spray covers field point `p` (and its raster cell).
bool SprayedAt(const Raster& r, const Eigen::Vector2d& p, int& col, int& row) {
  return r.At(p, col, row) && r.mask.at<uint8_t>(row, col) != 0;
}

// Centre of the bounding box of the sprayed patch holding pixel (col, row),
// within a window of ± half_size_m so that patches joined to a neighbour's
// (through a weed between them) are cut at the window.
Eigen::Vector2d PatchCentre(const Raster& r, int col, int row, double half_size_m) {
  const int h = std::max(1, static_cast<int>(std::lround(half_size_m / r.cell)));
  const cv::Rect window = cv::Rect(col - h, row - h, 2 * h + 1, 2 * h + 1) &
                          cv::Rect(0, 0, r.mask.cols, r.mask.rows);
  cv::Mat labels, stats, centroids;
  cv::connectedComponentsWithStats(r.mask(window), labels, stats, centroids, 8, CV_32S);
  const int k = labels.at<int>(row - window.y, col - window.x);
  const double left = window.x + stats.at<int>(k, cv::CC_STAT_LEFT);
  const double top = window.y + stats.at<int>(k, cv::CC_STAT_TOP);
  return {r.x0 + (left + 0.5 * stats.at<int>(k, cv::CC_STAT_WIDTH)) * r.cell,
          r.y0 + (top + 0.5 * stats.at<int>(k, cv::CC_STAT_HEIGHT)) * r.cell};
}

// Distance from p to the centre of the nearest sprayed cell within ± half_size_m.
double NearestSpray(const Raster& r, const Eigen::Vector2d& p, double half_size_m) {
  const int h = std::max(1, static_cast<int>(std::lround(half_size_m / r.cell)));
  const int col = static_cast<int>(std::floor((p.x() - r.x0) / r.cell));
  const int row = static_cast<int>(std::floor((p.y() - r.y0) / r.cell));
  double best = std::numeric_limits<double>::infinity();
  for (int v = std::max(0, row - h); v <= std::min(r.mask.rows - 1, row + h); ++v) {
    for (int u = std::max(0, col - h); u <= std::min(r.mask.cols - 1, col + h); ++u) {
      if (r.mask.at<uint8_t>(v, u) == 0) continue;
      const Eigen::Vector2d c(r.x0 + (u + 0.5) * r.cell, r.y0 + (v + 0.5) * r.cell);
      best = std::min(best, (c - p).norm());
    }
  }
  return best;
}

}  // namespace

void SprayScore::Merge(const SprayScore& o) {
  crop_plants += o.crop_plants;
  crop_hits += o.crop_hits;
  weeds += o.weeds;
  weed_hits += o.weed_hits;
  weeds_clear += o.weeds_clear;
  weed_hits_clear += o.weed_hits_clear;
  weeds_touching += o.weeds_touching;
  weed_hits_touching += o.weed_hits_touching;
  weed_hits_touching_crop_dry += o.weed_hits_touching_crop_dry;
  error_sum += o.error_sum;
  error2_sum += o.error2_sum;
  centre_error_sum += o.centre_error_sum;
  centre_error2_sum += o.centre_error2_sum;
  sprayed_bed_m2 += o.sprayed_bed_m2;
  bed_m2 += o.bed_m2;
  missed.insert(missed.end(), o.missed.begin(), o.missed.end());
}

SprayScore ScoreSpray(const sim::Field& field, std::span<const treatment::Shot> shots,
                      const SprayScoreRegion& region) {
  const double margin = 0.5;
  Raster r;
  r.cell = region.raster_m;
  r.x0 = -region.bed_half_width_m - margin;
  r.y0 = region.y_begin_m - margin;
  const int cols = static_cast<int>(std::ceil(2 * (region.bed_half_width_m + margin) / r.cell));
  const int rows =
      static_cast<int>(std::ceil((region.y_end_m - region.y_begin_m + 2 * margin) / r.cell));
  r.mask = cv::Mat(std::max(rows, 1), cols, CV_8UC1, cv::Scalar(0));
  for (const treatment::Shot& s : shots) {
    for (size_t i = 0; i + 1 < s.path_field_m.size(); ++i) {
      Paint(r, s.path_field_m[i], s.path_field_m[i + 1], s.width_m);
    }
    if (s.path_field_m.size() == 1) Paint(r, s.path_field_m[0], s.path_field_m[0], s.width_m);
  }

  SprayScore score;
  const auto in_region = [&](const Eigen::Vector2d& p) {
    return p.y() >= region.y_begin_m && p.y() < region.y_end_m &&
           std::abs(p.x()) <= region.bed_half_width_m;
  };
  for (const sim::Plant& p : field.plants()) {
    if (!in_region(p.position_m)) continue;
    int col = 0, row = 0;
    const bool sprayed = SprayedAt(r, p.position_m, col, row);
    if (p.cls == sim::PlantClass::kWeed) {
      ++score.weeds;
      score.weed_hits += sprayed;
      const NearestOutline crop = NearestCropOutline(field, p);
      if (crop.gap_m > 0.0) {  // not under a crop's leaves
        ++score.weeds_clear;
        score.weed_hits_clear += sprayed;
        if (crop.gap_m <= p.radius_m) {  // its outline touches the crop's
          int c = 0, w = 0;
          ++score.weeds_touching;
          score.weed_hits_touching += sprayed;
          score.weed_hits_touching_crop_dry += sprayed && !SprayedAt(r, crop.crop->position_m, c, w);
        }
      }
      continue;
    }
    ++score.crop_plants;
    if (!sprayed) {
      score.missed.push_back({0, p.id, p.position_m, p.radius_m,
                              NearestSpray(r, p.position_m, region.patch_half_size_m)});
      continue;
    }
    ++score.crop_hits;
    const Eigen::Vector2d centre = PatchCentre(r, col, row, region.patch_half_size_m);
    const Eigen::Vector2d e = centre - p.position_m;
    score.error_sum += e;
    score.error2_sum += e.cwiseAbs2();
    const Eigen::Vector2d ec = centre - (p.position_m + p.lean_m);
    score.centre_error_sum += ec;
    score.centre_error2_sum += ec.cwiseAbs2();
  }
  // Treated area of the bed.
  int bed = 0, sprayed = 0;
  for (int row = 0; row < r.mask.rows; ++row) {
    const double y = r.y0 + (row + 0.5) * r.cell;
    if (y < region.y_begin_m || y >= region.y_end_m) continue;
    for (int col = 0; col < r.mask.cols; ++col) {
      const double x = r.x0 + (col + 0.5) * r.cell;
      if (std::abs(x) > region.bed_half_width_m) continue;
      ++bed;
      sprayed += r.mask.at<uint8_t>(row, col) != 0;
    }
  }
  score.bed_m2 = bed * r.cell * r.cell;
  score.sprayed_bed_m2 = sprayed * r.cell * r.cell;
  return score;
}

}  // namespace plantscale::app
