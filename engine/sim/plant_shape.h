#pragma once
// The 3-D shape of a simulated plant: an inverted bowl of leaves (thesis
// §2.3.8 models cauliflowers as inverted hemispheres) whose outline is lobed
// into leaves. The solid is { (ρ, θ, z): z ≤ H, z ≥ H·(1 − √(1 − (ρ/R(θ))²)) }
// around the rim centre, with R(θ) = R·(1 − d + d·|cos(k(θ − θ0)/2)|).
// A ray hits the plant where it first enters that solid.

#include <Eigen/Core>
#include <array>

#include "engine/sim/field.h"

namespace plantscale::sim {

struct PlantHit {
  bool hit = false;
  double radial = 0.0;  // ρ/R(θ) at the hit, 0 at the centre, 1 at the leaf tips
  double z_m = 0.0;     // height of the hit
};

// Per-plant constants of the intersection, computed once per frame.
class PlantShape {
 public:
  explicit PlantShape(const Plant& plant);

  // `origin` is the camera centre and `direction` the ray (field frame, with
  // direction.z() < 0). `samples` heights are tested from the rim downwards.
  PlantHit Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                     int samples) const;

 private:
  double OutlineFactor(double dx, double dy, double rho) const;
  bool InFractureGap(double dx, double dy, double radial) const;

  const Plant* plant_;
  double cx_, cy_;  // root
  double lean_x_, lean_y_;
  double radius_, height_;
  double lobe_cos_, lobe_sin_;
  const std::array<float, 4097>* lobe_table_;
};

// Convenience for one-off rays (tests).
inline PlantHit IntersectPlant(const Plant& plant, const Eigen::Vector3d& origin,
                               const Eigen::Vector3d& direction, int samples = 6) {
  return PlantShape(plant).Intersect(origin, direction, samples);
}

}  // namespace plantscale::sim
