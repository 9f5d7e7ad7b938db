#pragma once
// Segmented blobs (engine/vision) as tracker features.

#include <span>
#include <vector>

#include "engine/tracking/feature.h"
#include "engine/vision/blobs.h"

namespace plantscale::tracking {

// Blobs whose centroid ray misses the virtual ground plane are left out; a
// blob whose bounding box touches the image border is marked clipped.
void FeaturesFromBlobs(std::span<const vision::Blob> blobs, int image_width_px,
                       int image_height_px, std::vector<Feature>& out);

}  // namespace plantscale::tracking
