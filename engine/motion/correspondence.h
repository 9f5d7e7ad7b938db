#pragma once
// The stages of Sanchiz & Pla's correspondence (§3.1–3.4), each a function:
// similarity (eq. 6), the elliptic search region along the epipolar line
// (§3.2), two-way matches (§3.1), the Hough-like selection by clustering in
// (ψ, t_x, t_y) (§3.3, step 2) with Trahanias's two-threshold sequential
// clustering, the filtering of step 4 and the greedy final matching of
// step 5. Positions are on the feature plane in metres (planar_motion.h).

#include <Eigen/Core>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "engine/motion/planar_motion.h"

namespace plantscale::motion {

inline constexpr double kNoMatch = std::numeric_limits<double>::infinity();

// The characteristics compared by eq. 6 (§5: N = 2, w₁ = w₂ = 1).
struct Characteristics {
  double convexity_rad = 0.0;
  double orientation_rad = 0.0;
};

// Eq. 6: d² = Σ w_l² (c_li − c_lj)²; the orientation difference is wrapped.
double SimilarityDistance(const Characteristics& a, const Characteristics& b,
                          double convexity_weight = 1.0, double orientation_weight = 1.0);

// §3.2: ellipse with foci a and b, the feature back-projected with the
// previous motion at depths (1 ∓ depth_tolerance)·z; `margin_m` widens it
// (a point q is inside when |q−a| + |q−b| ≤ |a−b| + 2·margin).
struct SearchRegion {
  Eigen::Vector2d a{0.0, 0.0}, b{0.0, 0.0};
  double margin_m = 0.0;
  bool Contains(const Eigen::Vector2d& q) const;
};
SearchRegion EpipolarSearchRegion(const Eigen::Vector2d& feature_m, const PlanarMotion& previous,
                                  double depth_tolerance, double margin_m);

using Match = std::pair<int, int>;  // (feature i in image k, track j in image k−1)

// §3.1: entries of dm (rows: features, columns: tracks) that are the finite
// minimum of both their row and their column.
std::vector<Match> TwoWayMatches(const Eigen::MatrixXd& dm);

// Trahanias & Skordalakis's sequential clustering with two thresholds: a
// point within `join` of a cluster centre joins it, one farther than `open`
// from every centre opens a new one, the rest wait for another pass.
// Returns a cluster label per point. Distances are Euclidean on `points`.
std::vector<int> SequentialCluster(std::span<const Eigen::Vector3d> points, double join,
                                   double open);

struct HoughOptions {
  double psi_range_rad = 6.0 * M_PI / 180.0;  // §3.3: 6° centred on the last ψ
  int psi_steps = 20;
  double join_m = 0.01;   // clustering thresholds on (t_x, t_y)
  double open_m = 0.02;
};
struct HoughResult {
  PlanarMotion motion;          // cluster centre (ψ₀, t_x0, t_y0)
  std::vector<int> coherent;    // indices into the candidate list
};
// §3.3 / step 2: for each candidate and each ψ of the range, t from eq. 2;
// the biggest cluster (counted in distinct candidates) wins.
HoughResult HoughSelect(std::span<const Eigen::Vector2d> previous,
                        std::span<const Eigen::Vector2d> current, double psi_centre_rad,
                        const HoughOptions& options);

// Step 4 / step 5 test: depth change (eq. 10) within depth_tolerance and
// translation direction (eq. 11) within direction_tolerance_rad.
bool ConsistentWithMotion(const PlanarMotion& motion, const Eigen::Vector2d& previous,
                          const Eigen::Vector2d& current, double depth_tolerance,
                          double direction_tolerance_rad);

// Step 5: repeatedly take the smallest finite entry of `cost`, pairing its
// row and column, until none is left. Rows or columns already used (flags
// non-zero) are skipped.
std::vector<Match> GreedyMatches(const Eigen::MatrixXd& cost, std::vector<uint8_t> row_used,
                                 std::vector<uint8_t> col_used);

}  // namespace plantscale::motion
