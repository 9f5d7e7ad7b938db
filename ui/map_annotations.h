#pragma once
// What the station draws over its map in screen space, so that the map reads
// without a manual: a legend (each colour and what it is, with the ellipses'
// confidence and magnification), a scale bar of a round length that follows
// the zoom, and, on `h` or `?`, the list of keys.

#include <vtkActor2D.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>

#include <string>
#include <vector>

#include "ui/canvas.h"

namespace plantscale::ui {

// The longest round length (1, 2 or 5 × 10^k m) no longer than `max_m`.
double RoundScaleLength(double max_m);
// "50 cm", "2 m", "500 m", "2 km".
std::string LengthText(double metres);

class MapAnnotations {
 public:
  MapAnnotations();
  void AddTo(vtkRenderer* renderer);
  // `metres_per_pixel` of the map now; `ellipses` says their confidence and
  // magnification (empty: ellipses hidden). Touches VTK only on a change.
  void Update(double metres_per_pixel, const std::string& ellipses);
  void SetHelp(const std::string& text);  // empty: hidden
  bool help_visible() const { return !help_text_.empty(); }

 private:
  void PlaceLegend();
  void PlaceScaleBar(double metres_per_pixel);

  vtkRenderer* renderer_ = nullptr;
  std::vector<vtkNew<vtkTextActor>> labels_;
  vtkNew<vtkPolyData> swatches_, bar_;
  vtkNew<vtkActor2D> swatch_actor_, bar_actor_;
  vtkNew<vtkTextActor> bar_label_, help_;
  std::string help_text_, ellipses_;
  double scale_mpp_ = -1.0;
  int width_px_ = -1, height_px_ = -1;
};

}  // namespace plantscale::ui
