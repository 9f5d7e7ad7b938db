#include "engine/vision/blobs.h"

#include <array>

#include "engine/common/check.h"
#include "engine/vision/row_bits.h"

namespace plantscale::vision {
namespace {

// Σ (a + k)² for k = 0..n-1.
double SumOfSquares(double a, double n) {
  return n * a * a + a * n * (n - 1.0) + (n - 1.0) * n * (2.0 * n - 1.0) / 6.0;
}

// Moore neighbours clockwise on screen (v grows downwards), starting west.
const std::array<cv::Point, 8> kClockwise = {{
    {-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}, {1, 1}, {0, 1}, {-1, 1}}};

int DirectionIndex(cv::Point d) {
  for (int i = 0; i < 8; ++i) {
    if (kClockwise[static_cast<size_t>(i)] == d) return i;
  }
  PLANTSCALE_CHECK(false, "not a neighbour offset");
}

bool IsSet(const cv::Mat& mask, cv::Point p) {
  return p.x >= 0 && p.y >= 0 && p.x < mask.cols && p.y < mask.rows &&
         mask.ptr<uint8_t>(p.y)[p.x] != 0;
}

// Clockwise search around `c` starting after the background pixel at `back`.
int NextBoundaryDirection(const cv::Mat& mask, cv::Point c, int back) {
  for (int k = 1; k <= 8; ++k) {
    const int d = (back + k) % 8;
    if (IsSet(mask, c + kClockwise[static_cast<size_t>(d)])) return d;
  }
  return -1;  // an isolated pixel
}

// Run r's pixels into the moments m: n, Σu, Σv, Σu², Σv², Σuv (pixel centres).
void AddRun(const detail::RowRun& r, double* m) {
  const double n = r.u_end - r.u_begin, vc = r.v + 0.5;
  const double su = n * (r.u_begin + r.u_end) / 2.0;
  m[0] += n;
  m[1] += su;
  m[2] += n * vc;
  m[3] += SumOfSquares(r.u_begin + 0.5, n);
  m[4] += n * vc * vc;
  m[5] += su * vc;
}

// Centroid and second central moments from AddRun's sums (m[0] > 0).
void MomentsToCentroid(const double* m, Eigen::Vector2d& centroid, Eigen::Matrix2d& covariance) {
  centroid = {m[1] / m[0], m[2] / m[0]};
  const double cu = centroid.x(), cv_ = centroid.y();
  covariance << m[3] / m[0] - cu * cu, m[5] / m[0] - cu * cv_, m[5] / m[0] - cu * cv_,
      m[4] / m[0] - cv_ * cv_;
}

}  // namespace

OptionErrors BlobOptions::Validate() const {
  OptionErrors e;
  if (min_area_px < 1) e.push_back({"min_area_px", "must be >= 1 (got " +
                                                       std::to_string(min_area_px) + ")"});
  return e;
}

BlobExtractor::BlobExtractor(const BlobOptions& options) : options_(options) {
  ThrowIfInvalid("blob options", options_.Validate());
}

BlobCore CoreOf(const Blob& blob) {
  if (blob.core_area_px < 0) return {static_cast<double>(blob.area_px), blob.centroid_px, blob.covariance_px2};
  return {static_cast<double>(blob.core_area_px), blob.core_centroid_px, blob.core_covariance_px2};
}

void BlobExtractor::SetCores(std::span<const detail::RowRun> core) {
  std::vector<double>& m = core_moments_;
  m.assign(6 * static_cast<size_t>(count_), 0.0);
  size_t j = 0;
  for (const Run& c : core) {
    while (j < runs_.size() && (runs_[j].v < c.v || (runs_[j].v == c.v && runs_[j].u_end <= c.u_begin))) ++j;
    if (j == runs_.size()) break;
    const Run& r = runs_[j];
    if (r.v != c.v || r.u_begin > c.u_begin || r.u_end < c.u_end) continue;  // not inside: no blob of it
    const int b = slot_blob_[static_cast<size_t>(run_blob_[static_cast<size_t>(parent_[j])])];
    if (b >= 0) AddRun(c, &m[6 * static_cast<size_t>(b)]);
  }
  for (int i = 0; i < count_; ++i) {
    Blob& blob = pool_[static_cast<size_t>(i)];
    const double* s = &m[6 * static_cast<size_t>(i)];
    blob.core_area_px = static_cast<int>(s[0]);
    blob.core_centroid_px = blob.centroid_px;
    blob.core_covariance_px2.setZero();
    if (s[0] > 0.0) MomentsToCentroid(s, blob.core_centroid_px, blob.core_covariance_px2);
  }
}

void BlobExtractor::SetClasses(const cv::Mat& classes, const cv::Mat& confidence) {
  if (classes.type() != CV_8UC1 || confidence.type() != CV_32FC1 || classes.size() != confidence.size()) {
    throw DataError("learned classes must be CV_8UC1 with CV_32FC1 confidence of one size");
  }
  // Per blob: pixel count and summed probability of each class.
  std::vector<double>& sums = class_sums_;
  sums.assign(6 * static_cast<size_t>(count_), 0.0);
  for (size_t j = 0; j < runs_.size(); ++j) {
    const Run& r = runs_[j];
    if (r.v >= classes.rows || r.u_end > classes.cols) {
      throw DataError("learned classes of " + std::to_string(classes.cols) + "x" +
                      std::to_string(classes.rows) + " px do not cover the mask");
    }
    const int b = slot_blob_[static_cast<size_t>(run_blob_[static_cast<size_t>(parent_[j])])];
    if (b < 0) continue;
    const uint8_t* c = classes.ptr<uint8_t>(r.v);
    const float* p = confidence.ptr<float>(r.v);
    double* s = &sums[6 * static_cast<size_t>(b)];
    for (int u = r.u_begin; u < r.u_end; ++u) {
      const int k = std::min<int>(c[u], 2);
      s[2 * k] += 1.0;
      s[2 * k + 1] += static_cast<double>(p[u]);
    }
  }
  for (int i = 0; i < count_; ++i) {
    Blob& blob = pool_[static_cast<size_t>(i)];
    const double* s = &sums[6 * static_cast<size_t>(i)];
    int best = 0;
    for (int k = 1; k < 3; ++k) {
      if (s[2 * k] > s[2 * best]) best = k;
    }
    const double n = s[0] + s[2] + s[4];
    blob.learned_class = best;
    blob.learned_confidence = n > 0.0 ? s[2 * best + 1] / n : 0.0;
  }
}

void BlobExtractor::FindRuns(const cv::Mat& mask) {
  row_bits_.resize(static_cast<size_t>((mask.cols + 63) / 64));
  detail::LabelRuns(
      mask.cols, mask.rows, true,
      [&](int v) {
        detail::RowBits(mask.ptr<uint8_t>(v), mask.cols, row_bits_.data());
        return row_bits_.data();
      },
      runs_, parent_);
}

void BlobExtractor::Accumulate(const cv::Mat& mask) {
  run_blob_.assign(runs_.size(), -1);
  moments_.clear();
  boxes_.clear();
  first_run_.clear();
  int slots = 0;
  for (size_t i = 0; i < runs_.size(); ++i) {
    const Run& r = runs_[i];
    const auto root = static_cast<size_t>(parent_[i]);  // FindRuns resolved the roots
    if (run_blob_[root] < 0) {
      run_blob_[root] = slots++;
      moments_.insert(moments_.end(), 6, 0.0);
      boxes_.emplace_back(r.u_begin, r.v, 0, 0);
      first_run_.push_back(static_cast<int>(i));
    }
    const auto s = static_cast<size_t>(run_blob_[root]);
    AddRun(r, &moments_[6 * s]);
    boxes_[s] |= cv::Rect(r.u_begin, r.v, r.u_end - r.u_begin, 1);
  }
  count_ = 0;
  slot_blob_.assign(static_cast<size_t>(slots), -1);
  for (int s = 0; s < slots; ++s) {
    const double* m = &moments_[6 * static_cast<size_t>(s)];
    if (m[0] < options_.min_area_px) continue;
    if (pool_.size() <= static_cast<size_t>(count_)) pool_.emplace_back();
    slot_blob_[static_cast<size_t>(s)] = count_;
    Blob& b = pool_[static_cast<size_t>(count_++)];
    b.id = count_;
    b.area_px = static_cast<int>(m[0]);
    MomentsToCentroid(m, b.centroid_px, b.covariance_px2);
    b.core_area_px = -1;
    b.learned_class = -1;
    b.learned_confidence = 0.0;
    b.bbox_px = boxes_[static_cast<size_t>(s)];
    b.on_ground = false;
    b.contour.clear();
    if (options_.trace_contours) {
      const Run& first = runs_[static_cast<size_t>(first_run_[static_cast<size_t>(s)])];
      TraceOuterContour(mask, {first.u_begin, first.v}, b.contour);
    }
  }
}

std::span<const Blob> BlobExtractor::Extract(const cv::Mat& mask) {
  PLANTSCALE_CHECK(mask.type() == CV_8UC1, "mask must be CV_8UC1");
  FindRuns(mask);
  Accumulate(mask);
  return {pool_.data(), static_cast<size_t>(count_)};
}

std::span<const Blob> BlobExtractor::Extract(const cv::Mat& mask,
                                             const geometry::CameraModel& camera) {
  Extract(mask);
  Project(camera);
  return {pool_.data(), static_cast<size_t>(count_)};
}

std::span<const Blob> BlobExtractor::ExtractLabelled(std::span<const detail::RowRun> runs,
                                                     std::span<const int> parent,
                                                     const geometry::CameraModel* camera) {
  PLANTSCALE_CHECK(!options_.trace_contours, "contours need the mask: use Extract");
  PLANTSCALE_CHECK(runs.size() == parent.size(), "one parent per run");
  runs_.assign(runs.begin(), runs.end());
  parent_.assign(parent.begin(), parent.end());
  Accumulate(cv::Mat());
  if (camera) Project(*camera);
  return {pool_.data(), static_cast<size_t>(count_)};
}

void BlobExtractor::Project(const geometry::CameraModel& camera) {
  const double h = camera.options().virtual_plane_height_m;
  for (int i = 0; i < count_; ++i) {
    Blob& b = pool_[static_cast<size_t>(i)];
    const auto ground = camera.ImageToPlane(b.centroid_px, h);
    b.on_ground = ground.has_value();
    if (!ground) continue;
    b.ground_m = *ground;
    b.ground_area_m2 = b.area_px * std::abs(camera.ImageToPlaneJacobian(b.centroid_px, h)
                                                .determinant());
  }
}

void TraceOuterContour(const cv::Mat& mask, cv::Point start, std::vector<cv::Point>& contour) {
  contour.clear();
  contour.push_back(start);
  // `start` is the blob's top-left pixel, so its west neighbour is soil.
  const int first = NextBoundaryDirection(mask, start, 0);
  if (first < 0) return;
  cv::Point c = start;
  int d = first;
  const size_t limit = 4 * static_cast<size_t>(mask.total()) + 8;
  while (contour.size() < limit) {
    const cv::Point next = c + kClockwise[static_cast<size_t>(d)];
    // The last soil pixel checked before `next`, seen from `next`.
    const cv::Point back = c + kClockwise[static_cast<size_t>((d + 7) % 8)];
    c = next;
    d = NextBoundaryDirection(mask, c, DirectionIndex(back - c));
    if (c == start && d == first) break;  // Jacob's stopping criterion
    contour.push_back(c);
  }
}

void FreemanChainCode(std::span<const cv::Point> contour, std::vector<uint8_t>& codes) {
  // Freeman code of each clockwise direction index (screen v grows downwards).
  constexpr std::array<uint8_t, 8> kFreeman = {4, 3, 2, 1, 0, 7, 6, 5};
  codes.clear();
  if (contour.size() < 2) return;
  for (size_t i = 0; i < contour.size(); ++i) {
    const cv::Point d = contour[(i + 1) % contour.size()] - contour[i];
    codes.push_back(kFreeman[static_cast<size_t>(DirectionIndex(d))]);
  }
}

}  // namespace plantscale::vision
