#include "ui/camera_view.h"

#include <vtkCamera.h>
#include <vtkImageData.h>
#include <vtkImageMapper3D.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "ui/palette.h"

namespace plantscale::ui {
namespace {

namespace tm = plantscale::telemetry;

Polyline Circle(const Eigen::Vector2d& c, double r) {
  return EllipseOutline(c, Eigen::Matrix2d::Identity() * r * r, 1.0, 20);
}

}  // namespace

CameraView::CameraView(const CameraViewParams& params)
    : params_(params),
      gate_k2_(review::EllipseScale2d(params.gate_probability)),
      crop_blobs_(palette::kBlobCrop, 2.0, 0.1),
      weed_blobs_(palette::kBlobWeed, 2.0, 0.1),
      other_blobs_(palette::kBlobUnknown, 2.0, 0.1),
      rows_(palette::kRowLine, 1.5, 0.2),
      gates_(palette::kGate, 1.0, 0.25) {
  image_->InterpolateOn();
  vtkNew<vtkImageData> blank;  // until a thumbnail arrives (VTK wants an input)
  blank->SetDimensions(1, 1, 1);
  blank->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  static_cast<unsigned char*>(blank->GetScalarPointer())[0] = 0;
  image_->GetMapper()->SetInputData(blank);
  image_->SetVisibility(false);
}

void CameraView::AddTo(vtkRenderer* renderer) {
  renderer_ = renderer;
  renderer->AddActor(image_);
  for (LineLayer* l : {&crop_blobs_, &weed_blobs_, &other_blobs_, &rows_, &gates_}) l->AddTo(renderer);
  grid_points_.AddTo(renderer);
  renderer->GetActiveCamera()->ParallelProjectionOn();
  FitCamera();
}

void CameraView::SetVisible(bool visible) {
  visible_ = visible;
  image_->SetVisibility(visible && has_image_);
  for (LineLayer* l : {&crop_blobs_, &weed_blobs_, &other_blobs_, &rows_, &gates_}) l->SetVisible(visible);
  grid_points_.SetVisible(visible);
}

Eigen::Vector2d CameraView::ToWorld(const Eigen::Vector2d& uv) const {
  const double sx = static_cast<double>(width_) / source_w_;
  const double sy = static_cast<double>(height_) / source_h_;
  return {uv.x() * sx, height_ - uv.y() * sy};
}

void CameraView::Update(const review::RunModel& model) {
  const tm::GridEstimate* grid = model.grid() ? &*model.grid() : model.truth() ? &*model.truth() : nullptr;
  const int64_t thumb = model.thumbnail() ? model.thumbnail()->seq : -1;
  const int64_t g = grid ? grid->utime : -1;
  if (thumb == seen_thumbnail_ && g == seen_grid_) return;
  Show(model.thumbnail() ? &*model.thumbnail() : nullptr, grid);
  seen_thumbnail_ = thumb;
  seen_grid_ = g;
}

void CameraView::Show(const plantscale_thumbnail_t* thumbnail, const tm::GridEstimate* grid) {
  if (thumbnail != nullptr) {
    ShowImage(*thumbnail);
    ShowBlobs(*thumbnail);
  }
  if (grid != nullptr) {
    ShowGrid(*grid);
  } else {
    rows_.Set({});
    gates_.Set({});
    grid_points_.Set({}, {});
  }
  FitCamera();
}

void CameraView::ShowImage(const plantscale_thumbnail_t& t) {
  source_w_ = std::max<int>(1, t.source_width);
  source_h_ = std::max<int>(1, t.source_height);
  const cv::Mat bgr = cv::imdecode(t.jpeg, cv::IMREAD_COLOR);
  if (bgr.empty()) return;  // a bad JPEG keeps the previous picture
  width_ = bgr.cols, height_ = bgr.rows;
  vtkNew<vtkImageData> image;
  image->SetDimensions(width_, height_, 1);
  image->SetOrigin(0.5, 0.5, 0.0);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(image->GetScalarPointer());
  for (int row = 0; row < height_; ++row) {  // VTK row 0 is the bottom of the picture
    const cv::Vec3b* in = bgr.ptr<cv::Vec3b>(height_ - 1 - row);
    for (int col = 0; col < width_; ++col, out += 3) {
      out[0] = in[col][2], out[1] = in[col][1], out[2] = in[col][0];
    }
  }
  image_->GetMapper()->SetInputData(image);
  has_image_ = true;
  image_->SetVisibility(visible_);
  image_->Modified();
}

void CameraView::ShowBlobs(const plantscale_thumbnail_t& t) {
  std::vector<Polyline> crop, weed, other;
  const double scale = static_cast<double>(width_) / source_w_;
  for (const plantscale_blob_t& b : t.blobs) {
    const double r = std::max(6.5, 2.0 * scale * std::sqrt(std::max(0, b.area_px) / 3.14159));
    const Polyline c = Circle(ToWorld({b.u, b.v}), r);
    (b.cls == 1 ? crop : b.cls == 2 ? weed : other).push_back(c);
  }
  crop_blobs_.Set(crop);
  weed_blobs_.Set(weed);
  other_blobs_.Set(other);
}

void CameraView::ShowGrid(const tm::GridEstimate& g) {
  geometry::CameraOptions camera = params_.camera;
  camera.image_width_px = source_w_;
  camera.image_height_px = source_h_;
  const geometry::GridModel model(geometry::CameraModel(camera), params_.grid);
  const Eigen::Matrix2d r =
      Eigen::Matrix2d::Identity() * params_.measurement_sigma_px * params_.measurement_sigma_px;
  const double scale = static_cast<double>(width_) / source_w_;
  std::map<int, Polyline> rows;
  std::vector<Polyline> gates;
  std::vector<Eigen::Vector2d> points;
  for (const geometry::GridPlant& p : model.PlantsInView(g.state)) {
    const Eigen::Vector2d w = ToWorld(p.image_px);
    points.push_back(w);
    rows[p.n].push_back(w);
    const Eigen::Matrix<double, 2, 5> h = model.ImageOfPlantJacobian(g.state, p.m, p.n);
    Eigen::Matrix2d s = h * g.covariance * h.transpose() + r;
    s.row(1) *= -1.0, s.col(1) *= -1.0;  // v down → world y up
    gates.push_back(EllipseOutline(w, s * scale * scale, gate_k2_, 24));
  }
  std::vector<Polyline> row_lines;
  for (auto& [n, line] : rows) row_lines.push_back(std::move(line));
  rows_.Set(row_lines);
  gates_.Set(gates);
  grid_points_.Set(points, std::vector<Rgb>(points.size(), palette::kRowLine));
}

void CameraView::FitCamera() {
  if (renderer_ == nullptr) return;
  vtkCamera* c = renderer_->GetActiveCamera();
  const double aspect = std::max(1e-6, renderer_->GetTiledAspectRatio());
  const double half_h = std::max(0.5 * height_, 0.5 * width_ / aspect);
  c->SetFocalPoint(0.5 * width_, 0.5 * height_, 0.0);
  c->SetPosition(0.5 * width_, 0.5 * height_, 100.0);
  c->SetViewUp(0.0, 1.0, 0.0);
  c->SetParallelScale(half_h);
  c->SetClippingRange(1.0, 200.0);
}

}  // namespace plantscale::ui
