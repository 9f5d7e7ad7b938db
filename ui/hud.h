#pragma once
// Heads-up display and nozzle bar. The HUD strip shows speed, filter mode,
// frame rate, distance, link health and heartbeat age; its background turns
// red at once when the heartbeat is older than the lost-link limit (amber
// when nothing has arrived at all), and the first problem is spelt out. The
// nozzle bar shows each nozzle (closed grey, open blue, fault orange) with
// its shots over the last few seconds as a bar above it.

#include <vtkNew.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>

#include <string>
#include <vector>

#include "review/run_model.h"
#include "ui/poly.h"

namespace plantscale::ui {

struct HudParams {
  int font_size = 14;
};

// One line of HUD text for people (also used by the report).
std::string HudLine(const review::RunModel& model, int64_t now_utime);
std::string FilterModeName(telemetry::FilterMode mode);

class Hud {
 public:
  explicit Hud(const HudParams& params = {});
  void AddTo(vtkRenderer* renderer);
  void Update(const review::RunModel& model, int64_t now_utime);
  // Extra text on the right of the second line (station: play state, tool).
  void SetStatus(const std::string& text) { status_ = text; }

 private:
  HudParams params_;
  vtkRenderer* renderer_ = nullptr;
  vtkNew<vtkTextActor> line1_, line2_;
  std::string status_;
};

struct NozzleBarParams {
  double recent_s = 5.0;  // shots counted over this past window
  int full_scale_shots = 4;
};

class NozzleBarView {
 public:
  explicit NozzleBarView(const NozzleBarParams& params = {});
  void AddTo(vtkRenderer* renderer);
  void Update(const review::RunModel& model, int64_t now_utime);

 private:
  void Show(int nozzles);

  NozzleBarParams params_;
  vtkRenderer* renderer_ = nullptr;
  LineLayer closed_, open_, fault_, recent_;
  std::vector<int> shown_;  // per nozzle state and recent shots, then failsafe (empty: nothing yet)
  double aspect_ = 0.0;     // of the viewport the camera was fitted to
  vtkNew<vtkTextActor> label_;
};

}  // namespace plantscale::ui
