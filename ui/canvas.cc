#include "ui/canvas.h"

#include <vtkUnsignedCharArray.h>

#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace plantscale::ui {

bool DisplayAvailable() {
  const char* display = std::getenv("DISPLAY");
  return display != nullptr && display[0] != '\0';
}

void RequireDisplay(const std::string& what) {
  if (DisplayAvailable()) return;
  throw DisplayError(what +
                     " needs an X display (VTK renders through GLX) and DISPLAY is not set; "
                     "run it under a virtual one: xvfb-run -a plantscale ...");
}

Canvas::Canvas(int width_px, int height_px, bool offscreen) {
  RequireDisplay("rendering");
  window_->SetSize(width_px, height_px);
  window_->SetOffScreenRendering(offscreen ? 1 : 0);
  window_->SetMultiSamples(0);  // identical pixels run to run
  window_->SetAlphaBitPlanes(0);
}

vtkRenderer* Canvas::AddRenderer(double x0, double y0, double x1, double y1, Rgb background) {
  vtkNew<vtkRenderer> renderer;
  renderer->SetViewport(x0, y0, x1, y1);
  renderer->SetBackground(background.r, background.g, background.b);
  window_->AddRenderer(renderer);
  return renderer;  // owned by the window
}

cv::Mat Canvas::Render() {
  window_->Render();
  const int* size = window_->GetSize();
  const int w = size[0], h = size[1];
  vtkNew<vtkUnsignedCharArray> pixels;
  window_->GetPixelData(0, 0, w - 1, h - 1, 0, pixels);  // back buffer, bottom row first
  cv::Mat rgb(h, w, CV_8UC3, pixels->GetPointer(0));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  cv::flip(bgr, bgr, 0);
  return bgr;
}

void WritePng(const cv::Mat& bgr, const std::filesystem::path& path) {
  const std::vector<int> params{cv::IMWRITE_PNG_COMPRESSION, 6};
  if (!cv::imwrite(path.string(), bgr, params)) {
    throw std::runtime_error(path.string() + ": cannot write PNG");
  }
}

}  // namespace plantscale::ui
