#include "ui/canvas.h"

#include <vtkCamera.h>
#include <vtkObjectFactory.h>
#include <vtkOpenGLFramebufferObject.h>
#include <vtkOpenGLState.h>
#include <vtkProp.h>
#include <vtkPropCollection.h>
#include <vtkRendererCollection.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXOpenGLRenderWindow.h>

#include <array>
#include <cstdlib>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "vtk_glew.h"

namespace plantscale::ui {
namespace {

// What a renderer's pixels depend on: its viewport and background, its
// camera, and its props with their data (vtkProp::GetRedrawMTime covers a
// prop's mapper, input, property and texture). Not the renderer's own MTime:
// switching its drawing on and off changes that.
struct RendererState {
  std::array<double, 7> viewport_background{};
  vtkMTimeType content = 0;
  int props = 0;
  bool trackable = true;

  bool operator==(const RendererState& o) const {
    return viewport_background == o.viewport_background && content == o.content && props == o.props;
  }
};

RendererState StateOf(vtkRenderer* r) {
  RendererState s;
  const double* v = r->GetViewport();
  const double* b = r->GetBackground();
  s.viewport_background = {v[0], v[1], v[2], v[3], b[0], b[1], b[2]};
  s.content = r->GetActiveCamera()->GetMTime();
  vtkPropCollection* props = r->GetViewProps();
  vtkCollectionSimpleIterator it;
  props->InitTraversal(it);
  while (vtkProp* p = props->GetNextProp(it)) {
    ++s.props;
    // A hidden prop draws nothing: its own MTime covers showing it again (and
    // skips the pipeline update GetRedrawMTime makes, for the map's culled tiles).
    s.content = std::max(s.content, p->GetVisibility() ? p->GetRedrawMTime() : p->GetMTime());
    // A context actor (chart) draws a scene whose changes its MTime misses.
    if (p->IsA("vtkContextActor")) s.trackable = false;
  }
  return s;
}

class CanvasWindow : public vtkXOpenGLRenderWindow {
 public:
  static CanvasWindow* New();
  vtkTypeMacro(CanvasWindow, vtkXOpenGLRenderWindow)

  void SetPartialRedraw(bool on) { partial_ = on, drawn_.clear(); }

  void Render() override {
    const bool all = !partial_ || this->Size[0] != drawn_size_[0] || this->Size[1] != drawn_size_[1];
    vtkRendererCollection* renderers = this->GetRenderers();
    vtkCollectionSimpleIterator it;
    renderers->InitTraversal(it);
    while (vtkRenderer* r = renderers->GetNextRenderer(it)) {
      const auto drawn = drawn_.find(r);
      const RendererState now = StateOf(r);
      r->SetDraw(all || !now.trackable || drawn == drawn_.end() || !(drawn->second == now));
    }
    vtkXOpenGLRenderWindow::Render();
    drawn_.clear();
    renderers->InitTraversal(it);
    while (vtkRenderer* r = renderers->GetNextRenderer(it)) {
      r->SetDraw(true);
      drawn_[r] = StateOf(r);  // after the render: drawing may touch a prop (text textures)
    }
    drawn_size_ = {this->Size[0], this->Size[1]};
  }

  // Same-format copies without a scissor test are a memcpy in llvmpipe, not a
  // shader pass; the scissor covers the whole window here anyway.
  void Frame() override {
    this->MakeCurrent();
    vtkOpenGLState::ScopedglEnableDisable scissor(this->GetState(), GL_SCISSOR_TEST);
    this->GetState()->vtkglDisable(GL_SCISSOR_TEST);
    vtkXOpenGLRenderWindow::Frame();
  }

 protected:
  // Colour only: VTK 9.1 also writes its depth buffer into the window's.
  void BlitDisplayFramebuffersToHardware() override {
    vtkOpenGLState* state = this->GetState();
    state->PushFramebufferBindings();
    state->vtkglViewport(0, 0, this->Size[0], this->Size[1]);
    state->vtkglScissor(0, 0, this->Size[0], this->Size[1]);
    state->vtkglBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    state->vtkglDrawBuffer(this->DoubleBuffer ? GL_BACK_LEFT : GL_FRONT_LEFT);
    this->DisplayFramebuffer->Bind(GL_READ_FRAMEBUFFER);
    this->DisplayFramebuffer->ActivateReadBuffer(0);
    state->vtkglBlitFramebuffer(0, 0, this->Size[0], this->Size[1], 0, 0, this->Size[0], this->Size[1],
                                GL_COLOR_BUFFER_BIT, GL_NEAREST);
    state->PopFramebufferBindings();
  }

 private:
  bool partial_ = true;
  std::map<vtkRenderer*, RendererState> drawn_;
  std::array<int, 2> drawn_size_{0, 0};
};

vtkStandardNewMacro(CanvasWindow);

}  // namespace

Canvas::Canvas(int width_px, int height_px, bool offscreen)
    : window_(vtkSmartPointer<CanvasWindow>::New()) {
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

void Canvas::SetPartialRedraw(bool on) { static_cast<CanvasWindow*>(window_.Get())->SetPartialRedraw(on); }

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
