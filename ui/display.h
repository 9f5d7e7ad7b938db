#pragma once
// The X display check, with no VTK types: VTK 9.1 here renders only through
// GLX and aborts the process without an X server, so everything that renders
// (ui/canvas.h) calls RequireDisplay() first, and app/ asks DisplayAvailable()
// before it starts a station or draws the report's camera views.

#include <stdexcept>
#include <string>

namespace plantscale::ui {

// No X display to render with.
class DisplayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// DISPLAY is set (and not empty).
bool DisplayAvailable();
// Throws DisplayError naming `what` and how to get a display (xvfb-run -a).
void RequireDisplay(const std::string& what);

}  // namespace plantscale::ui
