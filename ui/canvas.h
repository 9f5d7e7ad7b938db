#pragma once
// An off-screen (or on-screen) VTK render window of a fixed size whose
// pixels can be read back. VTK 9.1 here renders only through GLX and aborts
// the process without an X server, so a canvas calls RequireDisplay()
// (ui/display.h) first.

#include <vtkNew.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "ui/display.h"

namespace plantscale::ui {

struct Rgb {
  double r = 0.0, g = 0.0, b = 0.0;  // 0..1
};

// The window redraws only the renderers whose content changed since its last
// render (camera, background, viewport, props and their data; a renderer
// holding a prop it cannot track, such as a chart, is always redrawn): VTK
// renders into a framebuffer of its own that keeps the other viewports'
// pixels. On screen it copies colour only to the X window (VTK 9.1 also
// copies depth there, a full-window shader pass under llvmpipe that nothing
// reads).
class Canvas {
 public:
  // Throws DisplayError without DISPLAY.
  Canvas(int width_px, int height_px, bool offscreen = true);
  vtkRenderWindow* window() { return window_; }
  // A renderer over the viewport (x0, y0)–(x1, y1), normalised, y up.
  vtkRenderer* AddRenderer(double x0, double y0, double x1, double y1, Rgb background);
  // Renders and reads the colour buffer back: 8-bit BGR, top row first.
  cv::Mat Render();
  // Off: every renderer is drawn on every render (to compare against).
  void SetPartialRedraw(bool on);

 private:
  vtkSmartPointer<vtkRenderWindow> window_;
};

// Throws std::runtime_error naming the file when it cannot be written.
void WritePng(const cv::Mat& bgr, const std::filesystem::path& path);

}  // namespace plantscale::ui
