#include "engine/tracking/blob_features.h"

namespace plantscale::tracking {

void FeaturesFromBlobs(std::span<const vision::Blob> blobs, int width, int height,
                       std::vector<Feature>& out, const geometry::CentroidHeights* heights) {
  out.clear();
  for (const vision::Blob& b : blobs) {
    if (!b.on_ground) continue;
    Feature f;
    f.ground_m = b.ground_m;
    if (heights) {
      const auto located = heights->Locate(b.centroid_px);
      if (located) f.ground_m = *located;
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
