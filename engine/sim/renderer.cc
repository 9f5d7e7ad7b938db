#include "engine/sim/renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "engine/common/rng.h"
#include "engine/sim/plant_shape.h"

namespace plantscale::sim {
namespace {

constexpr int kTexture = 512;               // texels per side (power of two)
constexpr double kTexelM = 0.004;           // 4 mm texels: a 2.048 m tile
constexpr double kTextureOffsetM = 4096.0;  // keeps texel indices positive
constexpr int kNoiseTable = 1 << 20;

enum Material : uint8_t { kSoil = 0, kCrop = 1, kWeed = 2, kStone = 3, kBeyond = 4 };
enum ShadowBit : uint8_t { kPlantShadow = 1, kVehicleShadow = 2 };

// Tileable value noise: octaves of smoothly interpolated random lattices,
// normalised to zero mean and unit standard deviation.
std::vector<float> ValueNoise(Rng& rng, int first_period, int octaves) {
  std::vector<float> tex(static_cast<size_t>(kTexture) * kTexture, 0.0F);
  double amplitude = 1.0;
  for (int o = 0, period = first_period; o < octaves && period >= 1; ++o, period /= 2) {
    const int cells = kTexture / period;
    std::vector<double> lattice(static_cast<size_t>(cells) * cells);
    for (double& v : lattice) v = rng.Normal();
    for (int y = 0; y < kTexture; ++y) {
      const int y0 = y / period;
      const double fy = static_cast<double>(y % period) / period;
      const double sy = fy * fy * (3.0 - 2.0 * fy);
      for (int x = 0; x < kTexture; ++x) {
        const int x0 = x / period;
        const double fx = static_cast<double>(x % period) / period;
        const double sx = fx * fx * (3.0 - 2.0 * fx);
        const auto at = [&](int i, int j) {
          return lattice[static_cast<size_t>((j % cells) * cells + (i % cells))];
        };
        const double top = at(x0, y0) * (1 - sx) + at(x0 + 1, y0) * sx;
        const double bottom = at(x0, y0 + 1) * (1 - sx) + at(x0 + 1, y0 + 1) * sx;
        tex[static_cast<size_t>(y) * kTexture + x] +=
            static_cast<float>(amplitude * (top * (1 - sy) + bottom * sy));
      }
    }
    amplitude *= 0.55;
  }
  double sum = 0.0;
  double sum2 = 0.0;
  for (float f : tex) {
    const auto v = static_cast<double>(f);
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / static_cast<double>(tex.size());
  const double sd = std::sqrt(sum2 / static_cast<double>(tex.size()) - mean * mean);
  for (float& v : tex) v = static_cast<float>((static_cast<double>(v) - mean) / sd);
  return tex;
}

inline float Texel(const std::vector<float>& tex, double x_m, double y_m, double scale) {
  const auto i = static_cast<unsigned>((x_m + kTextureOffsetM) * scale) & (kTexture - 1U);
  const auto j = static_cast<unsigned>((y_m + kTextureOffsetM) * scale) & (kTexture - 1U);
  return tex[j * kTexture + i];
}

// Runs f(first_row, end_row) on `threads` bands of rows; results do not
// depend on the number of threads because every row is computed alone.
template <typename F>
void ForRowBands(int rows, int threads, F&& f) {
  threads = std::clamp(threads, 1, std::max(1, rows));
  if (threads == 1) {
    f(0, rows);
    return;
  }
  std::vector<std::thread> workers;
  workers.reserve(static_cast<size_t>(threads - 1));
  const auto band = [&](int k) {
    return static_cast<int>(static_cast<int64_t>(rows) * k / threads);
  };
  for (int k = 1; k < threads; ++k) workers.emplace_back([&, k] { f(band(k), band(k + 1)); });
  f(0, band(1));
  for (std::thread& w : workers) w.join();
}

// Value of the standard normal exceeded with probability `fraction`.
float UpperQuantile(std::vector<float> values, double fraction) {
  if (fraction <= 0.0) return 1e9F;
  const auto k = static_cast<size_t>((1.0 - fraction) * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

// Per-frame geometry: the ray through pixel (u, v) in the field frame is
// row_base[v] + u·du, starting at the camera centre.
struct Renderer::View {
  int width = 0;
  int height = 0;
  Eigen::Vector3d centre;  // field frame
  Eigen::Vector3d du;
  std::vector<Eigen::Vector3d> row_base;
  Pose2 pose;
  double cos_h = 1.0;
  double sin_h = 0.0;
  double y_min = 0.0, y_max = 0.0, x_min = 0.0, x_max = 0.0;  // field AABB seen
  const geometry::CameraModel* camera = nullptr;

  Eigen::Vector3d RayAt(double u, int v) const { return row_base[static_cast<size_t>(v)] + u * du; }
  // Field-frame ground point seen through the centre of pixel (u, v);
  // nullopt when the ray does not go down to the ground.
  std::optional<Eigen::Vector2d> GroundAt(int u, int v) const {
    const Eigen::Vector3d d = RayAt(u + 0.5, v);
    if (d.z() >= 0.0) return std::nullopt;
    const double s = -centre.z() / d.z();
    return Eigen::Vector2d(centre.x() + s * d.x(), centre.y() + s * d.y());
  }
  // Image position of a field-frame point at height z.
  std::optional<Eigen::Vector2d> Project(double x, double y, double z) const {
    const Eigen::Vector2d p = FieldToVehicle(pose, {x, y});
    return camera->Project({p.x(), p.y(), z});
  }
};

OptionErrors RenderOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "exposure", exposure);
  for (const auto& [key, value] : {std::pair{"soil_reflectance", soil_reflectance},
                                   {"crop_reflectance", crop_reflectance},
                                   {"weed_reflectance", weed_reflectance},
                                   {"stone_reflectance", stone_reflectance}}) {
    RequireInRange(e, key, value, 0.0, 1.0);
  }
  RequireInRange(e, "soil_texture_contrast", soil_texture_contrast, 0.0, 1.0);
  RequireInRange(e, "leaf_texture_contrast", leaf_texture_contrast, 0.0, 1.0);
  RequireInRange(e, "illumination_gradient", illumination_gradient, -1.0, 1.0);
  RequireInRange(e, "vehicle_shadow_depth", vehicle_shadow_depth, 0.0, 1.0);
  RequireFinite(e, "vehicle_shadow_edge_m", vehicle_shadow_edge_m);
  RequireFinite(e, "vehicle_shadow_slope", vehicle_shadow_slope);
  RequireInRange(e, "plant_shadow_depth", plant_shadow_depth, 0.0, 1.0);
  RequireInRange(e, "leaf_shadow_fraction", leaf_shadow_fraction, 0.0, 1.0);
  RequireInRange(e, "leaf_shadow_depth", leaf_shadow_depth, 0.0, 1.0);
  RequireInRange(e, "optical_blur_px", optical_blur_px, 0.0, 10.0);
  RequireFinite(e, "sun_azimuth_rad", sun_azimuth_rad);
  RequireInRange(e, "sun_elevation_rad", sun_elevation_rad, 0.05, std::numbers::pi / 2.0);
  RequireInRange(e, "specular_fraction", specular_fraction, 0.0, 0.5);
  RequireNonNegative(e, "specular_gain", specular_gain);
  RequireInRange(e, "sensor_noise", sensor_noise, 0.0, 0.5);
  RequirePositive(e, "max_range_m", max_range_m);
  if (ray_samples < 1 || ray_samples > 64) e.push_back({"ray_samples", "must be in [1, 64]"});
  if (threads < 0 || threads > 64)
    e.push_back({"threads", "must be in [0, 64] (0: one per core, at most 4)"});
  return e;
}

Renderer::Renderer(const RenderOptions& options, uint64_t seed) : options_(options) {
  ThrowIfInvalid("render", options.Validate());
  threads_ = options.threads > 0
                 ? options.threads
                 : std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, 4);
  Rng rng = Rng::Derived(seed, 0x7e27);
  soil_texture_ = ValueNoise(rng, 64, 6);
  leaf_texture_ = ValueNoise(rng, 8, 3);
  specular_threshold_ = UpperQuantile(soil_texture_, options_.specular_fraction);
  leaf_shadow_threshold_ = UpperQuantile(leaf_texture_, options_.leaf_shadow_fraction);
  noise_table_.resize(kNoiseTable);
  for (float& v : noise_table_) v = static_cast<float>(rng.Normal());
}

void Renderer::Render(const Field& field, const geometry::CameraModel& camera, const Pose2& pose,
                      double speed_m_s, double exposure_s, uint64_t frame_seed,
                      RenderedFrame& out) {
  View view;
  view.camera = &camera;
  view.width = camera.width();
  view.height = camera.height();
  view.pose = pose;
  view.cos_h = std::cos(pose.heading_rad);
  view.sin_h = std::sin(pose.heading_rad);
  view.centre = {pose.x_m, pose.y_m, camera.options().height_m};
  // Field ray = Rz(ψ)·Rᵀ·((u − c_u)/f_x, (v − c_v)/f_y, 1).
  Eigen::Matrix3d rz = Eigen::Matrix3d::Identity();
  rz.topLeftCorner<2, 2>() << view.cos_h, -view.sin_h, view.sin_h, view.cos_h;
  const Eigen::Matrix3d m = rz * camera.rotation().transpose();
  const Eigen::Vector2d c = camera.principal_point();
  view.du = m.col(0) / camera.fx();
  view.row_base.resize(static_cast<size_t>(view.height));
  for (int v = 0; v < view.height; ++v) {
    view.row_base[static_cast<size_t>(v)] =
        m * Eigen::Vector3d(-c.x() / camera.fx(), (v + 0.5 - c.y()) / camera.fy(), 1.0);
  }

  shade_.create(view.height, view.width, CV_32F);
  material_.create(view.height, view.width, CV_8U);
  shadow_.create(view.height, view.width, CV_8U);
  shadow_.setTo(0);
  out.labels.create(view.height, view.width, CV_8U);
  out.instances.create(view.height, view.width, CV_16U);
  out.instances.setTo(0);

  RenderGround(view);
  RenderStones(field, view);
  if (options_.plant_shadow_depth > 0.0) RenderPlantShadows(field, view);
  RenderPlants(field, view, out);
  Compose(view, frame_seed, out);
  Blur(view, speed_m_s * exposure_s, out);
  if (options_.optical_blur_px > 0.0) {
    cv::GaussianBlur(out.image, out.image, cv::Size(0, 0), options_.optical_blur_px);
  }
}

void Renderer::RenderGround(View& view) {
  const double h = view.centre.z();
  const double range2 = options_.max_range_m * options_.max_range_m;
  const double fine = 1.0 / kTexelM;
  const double coarse = fine / 5.3;
  const auto contrast = static_cast<float>(options_.soil_texture_contrast);
  const auto glint = static_cast<float>(options_.specular_gain);
  const double shadow_on = options_.vehicle_shadow_depth > 0.0 ? 1.0 : 0.0;
  ForRowBands(view.height, threads_, [&](int first_row, int end_row) {
    for (int v = first_row; v < end_row; ++v) {
      auto* shade = shade_.ptr<float>(v);
      auto* material = material_.ptr<uint8_t>(v);
      auto* shadow = shadow_.ptr<uint8_t>(v);
      for (int u = 0; u < view.width; ++u) {
        const Eigen::Vector3d d = view.RayAt(u + 0.5, v);
        const double s = d.z() < 0.0 ? -h / d.z() : -1.0;
        const double gx = s * d.x();
        const double gy = s * d.y();
        if (s <= 0.0 || gx * gx + gy * gy > range2) {
          material[u] = kBeyond;
          shade[u] = 1.0F;
          continue;
        }
        const double x = view.centre.x() + gx;
        const double y = view.centre.y() + gy;
        const float t1 = Texel(soil_texture_, x, y, fine);
        const float t2 = Texel(soil_texture_, y + 17.3, x - 5.1, coarse);
        material[u] = kSoil;
        shade[u] = 1.0F + contrast * (0.65F * t1 + 0.35F * t2);
        // Glints: small speckles where a fine (≈1 cm) lookup is in its top fraction.
        if (Texel(soil_texture_, x - 3.7, y + 1.9, 7.0 * fine) > specular_threshold_) {
          shade[u] += glint;
        }
        if (shadow_on > 0.0) {
          const double vy = -view.sin_h * gx + view.cos_h * gy;
          const double vx = view.cos_h * gx + view.sin_h * gy;
          if (vy < options_.vehicle_shadow_edge_m + options_.vehicle_shadow_slope * vx) {
            shadow[u] |= kVehicleShadow;
          }
        }
      }
    }
  });
  SetGroundBounds(view);
}

// The field-frame box seen: the ground footprint's extremes lie on the
// image border (the footprint of a convex view cone on a plane).
void Renderer::SetGroundBounds(View& view) const {
  double x_lo = 1e18, x_hi = -1e18, y_lo = 1e18, y_hi = -1e18;
  const double h = view.centre.z();
  const auto visit = [&](double u, int v) {
    const Eigen::Vector3d d = view.RayAt(u, v);
    // Rays that miss the ground are clipped at the rendering range.
    const double horizontal = std::hypot(d.x(), d.y());
    double s = d.z() < 0.0 ? -h / d.z() : 1e18;
    if (s * horizontal > options_.max_range_m)
      s = options_.max_range_m / std::max(horizontal, 1e-12);
    const double x = view.centre.x() + s * d.x();
    const double y = view.centre.y() + s * d.y();
    x_lo = std::min(x_lo, x);
    x_hi = std::max(x_hi, x);
    y_lo = std::min(y_lo, y);
    y_hi = std::max(y_hi, y);
  };
  for (int u = 0; u <= view.width; u += 8) {
    visit(u, 0);
    visit(u, view.height - 1);
  }
  for (int v = 0; v < view.height; v += 8) {
    visit(0.0, v);
    visit(view.width, v);
  }
  visit(view.width, view.height - 1);
  view.x_min = x_lo;
  view.x_max = x_hi;
  view.y_min = y_lo;
  view.y_max = y_hi;
}

namespace {

struct PixelBox {
  int u0 = 0, v0 = 0, u1 = -1, v1 = -1;  // inclusive
  bool empty() const { return u1 < u0 || v1 < v0; }
};

// Image box around a ground disc of `radius` at (x, y) between heights 0 and
// `height`, clipped to the image; empty when any corner is behind the camera.
template <typename ViewT>
PixelBox BoxAround(const ViewT& view, double x, double y, double radius, double height) {
  double u_lo = 1e18, u_hi = -1e18, v_lo = 1e18, v_hi = -1e18;
  for (double z : {0.0, height}) {
    for (int k = 0; k < 8; ++k) {
      const double a = k * std::numbers::pi / 4.0;
      const auto uv = view.Project(x + radius * std::cos(a), y + radius * std::sin(a), z);
      if (!uv) return {};
      u_lo = std::min(u_lo, uv->x());
      u_hi = std::max(u_hi, uv->x());
      v_lo = std::min(v_lo, uv->y());
      v_hi = std::max(v_hi, uv->y());
    }
  }
  PixelBox box;
  box.u0 = std::max(0, static_cast<int>(std::floor(u_lo)) - 1);
  box.v0 = std::max(0, static_cast<int>(std::floor(v_lo)) - 1);
  box.u1 = std::min(view.width - 1, static_cast<int>(std::ceil(u_hi)) + 1);
  box.v1 = std::min(view.height - 1, static_cast<int>(std::ceil(v_hi)) + 1);
  return box;
}

}  // namespace

void Renderer::RenderStones(const Field& field, const View& view) {
  const auto [first, last] = field.StonesBetween(view.y_min - 0.2, view.y_max + 0.2);
  for (size_t i = first; i < last; ++i) {
    const Stone& st = field.stones()[i];
    if (st.position_m.x() < view.x_min - 0.2 || st.position_m.x() > view.x_max + 0.2) continue;
    const PixelBox box =
        BoxAround(view, st.position_m.x(), st.position_m.y(), st.semi_major_m, 0.0);
    const double ca = std::cos(st.angle_rad);
    const double sa = std::sin(st.angle_rad);
    for (int v = box.v0; v <= box.v1 && !box.empty(); ++v) {
      for (int u = box.u0; u <= box.u1; ++u) {
        const auto ground = view.GroundAt(u, v);
        if (!ground) continue;
        const double dx = ground->x() - st.position_m.x();
        const double dy = ground->y() - st.position_m.y();
        const double a = (ca * dx + sa * dy) / st.semi_major_m;
        const double b = (-sa * dx + ca * dy) / st.semi_minor_m;
        const double r2 = a * a + b * b;
        if (r2 > 1.0) continue;
        material_.at<uint8_t>(v, u) = kStone;
        shade_.at<float>(v, u) = static_cast<float>(st.brightness * (1.1 - 0.3 * r2));
      }
    }
  }
}

void Renderer::RenderPlantShadows(const Field& field, const View& view) {
  // Shadows fall away from the sun, a plant's length ≈ its rim height / tan(elevation).
  const double reach = 1.0 / std::tan(options_.sun_elevation_rad);
  const double ax = -std::cos(options_.sun_azimuth_rad) * reach;
  const double ay = -std::sin(options_.sun_azimuth_rad) * reach;
  const double margin = field.max_plant_radius_m() + field.max_plant_height_m() * reach;
  const auto [first, last] = field.PlantsBetween(view.y_min - margin, view.y_max + margin);
  for (size_t i = first; i < last; ++i) {
    const Plant& p = field.plants()[i];
    const double cx = p.position_m.x() + p.lean_m.x() + 0.6 * p.height_m * ax;
    const double cy = p.position_m.y() + p.lean_m.y() + 0.6 * p.height_m * ay;
    if (cx < view.x_min - margin || cx > view.x_max + margin) continue;
    const double r = 0.85 * p.radius_m;
    const PixelBox box = BoxAround(view, cx, cy, r, 0.0);
    for (int v = box.v0; v <= box.v1 && !box.empty(); ++v) {
      auto* shadow = shadow_.ptr<uint8_t>(v);
      for (int u = box.u0; u <= box.u1; ++u) {
        const auto ground = view.GroundAt(u, v);
        if (!ground) continue;
        const double dx = ground->x() - cx;
        const double dy = ground->y() - cy;
        if (dx * dx + dy * dy <= r * r) shadow[u] |= kPlantShadow;
      }
    }
  }
}

void Renderer::RenderPlants(const Field& field, const View& view, RenderedFrame& out) {
  const double margin = field.max_plant_radius_m() + 0.5;
  const auto [first, last] = field.PlantsBetween(view.y_min - margin, view.y_max + margin);
  // Painter's order: far plants first, so nearer ones occlude them.
  visible_.clear();
  for (size_t i = first; i < last; ++i) {
    const Plant& p = field.plants()[i];
    if (p.position_m.x() < view.x_min - margin || p.position_m.x() > view.x_max + margin) continue;
    visible_.push_back(static_cast<int>(i));
  }
  const auto distance2 = [&](int i) {
    const Eigen::Vector2d d = field.plants()[static_cast<size_t>(i)].position_m -
                              Eigen::Vector2d(view.centre.x(), view.centre.y());
    return d.squaredNorm();
  };
  std::sort(visible_.begin(), visible_.end(), [&](int a, int b) {
    return distance2(a) > distance2(b) || (distance2(a) == distance2(b) && a < b);
  });

  out.plants.clear();
  struct Job {
    PlantShape shape;
    PixelBox box;
    int index;
    uint16_t instance;
  };
  std::vector<Job> jobs;
  for (int index : visible_) {
    const Plant& p = field.plants()[static_cast<size_t>(index)];
    const PixelBox box =
        BoxAround(view, p.position_m.x() + 0.5 * p.lean_m.x(),
                  p.position_m.y() + 0.5 * p.lean_m.y(), p.radius_m + p.lean_m.norm(), p.height_m);
    if (box.empty()) continue;
    out.plants.push_back({index, 0, {0.0, 0.0}});
    jobs.push_back({PlantShape(p), box, index,
                    static_cast<uint16_t>(std::min<size_t>(out.plants.size(), 65535))});
  }
  const double fine = 1.0 / (0.5 * kTexelM);
  const auto leaf = static_cast<float>(options_.leaf_texture_contrast);
  const auto leaf_shadow = static_cast<float>(1.0 - options_.leaf_shadow_depth);
  ForRowBands(view.height, threads_, [&](int first_row, int end_row) {
    for (const Job& job : jobs) {
      const Plant& p = field.plants()[static_cast<size_t>(job.index)];
      const PixelBox& box = job.box;
      const PlantShape& shape = job.shape;
      const int index = job.index;
      const uint16_t instance = job.instance;
      const uint8_t material = p.cls == PlantClass::kCrop ? kCrop : kWeed;
      for (int v = std::max(box.v0, first_row); v <= std::min(box.v1, end_row - 1); ++v) {
        auto* shade = shade_.ptr<float>(v);
        auto* mat = material_.ptr<uint8_t>(v);
        auto* inst = out.instances.ptr<uint16_t>(v);
        for (int u = box.u0; u <= box.u1; ++u) {
          const PlantHit hit =
              shape.Intersect(view.centre, view.RayAt(u + 0.5, v), options_.ray_samples);
          if (!hit.hit) continue;
          mat[u] = material;
          inst[u] = instance;
          const float t = Texel(leaf_texture_, u * 0.002 + index * 0.37, v * 0.002, fine);
          shade[u] =
              static_cast<float>(p.brightness * (0.78 + 0.3 * hit.radial)) * (1.0F + leaf * t);
          if (Texel(leaf_texture_, v * 0.002 - index * 0.53, u * 0.002 + 1.7, fine) >
              leaf_shadow_threshold_) {
            shade[u] *= leaf_shadow;
          }
        }
      }
    }
  });
}

void Renderer::Compose(const View& view, uint64_t frame_seed, RenderedFrame& out) {
  const RenderOptions& o = options_;
  // Reflectance per material: NIR grey, or BGR colour (excess green for plants).
  const std::array<std::array<float, 3>, 5> colour = {{
      {0.20F, 0.28F, 0.38F},  // soil (B, G, R): brown
      {0.10F, 0.55F, 0.25F},  // crop
      {0.12F, 0.50F, 0.30F},  // weed
      {0.40F, 0.42F, 0.45F},  // stone
      {0.60F, 0.60F, 0.60F},  // beyond range: haze
  }};
  const std::array<float, 5> nir = {
      static_cast<float>(o.soil_reflectance), static_cast<float>(o.crop_reflectance),
      static_cast<float>(o.weed_reflectance), static_cast<float>(o.stone_reflectance), 0.6F};
  const bool rgb = o.kind == ImageKind::kRgb;
  out.image.create(view.height, view.width, rgb ? CV_8UC3 : CV_8UC1);
  Rng rng(frame_seed);
  const size_t noise_base = rng.NextU64() % kNoiseTable;
  const size_t channels = rgb ? 3 : 1;
  const auto noise = static_cast<float>(o.sensor_noise);
  const auto vehicle_shadow = static_cast<float>(1.0 - o.vehicle_shadow_depth);
  const auto plant_shadow = static_cast<float>(1.0 - o.plant_shadow_depth);
  ForRowBands(view.height, threads_, [&](int first_row, int end_row) {
    for (int v = first_row; v < end_row; ++v) {
      size_t noise_at =
          noise_base + static_cast<size_t>(v) * static_cast<size_t>(view.width) * channels;
      const auto light = static_cast<float>(
          o.exposure * (1.0 + o.illumination_gradient * ((v + 0.5) / view.height - 0.5)));
      const auto* shade = shade_.ptr<float>(v);
      const auto* mat = material_.ptr<uint8_t>(v);
      const auto* shadow = shadow_.ptr<uint8_t>(v);
      auto* label = out.labels.ptr<uint8_t>(v);
      auto* pixel = out.image.ptr<uint8_t>(v);
      for (int u = 0; u < view.width; ++u) {
        const uint8_t m = mat[u];
        label[u] = (m == kCrop || m == kWeed) ? m : 0;
        float gain = light * shade[u];
        if ((shadow[u] & kVehicleShadow) != 0) gain *= vehicle_shadow;
        if ((shadow[u] & kPlantShadow) != 0 && (m == kSoil || m == kStone)) gain *= plant_shadow;
        if (!rgb) {
          const float value =
              nir[m] * gain + noise * noise_table_[(noise_at++) & (kNoiseTable - 1U)];
          pixel[u] = cv::saturate_cast<uint8_t>(255.0F * value);
          continue;
        }
        for (int ch = 0; ch < 3; ++ch) {
          const float value = colour[m][static_cast<size_t>(ch)] * gain +
                              noise * noise_table_[(noise_at++) & (kNoiseTable - 1U)];
          pixel[3 * u + ch] = cv::saturate_cast<uint8_t>(255.0F * value);
        }
      }
    }
  });
  // Per-plant visible area and centroid from the instance image.
  for (int v = 0; v < view.height; ++v) {
    const auto* inst = out.instances.ptr<uint16_t>(v);
    for (int u = 0; u < view.width; ++u) {
      if (inst[u] == 0) continue;
      RenderedPlant& p = out.plants[inst[u] - 1U];
      ++p.area_px;
      p.centroid_px += Eigen::Vector2d(u + 0.5, v + 0.5);
    }
  }
  for (RenderedPlant& p : out.plants) {
    if (p.area_px > 0) p.centroid_px /= p.area_px;
  }
}

void Renderer::Blur(const View& view, double blur_m, RenderedFrame& out) {
  // Forward motion smears the image along v by the ground distance covered
  // during the exposure, in pixels at the principal point.
  if (blur_m <= 0.0) return;
  const Eigen::Vector2d c = view.camera->principal_point();
  const double h = view.camera->options().height_m;
  const Eigen::Matrix2d j = view.camera->ImageToPlaneJacobian(c, 0.0);
  if (!std::isfinite(j(1, 1)) || std::abs(j(1, 1)) < 1e-12 || h <= 0.0) return;
  const int length = static_cast<int>(std::lround(blur_m / std::abs(j(1, 1))));
  if (length >= 2) cv::blur(out.image, out.image, cv::Size(1, length));
}

}  // namespace plantscale::sim
