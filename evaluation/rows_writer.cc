#include "evaluation/rows_writer.h"

#include <iomanip>

namespace plantscale::app {

nlohmann::json ToJson(const RowsEvaluation& e) {
  return {{"preset", e.preset},
          {"seeds", e.seeds},
          {"tilt_deg", e.tilt_deg},
          {"frames", e.frames},
          {"frames_with_rows", e.frames_with_rows},
          {"image_rows_scored", e.image_rows_scored},
          {"crda_mean", e.crda_mean},
          {"crda_frame_p10", e.crda_frame_p10},
          {"spacing_error_rel", e.spacing_error_rel},
          {"crda_per_seed", e.crda_per_seed}};
}

void WriteTable(const RowsEvaluation& e, std::ostream& out) {
  out << std::fixed << std::setprecision(3) << "preset " << e.preset << ", " << e.seeds
      << " seed(s), " << e.frames << " frames at tilt " << e.tilt_deg << " deg ("
      << e.frames_with_rows << " with rows)\n"
      << "crda_mean        " << e.crda_mean << "  (target >= 0.9)\n"
      << "crda_frame_p10   " << e.crda_frame_p10 << '\n'
      << "spacing_error    " << 100.0 * e.spacing_error_rel << " % at the bottom row\n";
}

nlohmann::json ToJson(const PhotoRowsEvaluation& e) {
  nlohmann::json per_image = nlohmann::json::array();
  for (const PhotoRowScore& s : e.per_image) {
    per_image.push_back({{"image", s.image},
                         {"crda", s.crda},
                         {"image_rows_scored", s.image_rows_scored},
                         {"rows_found", s.rows_found}});
  }
  return {{"images", e.images},
          {"images_with_rows", e.images_with_rows},
          {"image_rows_scored", e.image_rows_scored},
          {"crda_mean", e.crda_mean},
          {"per_image", per_image},
          {"mask", e.model ? "model crop class" : "excess green"},
          {"source", "labelled photographs"}};
}

void WriteTable(const PhotoRowsEvaluation& e, std::ostream& out) {
  out << "labelled photographs: " << e.images << " images (" << e.images_with_rows
      << " with rows), " << e.image_rows_scored << " image rows scored\n"
      << "crda_mean " << std::fixed << std::setprecision(3) << e.crda_mean << '\n';
}

nlohmann::json PhotoRowsJsonShape() {
  PhotoRowsEvaluation e;
  e.model = true;
  return ToJson(e);
}

}  // namespace plantscale::app
