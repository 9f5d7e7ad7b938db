#include "app/sim_output.h"


#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <ostream>
#include <set>
#include <sstream>

#include "app/config/progress.h"
#include "maps/staged_output.h"

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

std::ofstream OpenCsv(const fs::path& file, const std::string& header) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot be created");
  out << std::setprecision(9) << header << '\n';
  return out;
}

void CloseChecked(std::ofstream& out, const fs::path& file) {
  out.close();
  if (!out) throw std::runtime_error(file.string() + ": write failed (disk full?)");
}

void WritePng(const fs::path& file, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(file.string(), image);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(file.string() + ": cannot write PNG: " + e.what());
  }
  if (!ok) throw std::runtime_error(file.string() + ": cannot write PNG");
}

std::string FrameName(int index) {
  std::ostringstream name;
  name << std::setw(6) << std::setfill('0') << index << ".png";
  return name.str();
}

struct TruthFiles {
  explicit TruthFiles(const fs::path& folder)
      : dir(folder),
        frames(OpenCsv(folder / "frames.csv",
                       "frame,utime,x_m,y_m,heading_rad,distance_m,t_x_m,Y_m,psi_rad,"
                       "row_spacing_m,plant_spacing_m,line0,camera_pitch_rad,camera_roll_rad,"
                       "camera_height_offset_m,plants_visible,image")),
        visible(
            OpenCsv(folder / "visible_plants.csv",
                    "frame,instance,plant_id,class,row,line,x_m,y_m,vehicle_x_m,vehicle_y_m,"
                    "radius_m,height_m,root_u_px,root_v_px,area_px,centroid_u_px,centroid_v_px")),
        odometry(OpenCsv(folder / "odometry.csv",
                         "utime,left_m_s,right_m_s,true_left_m_s,true_right_m_s,slipping")) {
    // Speeds that read back as the same doubles: `run --odometry` feeds them
    // to the pipeline as simulate --publish does.
    odometry << std::setprecision(std::numeric_limits<double>::max_digits10);
  }

  void Close() {
    CloseChecked(frames, dir / "frames.csv");
    CloseChecked(visible, dir / "visible_plants.csv");
    CloseChecked(odometry, dir / "odometry.csv");
  }

  fs::path dir;
  std::ofstream frames;
  std::ofstream visible;
  std::ofstream odometry;
};

void WriteFrameTruth(TruthFiles& t, const sim::SimFrame& f, const std::string& image) {
  const sim::FrameTruth& x = f.truth;
  t.frames << x.index << ',' << x.utime << ',' << x.pose.x_m << ',' << x.pose.y_m << ','
           << x.pose.heading_rad << ',' << x.distance_m << ',' << x.grid.offset_m << ','
           << x.grid.forward_m << ',' << x.grid.bearing_rad << ',' << x.grid.row_spacing_m << ','
           << x.grid.plant_spacing_m << ',' << x.line0 << ',' << x.bounce.pitch_rad << ','
           << x.bounce.roll_rad << ',' << x.bounce.height_m << ',' << x.plants.size() << ','
           << image << '\n';
  for (const sim::PlantTruth& p : x.plants) {
    t.visible << x.index << ',' << p.instance << ',' << p.plant_id << ',' << sim::ToString(p.cls)
              << ',' << p.row << ',' << p.line << ',' << p.field_m.x() << ',' << p.field_m.y()
              << ',' << p.vehicle_m.x() << ',' << p.vehicle_m.y() << ',' << p.radius_m << ','
              << p.height_m << ',';
    if (p.root_px) {
      t.visible << p.root_px->x() << ',' << p.root_px->y();
    } else {
      t.visible << ',';
    }
    t.visible << ',' << p.area_px << ',' << p.centroid_px.x() << ',' << p.centroid_px.y() << '\n';
  }
  for (const sim::OdometrySample& s : f.odometry) {
    t.odometry << s.utime << ',' << s.left_m_s << ',' << s.right_m_s << ',' << s.true_left_m_s
               << ',' << s.true_right_m_s << ',' << (s.slipping ? 1 : 0) << '\n';
  }
}

void WriteFieldTruth(const fs::path& dir, const sim::Field& field) {
  const fs::path plants_file = dir / "plants.csv";
  std::ofstream plants =
      OpenCsv(plants_file, "plant_id,class,row,line,x_m,y_m,radius_m,height_m,fractured");
  for (const sim::Plant& p : field.plants()) {
    plants << p.id << ',' << sim::ToString(p.cls) << ',' << p.row << ',' << p.line << ','
           << p.position_m.x() << ',' << p.position_m.y() << ',' << p.radius_m << ',' << p.height_m
           << ',' << (p.fractured_lobe >= 0 ? 1 : 0) << '\n';
  }
  CloseChecked(plants, plants_file);
  const fs::path lines_file = dir / "lines.csv";
  std::ofstream lines = OpenCsv(lines_file, "line,y_m,row_spacing_m,plant_spacing_m");
  for (size_t i = 0; i < field.line_y_m().size(); ++i) {
    const double y = field.line_y_m()[i];
    lines << i << ',' << y << ',' << field.RowSpacingAt(y) << ',' << field.PlantSpacingAt(y)
          << '\n';
  }
  CloseChecked(lines, lines_file);
}

nlohmann::json RunJson(const SimulateRequest& r, const SimulateSummary& s,
                       const sim::Simulator& sim) {
  const geometry::CameraOptions& c = r.options.camera;
  return {
      {"preset", r.options.preset},
      {"seed", r.options.seed},
      {"length_m", r.options.length_m},
      {"frames", s.frames},
      {"dropped_frames", s.dropped},
      {"images_written", s.images_written},
      {"image_every", r.image_every},
      {"image", r.options.render.kind == sim::ImageKind::kRgb ? "rgb" : "nir"},
      {"crops_in_field", s.crops_in_field},
      {"weeds_in_field", s.weeds_in_field},
      {"camera",
       {{"height_m", c.height_m},
        {"tilt_rad", c.tilt_rad},
        {"focal_length_m", c.focal_length_m},
        {"pixel_width_m", c.pixel_width_m},
        {"pixel_height_m", c.pixel_height_m},
        {"image_width_px", c.image_width_px},
        {"image_height_px", c.image_height_px},
        {"principal_point_u_px", sim.camera().principal_point().x()},
        {"principal_point_v_px", sim.camera().principal_point().y()},
        {"virtual_plane_height_m", c.virtual_plane_height_m}}},
      {"labels", {{"0", "soil"}, {"1", "crop"}, {"2", "weed"}}},
  };
}

}  // namespace

SimulateSummary RunSimulation(const SimulateRequest& request, std::ostream& progress_out) {
  const auto wall_start = Clock::now();
  sim::Simulator simulator(request.options);  // validates before anything is written
  // The output folder is written under a temporary name beside it and
  // replaces the old one whole once complete.
  maps::StagedFile staging(request.out);
  const fs::path root = staging.temp_path();
  for (const char* sub : {"frames", "labels", "instances", "truth"}) {
    std::error_code ec;
    fs::create_directories(root / sub, ec);
    if (ec) throw std::runtime_error((root / sub).string() + ": cannot create folder: " + ec.message());
  }
  TruthFiles truth(root / "truth");
  WriteFieldTruth(root / "truth", simulator.field());

  SimulateSummary s;
  s.crops_in_field = simulator.field().crop_count();
  s.weeds_in_field = simulator.field().weed_count();
  ProgressBar bar(progress_out, "simulate", simulator.expected_frames(), request.progress);
  std::set<int> seen;
  double offset2 = 0.0;
  double plant_pixels = 0.0;
  int plant_count = 0;
  sim::SimFrame frame;
  Clock::duration engine_time{};
  for (;;) {
    const auto t0 = Clock::now();
    if (!simulator.Next(frame)) break;
    engine_time += Clock::now() - t0;
    const sim::FrameTruth& x = frame.truth;
    std::string image;
    if (x.index % request.image_every == 0) {
      image = FrameName(x.index);
      WritePng(root / "frames" / image, frame.rendered.image);
      WritePng(root / "labels" / image, frame.rendered.labels);
      WritePng(root / "instances" / image, frame.rendered.instances);
      ++s.images_written;
    }
    WriteFrameTruth(truth, frame, image);
    for (const sim::OdometrySample& o : frame.odometry) {
      s.odometry_distance_m +=
          0.5 * (o.left_m_s + o.right_m_s) / request.options.vehicle.odometry_rate_hz;
    }
    for (const sim::PlantTruth& p : x.plants) {
      seen.insert(p.plant_id);
      plant_pixels += p.area_px;
      ++plant_count;
    }
    offset2 += x.grid.offset_m * x.grid.offset_m;
    s.max_abs_offset_m = std::max(s.max_abs_offset_m, std::abs(x.grid.offset_m));
    s.max_abs_bearing_rad = std::max(s.max_abs_bearing_rad, std::abs(x.grid.bearing_rad));
    s.distance_m = x.distance_m;
    ++s.frames;
    bar.Update(s.frames);
  }
  bar.Finish();
  s.dropped = simulator.dropped_frames();
  s.plants_seen = static_cast<int>(seen.size());
  s.rms_offset_m = s.frames > 0 ? std::sqrt(offset2 / s.frames) : 0.0;
  s.mean_plant_pixels = plant_count > 0 ? plant_pixels / plant_count : 0.0;
  s.simulate_seconds = std::chrono::duration<double>(engine_time).count();
  truth.Close();
  const fs::path run_file = root / "run.json";
  std::ofstream run(run_file);
  run << RunJson(request, s, simulator).dump(2) << '\n';
  CloseChecked(run, run_file);
  staging.Commit();
  s.wall_seconds = std::chrono::duration<double>(Clock::now() - wall_start).count();
  return s;
}

}  // namespace plantscale::app
