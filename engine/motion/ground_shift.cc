#include "engine/motion/ground_shift.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

namespace plantscale::motion {

OptionErrors GroundShiftOptions::Validate() const {
  OptionErrors e;
  RequireNonNegative(e, "plane_height_m", plane_height_m);
  RequireInRange(e, "cell_m", cell_m, 0.001, 0.05);
  RequirePositive(e, "max_half_width_m", max_half_width_m);
  RequirePositive(e, "max_range_m", max_range_m);
  RequireInRange(e, "whiten", whiten, 0.0, 1.0);
  RequireInRange(e, "min_response", min_response, 0.0, 1.0);
  RequireInRange(e, "max_shift_fraction", max_shift_fraction, 0.01, 0.5);
  RequireInRange(e, "min_peak_ratio", min_peak_ratio, 1.0, 100.0);
  RequireInRange(e, "min_plant_fraction", min_plant_fraction, 0.0, 1.0);
  if (source == GroundShiftSource::kSoil && plane_height_m != 0.0)
    e.push_back({"plane_height_m", "must be 0 for the soil's texture (it lies on the ground)"});
  if (soil_plant_margin_px < 0 || soil_plant_margin_px > 32) e.push_back({"soil_plant_margin_px", "must be in [0, 32]"});
  if (soil_close_px < 0 || soil_close_px > 64) e.push_back({"soil_close_px", "must be in [0, 64]"});
  RequireInRange(e, "soil_detrend_m", soil_detrend_m, 0.01, 1.0);
  RequireInRange(e, "min_soil_fraction", min_soil_fraction, 0.0, 1.0);
  if (plants_fallback_height_m >= 0.0 && source != GroundShiftSource::kSoil)
    e.push_back({"plants_fallback_height_m", "must be negative (none) unless the soil is correlated"});
  RequireInRange(e, "max_half_disagreement_m", max_half_disagreement_m, 0.0, 1.0);
  if (measure_pitch && !measure_turn) e.push_back({"measure_pitch", "needs measure_turn (the same halves)"});
  if (measure_pitch && source != GroundShiftSource::kSoil)
    e.push_back({"measure_pitch", "needs the soil's texture (source soil)"});
  RequireInRange(e, "pitch_bias_weight", pitch_bias_weight, 0.0, 1.0);
  RequireInRange(e, "pitch_hold", pitch_hold, 0.0, 1.0);
  return e;
}

geometry::CameraModel WithPitch(const geometry::CameraModel& camera, double pitch_rad) {
  geometry::CameraOptions o = camera.options();
  o.tilt_rad += pitch_rad;
  return geometry::CameraModel(o);
}

GroundShiftOptions GroundShiftOptions::Soil() {
  GroundShiftOptions o;
  o.source = GroundShiftSource::kSoil;
  o.plane_height_m = 0.0;
  o.whiten = 0.7;
  o.measure_turn = true;
  o.gaussian_peak = true;
  o.mask_both_views = true;
  o.measure_pitch = true;
  return o;
}

GroundShiftEstimator::GroundShiftEstimator(const GroundShiftOptions& options,
                                           const geometry::CameraModel& camera)
    : options_(options), image_width_(camera.width()), image_height_(camera.height()),
      camera_height_m_(camera.centre().z() - options.plane_height_m) {
  ThrowIfInvalid("ground shift", options_.Validate());
  // The view: a rectangle inside the ground the image sees, so that the
  // image's edges, fixed to the camera, are not in it (they would pull
  // every shift towards none): across between the bottom corners (where
  // the ground seen is narrowest), along from the bottom edge's farthest
  // point for max_range_m, short of the top edge.
  const double w = camera.width(), h = camera.height();
  const auto on_plane = [&](double u, double v) { return camera.ImageToPlane({u, v}, options_.plane_height_m); };
  const auto left = on_plane(0.0, h), right = on_plane(w, h), middle = on_plane(0.5 * w, h);
  const auto far_left = on_plane(0.0, 0.0), far_right = on_plane(w, 0.0);
  if (!left || !right || !middle) throw DataError("ground shift: the camera's bottom edge sees no ground");
  const double x_lo = std::max(left->x(), -options_.max_half_width_m);
  const double x_hi = std::min(right->x(), options_.max_half_width_m);
  const double y_lo = std::max({left->y(), right->y(), middle->y()});
  double y_hi = y_lo + options_.max_range_m;
  if (far_left && far_right) y_hi = std::min({y_hi, far_left->y(), far_right->y()});
  if (!(y_hi > y_lo) || !(x_hi > x_lo)) throw DataError("ground shift: the camera sees no ground");
  // Sizes FFT-friendly (cv::getOptimalDFTSize), the view centred on what was asked
  // (rounded down, so the view stays inside).
  int nx = static_cast<int>(std::floor((x_hi - x_lo) / options_.cell_m));
  int ny = static_cast<int>(std::floor((y_hi - y_lo) / options_.cell_m));
  if (nx < 16 || ny < 16) throw DataError("ground shift: the ground seen is smaller than 16 cells");
  while (cv::getOptimalDFTSize(nx) != nx) --nx;
  while (cv::getOptimalDFTSize(ny) != ny) --ny;
  size_ = cv::Size(nx, ny);
  x0_ = 0.5 * (x_lo + x_hi) - 0.5 * nx * options_.cell_m;
  y0_ = 0.5 * (y_lo + y_hi) - 0.5 * ny * options_.cell_m;
  // Bird's-eye pixel (c, r) → plane (x0 + (c + ½)·cell, y0 + (r + ½)·cell)
  // → image (u, v) → OpenCV's pixel coordinates (u − ½, v − ½).
  const Eigen::Matrix3d h_plane = camera.PlaneToImageHomography(options_.plane_height_m);
  Eigen::Matrix3d to_plane;
  to_plane << options_.cell_m, 0.0, x0_ + 0.5 * options_.cell_m, 0.0, options_.cell_m,
      y0_ + 0.5 * options_.cell_m, 0.0, 0.0, 1.0;
  Eigen::Matrix3d to_cv;
  to_cv << 1.0, 0.0, -0.5, 0.0, 1.0, -0.5, 0.0, 0.0, 1.0;
  const Eigen::Matrix3d m = to_cv * h_plane * to_plane;
  to_image_ = cv::Mat(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) to_image_.at<double>(r, c) = m(r, c);
  }
  cv::createHanningWindow(window_, size_, CV_32F);
  cv::createHanningWindow(half_window_, cv::Size(size_.width, size_.height / 2), CV_32F);
  if (options_.plants_fallback_height_m >= 0.0) {
    GroundShiftOptions plants = options_;
    plants.source = GroundShiftSource::kPlants;
    plants.plane_height_m = options_.plants_fallback_height_m;
    plants.plants_fallback_height_m = -1.0;
    plants.whiten = GroundShiftOptions().whiten;
    plants.measure_turn = false;
    plants.measure_pitch = false;
    plants.gaussian_peak = false;
    plants_fallback_ = std::make_unique<GroundShiftEstimator>(plants, camera);
  }
}

void GroundShiftEstimator::Reset() {
  previous_.release();
  previous_weight_.release();
  if (plants_fallback_) plants_fallback_->Reset();
}

cv::Mat GroundShiftEstimator::BirdsEyeInput(const cv::Mat& mask) const {
  if (mask.empty() || mask.type() != CV_8UC1 || mask.cols != image_width_ || mask.rows != image_height_) {
    throw DataError("ground shift: the mask must be CV_8UC1 of " + std::to_string(image_width_) + "x" +
                    std::to_string(image_height_) + " pixels");
  }
  return mask > 0;
}

cv::Mat GroundShiftEstimator::BirdsEye(const cv::Mat& mask) const {
  cv::Mat plant, view;
  BirdsEyeInput(mask).convertTo(plant, CV_32F, 1.0 / 255.0);  // plant 1, soil 0
  cv::warpPerspective(plant, view, to_image_, size_, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  return view;
}

namespace {

// Cells either side of a correlation peak that belong to it (its main lobe
// after the Hann window and a parabola's sub-cell spread).
constexpr int kPeakExclusionCells = 4;

// The correlation's peak over its highest value beyond kPeakExclusionCells
// of it (wrapping, as the correlation does).
double PeakRatio(const cv::Mat& c, cv::Point peak, double max_value) {
  const int w = c.cols, h = c.rows;
  double second = 0.0;
  for (int y = 0; y < h; ++y) {
    int dy = std::abs(y - peak.y);
    dy = std::min(dy, h - dy);
    const float* row = c.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      int dx = std::abs(x - peak.x);
      dx = std::min(dx, w - dx);
      if (dx <= kPeakExclusionCells && dy <= kPeakExclusionCells) continue;
      second = std::max(second, static_cast<double>(row[x]));
    }
  }
  return second > 0.0 ? max_value / second : std::numeric_limits<double>::infinity();
}

// The shift of `b` against `a` (b(x) ≈ a(x − shift)) at the peak of their
// cross-correlation, its spectrum divided by its magnitude to the power
// `whiten` (1: phase correlation, 0: plain correlation); the peak placed
// to a fraction of a cell by a parabola through it and its neighbours
// along each axis (through their logarithms with `gaussian_peak`).
// `response`: the peak (whiten 1: 1 for two views one
// shift apart, near 0 for views that share nothing). `ratio`, when given:
// the peak over the highest value beyond `kPeakExclusionCells` of it (the
// runner-up shift; 1: two shifts explain the views equally well).
cv::Point2d Correlate(const cv::Mat& a, const cv::Mat& b, double whiten, bool gaussian_peak, double& response,
                      double* ratio = nullptr) {
  cv::Mat fa, fb, cross;
  cv::dft(a, fa, cv::DFT_COMPLEX_OUTPUT);
  cv::dft(b, fb, cv::DFT_COMPLEX_OUTPUT);
  cv::mulSpectrums(fb, fa, cross, 0, true);
  if (whiten > 0.0) {
    std::vector<cv::Mat> parts;
    cv::split(cross, parts);
    cv::Mat magnitude;
    cv::magnitude(parts[0], parts[1], magnitude);
    cv::pow(magnitude + 1e-9, whiten, magnitude);
    cv::divide(parts[0], magnitude, parts[0]);
    cv::divide(parts[1], magnitude, parts[1]);
    cv::merge(parts, cross);
  }
  cv::Mat c;
  cv::idft(cross, c, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  const int w = c.cols, h = c.rows;
  cv::Point peak;
  double max_value = 0.0;
  cv::minMaxLoc(c, nullptr, &max_value, nullptr, &peak);
  const auto at = [&](int x, int y) { return static_cast<double>(c.at<float>((y + h) % h, (x + w) % w)); };
  const auto vertex = [gaussian_peak](double l, double m, double r) {
    if (gaussian_peak && l > 0.0 && r > 0.0 && m > 0.0) {
      const double ll = std::log(l), lm = std::log(m), lr = std::log(r);
      const double dl = ll - 2.0 * lm + lr;
      if (dl < 0.0) return 0.5 * (ll - lr) / dl;
    }
    const double d = l - 2.0 * m + r;
    return d < 0.0 ? 0.5 * (l - r) / d : 0.0;
  };
  double x = peak.x + vertex(at(peak.x - 1, peak.y), max_value, at(peak.x + 1, peak.y));
  double y = peak.y + vertex(at(peak.x, peak.y - 1), max_value, at(peak.x, peak.y + 1));
  if (x > 0.5 * w) x -= w;
  if (y > 0.5 * h) y -= h;
  response = max_value;
  if (ratio != nullptr) *ratio = PeakRatio(c, peak, max_value);
  return {x, y};
}

}  // namespace

cv::Mat GroundShiftEstimator::PlantView(const cv::Mat& mask) {
  if (options_.source != GroundShiftSource::kPlants)
    throw DataError("ground shift: the soil's texture needs the image with the mask");
  cv::Mat view = BirdsEye(mask);
  const double fraction = cv::sum(view)[0] / static_cast<double>(view.total());
  if (fraction >= options_.min_plant_fraction) return view;
  previous_.release();
  return cv::Mat();
}

GroundShift GroundShiftEstimator::Update(const cv::Mat& mask) {
  cv::Mat view = PlantView(mask);
  if (view.empty()) {
    GroundShift out;
    out.reason = "too little plant matter in view";
    return out;
  }
  return Correlated(std::move(view), cv::Mat());
}

void GroundShiftEstimator::Remember(const cv::Mat& mask) {
  cv::Mat view = PlantView(mask);
  if (!view.empty()) previous_ = std::move(view);
}

cv::Mat GroundShiftEstimator::SoilView(const cv::Mat& image, const cv::Mat& mask, double& soil_fraction,
                                       cv::Mat* soil_weight) const {
  if (image.empty() || (image.type() != CV_8UC1 && image.type() != CV_8UC3) || image.cols != image_width_ ||
      image.rows != image_height_) {
    throw DataError("ground shift: the image must be CV_8UC1 or CV_8UC3 of " + std::to_string(image_width_) + "x" +
                    std::to_string(image_height_) + " pixels");
  }
  cv::Mat plants = BirdsEyeInput(mask);
  // A plant's holes and broken rings (leaves in their own shadow that the
  // segmenter left out) are plant too: the mask is closed, and each plant
  // cut out to its convex hull. Left in, a large crop's shaded heart
  // outweighed the soil's texture, and it moves with the leaves' height,
  // not the ground (preset A, tuning seeds 1–3: drift −34 cm/m; closed by
  // 5 px −4.9, by 10 px −2.7).
  if (options_.soil_close_px > 0) {
    const int k = 2 * options_.soil_close_px + 1;
    cv::morphologyEx(plants, plants, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  }
  std::vector<std::vector<cv::Point>> outlines;
  cv::findContours(plants, outlines, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  for (const auto& outline : outlines) {
    std::vector<cv::Point> hull;
    cv::convexHull(outline, hull);
    cv::fillConvexPoly(plants, hull, cv::Scalar(255));
  }
  if (options_.soil_plant_margin_px > 0) {
    const int k = 2 * options_.soil_plant_margin_px + 1;
    cv::dilate(plants, plants, cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  }
  cv::Mat grey, brightness, soil;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else {
    grey = image;
  }
  grey.convertTo(brightness, CV_32F, 1.0 / 255.0);
  cv::Mat(plants == 0).convertTo(soil, CV_32F, 1.0 / 255.0);  // soil 1, plant 0
  cv::Mat view, weight;
  cv::warpPerspective(brightness, view, to_image_, size_, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::warpPerspective(soil, weight, to_image_, size_, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::threshold(weight, weight, 0.999, 1.0, cv::THRESH_BINARY);  // wholly soil
  cv::multiply(view, weight, view);
  // The soil's local mean from the soil alone (normalised convolution).
  const double sigma = options_.soil_detrend_m / options_.cell_m;
  cv::Mat sum, count;
  cv::GaussianBlur(view, sum, cv::Size(), sigma);
  cv::GaussianBlur(weight, count, cv::Size(), sigma);
  cv::divide(sum, cv::max(count, 1e-3), sum);
  cv::subtract(view, sum, view);
  cv::multiply(view, weight, view);
  // What is left of plants, shadows' edges and glints clipped to 3σ of the
  // soil's texture, so that no one bright patch outweighs it.
  const double soil_cells = cv::sum(weight)[0];
  const double sd = std::sqrt(cv::sum(view.mul(view))[0] / std::max(1.0, soil_cells));
  if (sd > 0.0) {
    cv::min(view, 3.0 * sd, view);
    cv::max(view, -3.0 * sd, view);
  }
  soil_fraction = soil_cells / static_cast<double>(weight.total());
  if (soil_weight) *soil_weight = weight;
  return view;
}

GroundShift GroundShiftEstimator::Update(const cv::Mat& image, const cv::Mat& mask) {
  if (options_.source != GroundShiftSource::kSoil) return Update(mask);
  double soil = 0.0;
  cv::Mat weight;
  cv::Mat view = SoilView(image, mask, soil, &weight);
  GroundShift out;
  if (soil < options_.min_soil_fraction) {
    out.reason = "too little soil in view";
    previous_.release();
  } else {
    out = Correlated(std::move(view), std::move(weight));
  }
  out.source = GroundShiftSource::kSoil;
  if (options_.measure_pitch) {
    // Without a change measured the pitch returns towards level as well.
    pitch_rad_ = options_.pitch_hold * (pitch_rad_ + out.pitch_change_rad);
    out.pitch_rad = pitch_rad_;
  }
  if (!plants_fallback_) return out;
  if (out.valid) {
    plants_fallback_->Remember(mask);  // ready for the next frame the soil fails
    return out;
  }
  GroundShift plants = plants_fallback_->Update(mask);
  plants.pitch_rad = out.pitch_rad;
  if (!plants.valid) plants.reason = "soil: " + out.reason + "; plants: " + plants.reason;
  return plants;
}

GroundShift GroundShiftEstimator::Correlated(cv::Mat view, cv::Mat weight) {
  GroundShift out;
  if (previous_.empty()) {
    out.reason = "first frame";
    previous_ = std::move(view);
    previous_weight_ = std::move(weight);
    return out;
  }
  cv::Point2d p = Windowed(previous_, view, window_, out.response, &out.peak_ratio);
  // The turn from the views as they are: each view's holes carried over by
  // the shift alone would sit a turn's few millimetres off in the halves.
  const cv::Mat previous_view = std::move(previous_), current_view = view;
  const cv::Mat previous_weight = std::move(previous_weight_);
  previous_ = std::move(view);
  previous_weight_ = weight;
  if (!(out.response >= options_.min_response)) {
    out.t_m = Eigen::Vector2d(p.x * options_.cell_m, p.y * options_.cell_m);
    out.reason = "no clear correlation peak (" + std::to_string(out.response) + ")";
    return out;
  }
  if (!(out.peak_ratio >= options_.min_peak_ratio)) {
    out.t_m = Eigen::Vector2d(p.x * options_.cell_m, p.y * options_.cell_m);
    out.reason = "ambiguous correlation peak (" + std::to_string(out.peak_ratio) +
                 " times the runner-up shift's)";
    return out;
  }
  cv::Mat previous_exchanged, current_exchanged;  // empty unless mask_both_views
  if (options_.mask_both_views && !weight.empty() && !previous_weight.empty()) {
    // The holes where the plants were cut out move with the plants, faster
    // than the ground beneath them, and pull the peak with them. Each view
    // loses also the other's holes, carried over by the shift found: the
    // holes of both then move with the ground, and the correlation again.
    cv::Mat into_previous, into_current;
    const cv::Matx23d back(1.0, 0.0, p.x, 0.0, 1.0, p.y), ahead(1.0, 0.0, -p.x, 0.0, 1.0, -p.y);
    cv::warpAffine(weight, into_previous, back, size_, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                   cv::BORDER_CONSTANT, cv::Scalar(1));
    cv::warpAffine(previous_weight, into_current, ahead, size_, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                   cv::BORDER_CONSTANT, cv::Scalar(1));
    double response = 0.0;
    previous_exchanged = previous_view.mul(into_previous);
    current_exchanged = current_view.mul(into_current);
    p = Windowed(previous_exchanged, current_exchanged, window_, response);
  }
  out.t_m = Eigen::Vector2d(p.x * options_.cell_m, p.y * options_.cell_m);
  if (std::abs(p.x) > options_.max_shift_fraction * size_.width ||
      std::abs(p.y) > options_.max_shift_fraction * size_.height) {
    out.reason = "shift beyond a quarter of the view";
    return out;
  }
  out.valid = true;
  if (options_.measure_turn) {
    // The pitch from the views that lost each other's holes, if they did: the
    // holes' faster motion read the halves' along shifts apart (on tuning
    // seeds 1–12 the drift along +0.37 cm/m with the views as they are,
    // −0.01 with these).
    const bool exchanged = !previous_exchanged.empty();
    MeasureHalves({previous_view, current_view},
                  {exchanged ? previous_exchanged : previous_view, exchanged ? current_exchanged : current_view}, out);
  }
  return out;
}

bool GroundShiftEstimator::CanMeasure(const Eigen::Vector2d& expected_t_m) const {
  const double f = options_.max_shift_fraction * options_.cell_m;
  return std::abs(expected_t_m.x()) <= f * size_.width && std::abs(expected_t_m.y()) <= f * size_.height;
}

cv::Point2d GroundShiftEstimator::Windowed(const cv::Mat& previous, const cv::Mat& current, const cv::Mat& window,
                                           double& response, double* ratio) const {
  // The window on copies: a kept view is the next frame's previous one.
  cv::Mat a, b;
  cv::multiply(previous, window, a);
  cv::multiply(current, window, b);
  return Correlate(a, b, options_.whiten, options_.gaussian_peak, response, ratio);
}

void GroundShiftEstimator::MeasureHalves(const ViewPair& for_turn, const ViewPair& for_pitch, GroundShift& shift) {
  // The halves' shifts at their centres y_n and y_f: across Δx(y) = t_x − ψ·y,
  // along Δy(y) = t_y + Δθ·(H² + y²)/H.
  const int half = size_.height / 2;
  const cv::Rect near(0, 0, size_.width, half), far(0, size_.height - half, size_.width, half);
  cv::Point2d halves[2];
  const auto correlate_halves = [&](const ViewPair& views) {
    for (int k = 0; k < 2; ++k) {
      const cv::Rect& part = k == 0 ? near : far;
      double response = 0.0;
      halves[k] = Windowed(views.previous(part), views.current(part), half_window_, response) * options_.cell_m;
      if (!(response >= options_.min_response)) return false;
    }
    return true;
  };
  if (!correlate_halves(for_turn)) return;
  for (const cv::Point2d& h : halves) {
    if (std::abs(h.x - shift.t_m.x()) > options_.max_half_disagreement_m) return;
  }
  const double y_near = y0_ + 0.5 * half * options_.cell_m;
  const double y_far = y0_ + (size_.height - 0.5 * half) * options_.cell_m;
  shift.psi_rad = -(halves[1].x - halves[0].x) / (y_far - y_near);
  shift.turn_valid = true;
  // The view's shift is the motion of its centre c: R(ψ)·c + t − c ≈ t + ψ·(−c_y, c_x).
  const double cx = x0_ + 0.5 * size_.width * options_.cell_m, cy = y0_ + 0.5 * size_.height * options_.cell_m;
  shift.t_m += Eigen::Vector2d(shift.psi_rad * cy, -shift.psi_rad * cx);
  if (!options_.measure_pitch) return;
  if (for_pitch.previous.data != for_turn.previous.data && !correlate_halves(for_pitch)) return;
  for (const cv::Point2d& h : halves) {
    if (std::abs(h.y - shift.t_m.y()) > options_.max_half_disagreement_m) return;
  }
  const double H = camera_height_m_;
  const auto lever = [H](double y) { return (H * H + y * y) / H; };
  const double measured = (halves[1].y - halves[0].y) / (lever(y_far) - lever(y_near));
  pitch_bias_rad_ += options_.pitch_bias_weight * (measured - pitch_bias_rad_);
  shift.pitch_change_rad = measured - pitch_bias_rad_;
  shift.pitch_valid = true;
  shift.t_m.y() -= shift.pitch_change_rad * lever(cy);
}

}  // namespace plantscale::motion
