#pragma once
// Where the plant matter's streaks point: the local orientation of a plant
// image (structure tensor), and how well a row geometry's lines through the
// vanishing point agree with it.
//
// Why: the row comb (comb.h) weighs plant matter by its mass, so a big plant
// in the near field can carry a wrong geometry (a comb of twice the spacing
// leaning through it). Farther up, where the rows are narrow and many, every
// row and every gap between rows is a streak pointing at the vanishing
// point; a leaf's edges point anywhere. Each cell of the field holds the
// direction of its gradient n and its coherence; a geometry is scored by the
// mean over cells (coherence² weighted) of sin^16 of the angle between n and
// the row line through the cell, minus what the same mean is for streaks
// pointing at random (0.196): 0 when the geometry explains no more than
// chance, up to 0.8 when every streak points along its row line.

#include <opencv2/core.hpp>
#include <vector>

namespace plantscale::rows {

class OrientationField {
 public:
  // `plant` is CV_32FC1 (plant fraction); `scale_u`, `scale_v` image pixels
  // per pixel of it across and down; v_bottom the image's bottom pixel row
  // centre (image pixels).
  void Build(const cv::Mat& plant, double scale_u, double scale_v, double v_bottom);

  // Agreement, beyond chance, of the row lines of geometry (g, c) with the
  // streaks: u_n(v) = s·(1 − g·Δv) + c·Δv through each cell (row_detector.h).
  // Cells above the vanishing point do not count. 0 without streaks.
  double Support(double g, double c) const;

  size_t cells() const { return u_.size(); }

  static constexpr double kChance = 6435.0 / 32768.0;  // mean of sin^16 over uniform angles

 private:
  // Cells, one array per quantity (the support loop vectorises): position
  // in image pixels (Δv up from the bottom row), unit gradient direction
  // in (u, Δv), weight coherence².
  std::vector<float> u_, dv_, nu_, nv_, weight_;
  double total_weight_ = 0.0;
  cv::Mat blurred_, gu_, gv_, juu_, juv_, jvv_;
};

}  // namespace plantscale::rows
