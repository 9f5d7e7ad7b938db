#include "app/archive_run.h"

#include <openssl/evp.h>

#include <ctime>
#include <fstream>
#include <numbers>

#include "app/config/run_config.h"
#include "maps/sim_truth.h"
#include "review/agronomy.h"
#include "review/run_model.h"
#include "telemetry/log.h"
#include "telemetry/subscriber.h"

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

// Whole-run and per-row figures of an agronomic summary.
maps::ArchiveFigures FiguresOf(const review::AgronomySummary& a) {
  maps::ArchiveFigures f;
  f.crop = a.crop;
  f.plants_per_m = a.plants_per_m;
  f.gaps = a.gaps;
  f.missing = a.missing;
  f.median_radius_m = a.crop_size.median_m;
  f.weeds = a.weeds;
  f.weeds_per_m2 = a.weeds_per_m2;
  for (const review::RowAgronomy& r : a.rows) {
    f.rows.push_back({r.row, r.crop, a.y0_m, a.y1_m, r.row * a.row_spacing_m, r.plants_per_m, r.gaps, r.missing,
                      r.crop_size.median_m, r.weeds, r.weeds_per_m2});
  }
  return f;
}

// The first file of the input that identifies it (a simulator folder: its truth).
fs::path IdentifyingFile(const fs::path& input) {
  if (fs::is_directory(input)) return input / "truth" / "plants.csv";
  return input;
}

}  // namespace

std::string RunIdOf(const fs::path& input) {
  std::ifstream in(IdentifyingFile(input), std::ios::binary);
  std::string head(64 * 1024, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  EVP_Digest(head.data(), head.size(), digest, &n, EVP_sha256(), nullptr);
  static const char hex[] = "0123456789abcdef";
  std::string id;
  for (unsigned int i = 0; i < 8 && i < n; ++i) id += hex[digest[i] >> 4], id += hex[digest[i] & 15];
  return id;
}

std::string IsoUtc(int64_t utime) {
  const std::time_t t = static_cast<std::time_t>(utime / 1000000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

maps::ArchiveRun ArchiveRunFromLog(const fs::path& log) {
  telemetry::LogReader reader(log);
  telemetry::Subscriber subscriber;
  review::RunModel model;
  model.Follow(subscriber);
  while (const std::optional<telemetry::LogEvent> e = reader.Next()) {
    model.Feed(subscriber, e->channel, e->data.data(), e->data.size(), e->utime);
  }
  maps::ArchiveRun run;
  run.run_id = RunIdOf(log);
  run.source = log.filename().string();
  for (const plantscale_event_t& e : model.events()) {
    if (e.kind != "run_config") continue;
    const SimRunConfig c = ParseRunConfig(e.text, log.string());
    run.vehicle = fs::path(c.vehicle).stem().string();
    run.crop_profile = fs::path(c.crop).stem().string();
    break;
  }
  if (model.messages() > 0) {
    run.start_time = IsoUtc(model.first_message_utime());
    run.end_time = IsoUtc(model.last_message_utime());
  }
  const review::RunSummary summary = model.Summary();
  run.distance_m = summary.distance_m;
  run.figures = FiguresOf(review::Agronomy(model, summary));
  return run;
}

maps::ArchiveRun ArchiveRunFromMap(const fs::path& input, const maps::CropMap& map) {
  maps::ArchiveRun run;
  run.run_id = RunIdOf(input);
  run.source = input.filename().string();
  std::map<int64_t, review::PlantRecord> plants;
  for (const maps::MapPlant& p : map.plants()) {
    review::PlantRecord& r = plants[p.id];
    r.plant.id = p.id;
    r.plant.position_m = p.position_m;
    r.plant.kind = p.kind == maps::PlantKind::kCrop   ? telemetry::PlantKind::kCrop
                   : p.kind == maps::PlantKind::kWeed ? telemetry::PlantKind::kWeed
                                                      : telemetry::PlantKind::kUnknown;
    r.plant.size_m2 = std::numbers::pi * p.radius_m * p.radius_m;
    r.plant.sprayed = p.treated;
  }
  review::AgronomySummary a;
  review::AddPlantFigures(a, plants);
  run.figures = FiguresOf(a);
  return run;
}

}  // namespace plantscale::app
