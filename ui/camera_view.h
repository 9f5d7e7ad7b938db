#pragma once
// The camera view: the latest thumbnail with the segmented blobs coloured by
// class, the predicted grid plants projected into the image (thesis eq. 4.12)
// joined along rows, and each plant's validation gate, the ellipse
// (z − h)ᵀ S⁻¹ (z − h) = γ with S = H P Hᵀ + R (thesis §4.2, eqs. 4.18–4.27).
// Drawn in thumbnail pixels, origin at the bottom-left (VTK), so image v is
// flipped: world y = thumbnail height − v.

#include <vtkImageActor.h>
#include <vtkNew.h>
#include <vtkRenderer.h>

#include "engine/geometry/grid_model.h"
#include "review/run_model.h"
#include "ui/poly.h"

namespace plantscale::ui {

struct CameraViewParams {
  geometry::CameraOptions camera;  // the vehicle's camera; image size from the thumbnail
  geometry::GridModelOptions grid;
  double measurement_sigma_px = 4.0;  // R = σ² I, full-size pixels
  double gate_probability = 0.99;     // γ from the χ²(2) quantile
};

class CameraView {
 public:
  explicit CameraView(const CameraViewParams& params = {});
  void AddTo(vtkRenderer* renderer);
  // From the model's latest thumbnail and grid.
  void Update(const review::RunModel& model);
  // From a given thumbnail and grid (event snapshots in the report).
  void Show(const plantscale_thumbnail_t* thumbnail, const telemetry::GridEstimate* grid);
  void SetVisible(bool visible);
  // Thumbnail pixel of full-size image point (u, v), in world (y up) units.
  Eigen::Vector2d ToWorld(const Eigen::Vector2d& uv_full) const;

 private:
  void ShowImage(const plantscale_thumbnail_t& thumbnail);
  void ShowBlobs(const plantscale_thumbnail_t& thumbnail);
  void ShowGrid(const telemetry::GridEstimate& grid);
  void FitCamera();

  CameraViewParams params_;
  double gate_k2_;
  vtkRenderer* renderer_ = nullptr;
  vtkNew<vtkImageActor> image_;
  LineLayer crop_blobs_, weed_blobs_, other_blobs_, rows_, gates_;
  PointLayer grid_points_{6.0, 0.3};
  int width_ = 320, height_ = 240;   // thumbnail
  int source_w_ = 640, source_h_ = 480;
  int64_t seen_thumbnail_ = -1;
  int64_t seen_grid_ = -1;
  bool visible_ = true, has_image_ = false;
};

}  // namespace plantscale::ui
