#include "ui/display.h"

#include <cstdlib>

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

}  // namespace plantscale::ui
