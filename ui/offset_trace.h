#pragma once
// Row-offset trace: the filter's lateral offset t_x (mm, left axis) and
// bearing ψ (degrees, right axis) against distance driven, each with its
// ±2σ band, and the simulator's truth offset when it is in the log. A VTK
// chart (vtkChartXY) drawn through a context actor, so it shares a window
// with the other pieces.

#include <vtkChartXY.h>
#include <vtkContextActor.h>
#include <vtkNew.h>
#include <vtkRenderer.h>
#include <vtkTable.h>

#include "ui/run_model.h"

namespace plantscale::ui {

struct OffsetTraceParams {
  double band_sigmas = 2.0;
  double window_m = 0.0;  // > 0: only the last window_m of distance (the station)
  int max_points = 2000;  // decimated beyond this
};

class OffsetTrace {
 public:
  explicit OffsetTrace(const OffsetTraceParams& params = {});
  void AddTo(vtkRenderer* renderer);
  void Update(const RunModel& model);
  void SetVisible(bool visible);

 private:
  void Build();
  void Fill(vtkTable* table, const std::vector<TraceSample>& trace) const;

  OffsetTraceParams params_;
  vtkNew<vtkContextActor> actor_;
  vtkNew<vtkChartXY> chart_;
  vtkNew<vtkTable> estimate_;
  vtkNew<vtkTable> truth_;
  size_t seen_ = static_cast<size_t>(-1);
  size_t seen_truth_ = static_cast<size_t>(-1);
};

}  // namespace plantscale::ui
