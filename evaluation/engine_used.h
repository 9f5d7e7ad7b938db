#pragma once
// What a simulated evaluation configured its engine from, carried in its
// result so that the result alone is enough to write its JSON and table:
// the crop and vehicle profiles' names and the calibration error's sds,
// as parsed and as given on the command line.

#include <string>

#include "app/config/profiles.h"

namespace plantscale::app {

struct EngineUsed {
  std::string crop, vehicle;           // the profiles' names
  CalibrationError calibration_error;  // the sds (each seed draws its own signs)
  std::string calibration_error_text;  // as given; empty: none
  std::string segmenter_model;         // the learned model's file; empty: the grid's rule alone

  static EngineUsed Of(const Profiles& profiles, const CalibrationError& error,
                       const std::string& text) {
    return {profiles.crop.name, profiles.vehicle.name, error, text, profiles.crop.segmenter_model};
  }
};

}  // namespace plantscale::app
