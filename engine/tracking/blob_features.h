#pragma once
// Segmented blobs (engine/vision) as tracker features.

#include <span>
#include <vector>

#include "engine/geometry/centroid_height.h"
#include "engine/tracking/feature.h"
#include "engine/vision/blobs.h"

namespace plantscale::tracking {

// Blobs whose centroid ray misses the virtual ground plane are left out; a
// blob whose bounding box touches the image border is marked clipped. With
// `heights` (GridTracker::centroid_heights()) the centroid is located as the
// tracker locates it, so that blobs compare with its predictions.
void FeaturesFromBlobs(std::span<const vision::Blob> blobs, int image_width_px,
                       int image_height_px, std::vector<Feature>& out,
                       const geometry::CentroidHeights* heights = nullptr);

}  // namespace plantscale::tracking
