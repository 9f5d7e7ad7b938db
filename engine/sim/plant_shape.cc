#include "engine/sim/plant_shape.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace plantscale::sim {
namespace {

// cos(kα) from cos α by the Chebyshev recurrence T_k.
double CosMultiple(int k, double c) {
  if (k == 0) return 1.0;
  double t0 = 1.0;
  double t1 = c;
  for (int i = 1; i < k; ++i) {
    const double t2 = 2.0 * c * t1 - t0;
    t0 = t1;
    t1 = t2;
  }
  return t1;
}

// |cos(kα/2)| = √((1 + T_k(cos α))/2) tabulated over cos α ∈ [−1, 1] for
// every lobe count, so that no pixel pays for trigonometry or a recurrence.
constexpr int kMaxLobes = 16;
constexpr int kTableSize = 4096;

struct LobeTables {
  LobeTables() {
    for (int k = 0; k <= kMaxLobes; ++k) {
      for (int i = 0; i <= kTableSize; ++i) {
        const double c = -1.0 + 2.0 * i / kTableSize;
        table[static_cast<size_t>(k)][static_cast<size_t>(i)] =
            static_cast<float>(std::sqrt(std::max(0.0, 0.5 * (1.0 + CosMultiple(k, c)))));
      }
    }
  }
  std::array<std::array<float, kTableSize + 1>, kMaxLobes + 1> table{};
};

const LobeTables& Tables() {
  static const LobeTables tables;
  return tables;
}

}  // namespace

PlantShape::PlantShape(const Plant& plant)
    : plant_(&plant),
      cx_(plant.position_m.x()),
      cy_(plant.position_m.y()),
      lean_x_(plant.lean_m.x()),
      lean_y_(plant.lean_m.y()),
      radius_(plant.radius_m),
      height_(plant.height_m),
      lobe_cos_(std::cos(plant.lobe_phase_rad)),
      lobe_sin_(std::sin(plant.lobe_phase_rad)),
      lobe_table_(&Tables().table[static_cast<size_t>(std::clamp(plant.lobes, 0, kMaxLobes))]) {}

double PlantShape::OutlineFactor(double dx, double dy, double rho) const {
  const Plant& p = *plant_;
  if (p.lobes == 0 || rho < 1e-12) return 1.0;
  const double c = std::clamp((dx * lobe_cos_ + dy * lobe_sin_) / rho, -1.0, 1.0);
  const double x = (c + 1.0) * (0.5 * kTableSize);
  const auto i = std::min(static_cast<int>(x), kTableSize - 1);
  const auto& row = (*lobe_table_);
  const double w = x - i;
  const double abs_half = (1.0 - w) * static_cast<double>(row[static_cast<size_t>(i)]) +
                          w * static_cast<double>(row[static_cast<size_t>(i) + 1]);
  return 1.0 - p.lobe_depth + p.lobe_depth * abs_half;
}

// A dark gap across one leaf (thesis fig. 2.18) between 45 % and 58 % of its length.
bool PlantShape::InFractureGap(double dx, double dy, double radial) const {
  const Plant& p = *plant_;
  if (p.fractured_lobe < 0 || radial < 0.45 || radial > 0.58) return false;
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double a = std::atan2(dy, dx) - p.lobe_phase_rad;
  a = std::fmod(std::fmod(a, kTwoPi) + kTwoPi, kTwoPi);
  const int lobe = static_cast<int>(std::floor(a / (kTwoPi / p.lobes) + 0.5)) % p.lobes;
  return lobe == p.fractured_lobe;
}

PlantHit PlantShape::Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                               int samples) const {
  PlantHit result;
  const double r2 = radius_ * radius_;
  // The ray between the rim height and the ground is a short horizontal
  // segment; if it passes further than R from the plant's axis, no hit.
  const double s_top = (height_ - origin.z()) / direction.z();
  const double s_ground = -origin.z() / direction.z();
  const double ax = origin.x() + s_top * direction.x() - cx_ - lean_x_;
  const double ay = origin.y() + s_top * direction.y() - cy_ - lean_y_;
  const double bx = origin.x() + s_ground * direction.x() - cx_;
  const double by = origin.y() + s_ground * direction.y() - cy_;
  const double ex = bx - ax;
  const double ey = by - ay;
  const double len2 = ex * ex + ey * ey;
  const double t = len2 > 0.0 ? std::clamp(-(ax * ex + ay * ey) / len2, 0.0, 1.0) : 0.0;
  const double nx = ax + t * ex;
  const double ny = ay + t * ey;
  if (nx * nx + ny * ny > r2) return result;

  for (int i = 0; i < samples; ++i) {
    // Heights from the rim down to just above the root; the leaning rim
    // centre moves linearly from the root (z = 0) to the rim (z = H).
    const double f = 1.0 - static_cast<double>(i) / samples;
    const double dx = ax + (1.0 - f) * ex;
    const double dy = ay + (1.0 - f) * ey;
    const double rho2 = dx * dx + dy * dy;
    if (rho2 > r2) continue;
    const double rho = std::sqrt(rho2);
    const double radial = rho / (radius_ * OutlineFactor(dx, dy, rho));
    if (radial > 1.0) continue;
    const double z = height_ * f;
    // At the rim height (i = 0) every point inside the outline is in the solid.
    if (i > 0 && z + 1e-12 < height_ * (1.0 - std::sqrt(1.0 - radial * radial))) continue;
    if (plant_->fractured_lobe >= 0 && InFractureGap(dx, dy, radial)) continue;
    result.hit = true;
    result.radial = radial;
    result.z_m = z;
    return result;
  }
  return result;
}

}  // namespace plantscale::sim
