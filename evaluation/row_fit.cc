#include "evaluation/row_fit.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "engine/common/check.h"

namespace plantscale::motion {

OptionErrors RowFitOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "row_gap_m", row_gap_m);
  RequireNonNegative(e, "outlier_m", outlier_m);
  if (min_plants < 2) e.push_back({"min_plants", "must be >= 2"});
  return e;
}

double FittedLine::XAt(double y_m) const {
  if (std::abs(direction.y()) < 1e-12) return point_m.x();
  return point_m.x() + direction.x() * (y_m - point_m.y()) / direction.y();
}

FittedLine FitLine(std::span<const Eigen::Vector2d> points) {
  PLANTSCALE_CHECK(points.size() >= 2, "a line needs two points");
  FittedLine line;
  line.plants = static_cast<int>(points.size());
  for (const auto& p : points) line.point_m += p;
  line.point_m /= static_cast<double>(points.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const auto& p : points) scatter += (p - line.point_m) * (p - line.point_m).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  line.direction = eig.eigenvectors().col(1);
  if (line.direction.y() < 0.0) line.direction = -line.direction;
  const Eigen::Vector2d normal(-line.direction.y(), line.direction.x());
  double sum = 0.0;
  for (const auto& p : points) sum += std::pow(normal.dot(p - line.point_m), 2);
  line.rms_m = std::sqrt(sum / static_cast<double>(points.size()));
  return line;
}

namespace {

FittedLine FitRow(std::span<const Eigen::Vector2d> plants, const RowFitOptions& options) {
  FittedLine line = FitLine(plants);
  if (options.outlier_m <= 0.0) return line;
  const Eigen::Vector2d normal(-line.direction.y(), line.direction.x());
  std::vector<Eigen::Vector2d> kept;
  for (const auto& p : plants) {
    if (std::abs(normal.dot(p - line.point_m)) <= options.outlier_m) kept.push_back(p);
  }
  if (static_cast<int>(kept.size()) < options.min_plants || kept.size() == plants.size()) return line;
  FittedLine refit = FitLine(kept);
  refit.outliers = static_cast<int>(plants.size() - kept.size());
  return refit;
}

}  // namespace

RowFit FitRows(std::span<const Eigen::Vector2d> plants_m, double centre_y_m,
               const RowFitOptions& options) {
  std::vector<Eigen::Vector2d> sorted(plants_m.begin(), plants_m.end());
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.x() < b.x(); });
  RowFit fit;
  size_t begin = 0;
  for (size_t i = 1; i <= sorted.size(); ++i) {
    if (i < sorted.size() && sorted[i].x() - sorted[i - 1].x() <= options.row_gap_m) continue;
    if (static_cast<int>(i - begin) >= options.min_plants)
      fit.rows.push_back(FitRow(std::span(sorted).subspan(begin, i - begin), options));
    begin = i;
  }
  for (const auto& row : fit.rows) fit.mean_rms_m += row.rms_m / static_cast<double>(fit.rows.size());
  for (size_t r = 1; r < fit.rows.size(); ++r) {
    const FittedLine &a = fit.rows[r - 1], &b = fit.rows[r];
    fit.angles_rad.push_back(std::acos(std::clamp(a.direction.dot(b.direction), -1.0, 1.0)));
    const Eigen::Vector2d mean_dir = (a.direction + b.direction).normalized();
    const Eigen::Vector2d normal(-mean_dir.y(), mean_dir.x());
    const Eigen::Vector2d pa(a.XAt(centre_y_m), centre_y_m), pb(b.XAt(centre_y_m), centre_y_m);
    fit.spacings_m.push_back(std::abs(normal.dot(pb - pa)));
  }
  const auto mean = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
  };
  fit.mean_angle_rad = mean(fit.angles_rad);
  fit.mean_spacing_m = mean(fit.spacings_m);
  return fit;
}

}  // namespace plantscale::motion
