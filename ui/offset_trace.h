#pragma once
// Row-offset trace: the filter's lateral offset t_x (mm, left axis) and
// bearing ψ (degrees, right axis) against distance driven, each with its
// ±2σ band, and the simulator's truth offset when it is in the log. A VTK
// chart (vtkChartXY) drawn through a context actor, so it shares a window
// with the other pieces.

#include <vtkChartXY.h>
#include <vtkImageActor.h>
#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>
#include <vtkContextActor.h>
#include <vtkNew.h>
#include <vtkRenderer.h>
#include <vtkTable.h>

#include "review/run_model.h"

namespace plantscale::ui {

struct OffsetTraceParams {
  double band_sigmas = 2.0;
  double window_m = 0.0;  // > 0: only the last window_m of distance (the station)
  int max_points = 2000;  // decimated beyond this
  // > 0: draw the chart into a picture of this size in its own off-screen
  // window, redrawn when the trace has grown by `redraw_every` samples, and
  // show the picture (a VTK chart costs more per frame than the rest of
  // the station together; the picture costs one texture).
  int cached_width_px = 0, cached_height_px = 0;
  int redraw_every = 6;  // 0.5 s at 12.5 Hz
};

class OffsetTrace {
 public:
  explicit OffsetTrace(const OffsetTraceParams& params = {});
  void AddTo(vtkRenderer* renderer);
  void Update(const review::RunModel& model);
  void SetVisible(bool visible);

 private:
  void Build();
  void Rasterise();
  void Fill(vtkTable* table, const std::vector<review::TraceSample>& trace) const;
  size_t WindowStart(const std::vector<review::TraceSample>& trace) const;
  // The distance axis's ticks, labelled in metres along the bed, over the
  // drawn span [from_m, to_m].
  void SetDistanceTicks(double from_m, double to_m);

  OffsetTraceParams params_;
  vtkNew<vtkContextActor> actor_;
  vtkNew<vtkChartXY> chart_;
  vtkNew<vtkTable> estimate_;
  vtkNew<vtkTable> truth_;
  // Distances are drawn less this origin (a multiple of 10 m at the
  // window's start) and labelled whole: the chart's area plots (the ±2σ
  // bands) and its lines took kilometre-scale distances apart, the bands
  // drawn metres behind their lines at 2.5 km (VTK 9.1's shift and scale).
  double origin_m_ = 0.0;
  size_t seen_ = static_cast<size_t>(-1);
  size_t seen_truth_ = static_cast<size_t>(-1);
  size_t drawn_ = static_cast<size_t>(-1);
  vtkSmartPointer<vtkRenderWindow> cache_window_;
  vtkNew<vtkImageActor> cache_actor_;
  vtkRenderer* renderer_ = nullptr;
};

}  // namespace plantscale::ui
