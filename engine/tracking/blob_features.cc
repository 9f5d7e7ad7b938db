#include "engine/tracking/blob_features.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace plantscale::tracking {
namespace {

// The image's major axis (2σ) through the plane's Jacobian at the centroid.
void MajorAxis(const Eigen::Matrix2d& covariance_px2, const Eigen::Matrix2d& locate, Feature& f) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(covariance_px2);
  if (eig.info() != Eigen::Success) return;
  const double major = eig.eigenvalues()(1);
  const double minor = eig.eigenvalues()(0);
  if (!(major > 0.0)) return;
  f.axis_m = locate * (2.0 * std::sqrt(major) * eig.eigenvectors().col(1));
  f.elongation = minor > 0.0 ? std::sqrt(major / minor) : 1e6;
  if (!f.axis_m.allFinite()) {
    f.axis_m.setZero();
    f.elongation = 0.0;
  }
}

}  // namespace

void FeaturesFromBlobs(std::span<const vision::Blob> blobs, int width, int height,
                       std::vector<Feature>& out, const geometry::CentroidHeights* heights) {
  out.clear();
  for (const vision::Blob& b : blobs) {
    if (!b.on_ground) continue;
    Feature f;
    f.ground_m = b.ground_m;
    if (heights) {
      const auto located = heights->Locate(b.centroid_px);
      if (located) {
        f.ground_m = *located;
        MajorAxis(b.covariance_px2, heights->LocateJacobian(b.centroid_px), f);
      }
    }
    f.image_px = b.centroid_px;
    f.area_m2 = b.ground_area_m2;
    f.box_u0_px = b.bbox_px.x;
    f.box_v0_px = b.bbox_px.y;
    f.box_u1_px = b.bbox_px.x + b.bbox_px.width;
    f.box_v1_px = b.bbox_px.y + b.bbox_px.height;
    f.clipped = b.bbox_px.x <= 0 || b.bbox_px.y <= 0 || b.bbox_px.x + b.bbox_px.width >= width ||
                b.bbox_px.y + b.bbox_px.height >= height;
    out.push_back(f);
  }
}

}  // namespace plantscale::tracking
