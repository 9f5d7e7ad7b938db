#include "engine/motion/correspondence.h"

#include <algorithm>
#include <cmath>

#include "engine/common/check.h"

namespace plantscale::motion {

double SimilarityDistance(const Characteristics& a, const Characteristics& b,
                          double convexity_weight, double orientation_weight) {
  const double dc = convexity_weight * (a.convexity_rad - b.convexity_rad);
  const double dor = orientation_weight * WrapAngle(a.orientation_rad - b.orientation_rad);
  return std::sqrt(dc * dc + dor * dor);
}

bool SearchRegion::Contains(const Eigen::Vector2d& q) const {
  return (q - a).norm() + (q - b).norm() <= (a - b).norm() + 2.0 * margin_m;
}

SearchRegion EpipolarSearchRegion(const Eigen::Vector2d& feature_m, const PlanarMotion& previous,
                                  double depth_tolerance, double margin_m) {
  // Eq. 3 with z_vc scaled by (1 ∓ tolerance): on the plane the translation
  // scales by the inverse.
  PlanarMotion near = previous, far = previous;
  near.t_m /= (1.0 - depth_tolerance);
  far.t_m /= (1.0 + depth_tolerance);
  return {near.ApplyInverse(feature_m), far.ApplyInverse(feature_m), margin_m};
}

std::vector<Match> TwoWayMatches(const Eigen::MatrixXd& dm) {
  std::vector<Match> out;
  if (dm.size() == 0) return out;
  std::vector<int> row_min(dm.rows(), -1), col_min(dm.cols(), -1);
  for (int i = 0; i < dm.rows(); ++i) {
    for (int j = 0; j < dm.cols(); ++j) {
      if (!std::isfinite(dm(i, j))) continue;
      if (row_min[i] < 0 || dm(i, j) < dm(i, row_min[i])) row_min[i] = j;
      if (col_min[j] < 0 || dm(i, j) < dm(col_min[j], j)) col_min[j] = i;
    }
  }
  for (int i = 0; i < dm.rows(); ++i) {
    if (row_min[i] >= 0 && col_min[row_min[i]] == i) out.emplace_back(i, row_min[i]);
  }
  return out;
}

std::vector<int> SequentialCluster(std::span<const Eigen::Vector3d> points, double join,
                                   double open) {
  PLANTSCALE_CHECK(join > 0.0 && open >= join, "thresholds: 0 < join <= open");
  std::vector<int> label(points.size(), -1);
  std::vector<Eigen::Vector3d> sum;
  std::vector<int> count;
  size_t left = points.size();
  while (left > 0) {
    bool changed = false;
    for (size_t p = 0; p < points.size(); ++p) {
      if (label[p] >= 0) continue;
      int best = -1;
      double best_d = kNoMatch;
      for (size_t c = 0; c < sum.size(); ++c) {
        const double d = (points[p] - sum[c] / count[c]).norm();
        if (d < best_d) best_d = d, best = static_cast<int>(c);
      }
      if (best >= 0 && best_d <= join) {
        label[p] = best;
      } else if (best < 0 || best_d > open) {
        label[p] = static_cast<int>(sum.size());
        sum.push_back(Eigen::Vector3d::Zero());
        count.push_back(0);
      } else {
        continue;
      }
      sum[label[p]] += points[p];
      ++count[label[p]];
      --left;
      changed = true;
    }
    if (changed) continue;
    // Nothing moved: the first waiting point opens a cluster of its own.
    const auto first = std::find(label.begin(), label.end(), -1) - label.begin();
    label[first] = static_cast<int>(sum.size());
    sum.push_back(points[first]);
    count.push_back(1);
    --left;
  }
  return label;
}

HoughResult HoughSelect(std::span<const Eigen::Vector2d> previous,
                        std::span<const Eigen::Vector2d> current, double psi_centre_rad,
                        const HoughOptions& options) {
  PLANTSCALE_CHECK(previous.size() == current.size(), "one previous point per current point");
  HoughResult best;
  double best_spread = kNoMatch;
  const int steps = std::max(1, options.psi_steps);
  std::vector<Eigen::Vector3d> points(previous.size());
  for (int s = 0; s < steps; ++s) {
    const double psi = psi_centre_rad + options.psi_range_rad * ((s + 0.5) / steps - 0.5);
    const PlanarMotion rotation{psi, Eigen::Vector2d::Zero()};
    // Eq. 2 solved for t at this ψ; the plane of constant ψ is clustered.
    for (size_t m = 0; m < previous.size(); ++m) {
      const Eigen::Vector2d t = current[m] - rotation.Apply(previous[m]);
      points[m] = Eigen::Vector3d(t.x(), t.y(), 0.0);
    }
    const std::vector<int> label = SequentialCluster(points, options.join_m, options.open_m);
    const int clusters = label.empty() ? 0 : *std::max_element(label.begin(), label.end()) + 1;
    for (int c = 0; c < clusters; ++c) {
      std::vector<int> members;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (size_t m = 0; m < label.size(); ++m) {
        if (label[m] == c) members.push_back(static_cast<int>(m)), mean += points[m];
      }
      mean /= static_cast<double>(members.size());
      double spread = 0.0;
      for (int m : members) spread += (points[m] - mean).squaredNorm();
      spread /= static_cast<double>(members.size());
      if (members.size() > best.coherent.size() ||
          (members.size() == best.coherent.size() && spread < best_spread)) {
        best.coherent = std::move(members);
        best.motion = {psi, mean.head<2>()};
        best_spread = spread;
      }
    }
  }
  return best;
}

bool ConsistentWithMotion(const PlanarMotion& motion, const Eigen::Vector2d& previous,
                          const Eigen::Vector2d& current, double depth_tolerance,
                          double direction_tolerance_rad) {
  const MatchTriangulation t = Triangulate(motion, previous, current);
  return std::abs(t.depth_ratio - 1.0) <= depth_tolerance &&
         t.direction_error_rad <= direction_tolerance_rad;
}

std::vector<Match> GreedyMatches(const Eigen::MatrixXd& cost, std::vector<uint8_t> row_used,
                                 std::vector<uint8_t> col_used) {
  row_used.resize(cost.rows(), 0);
  col_used.resize(cost.cols(), 0);
  std::vector<std::pair<double, Match>> entries;
  for (int i = 0; i < cost.rows(); ++i) {
    for (int j = 0; j < cost.cols(); ++j) {
      if (std::isfinite(cost(i, j)) && !row_used[i] && !col_used[j])
        entries.push_back({cost(i, j), {i, j}});
    }
  }
  std::sort(entries.begin(), entries.end());
  std::vector<Match> out;
  for (const auto& [c, m] : entries) {
    if (row_used[m.first] || col_used[m.second]) continue;
    row_used[m.first] = col_used[m.second] = 1;
    out.push_back(m);
  }
  return out;
}

}  // namespace plantscale::motion
