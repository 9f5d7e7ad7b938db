#include "app/figures_commands.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>

#include "app/config/config_loader.h"
#include "evaluation/figures.h"
#include "maps/staged_output.h"

#ifndef PLANTSCALE_SOURCE_DIR
#define PLANTSCALE_SOURCE_DIR "."
#endif

namespace plantscale::app {
namespace fs = std::filesystem;
namespace {

struct FiguresArgs {
  std::string manifest = std::string(PLANTSCALE_SOURCE_DIR) + "/docs/results/figures.yaml";
  std::vector<std::string> only;
  int jobs = 0;
  std::string work;
  bool check = false, render = false, list = false, quiet = false;
};

// The repository the manifest's documents are relative to: two folders up
// from docs/results/figures.yaml.
fs::path RepositoryOf(const fs::path& manifest) {
  return fs::absolute(manifest).parent_path().parent_path().parent_path();
}

fs::path FiguresJsonPath(const fs::path& manifest) {
  return fs::path(manifest).replace_extension(".json");
}

nlohmann::json ReadJsonOrNull(const fs::path& p) {
  std::ifstream in(p);
  if (!in) return nullptr;
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw DataError(p.string() + ": not JSON (" + e.what() + ")");
  }
}

void WriteText(const fs::path& p, const std::string& text) {
  maps::WriteStaged(p, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    if (!out.flush()) throw std::runtime_error("cannot write " + p.string());
  });
}

// Rewrites every document's marked places from figures.json.
void RenderDocuments(const fs::path& repository, const Manifest& m, const nlohmann::json& fj) {
  for (const std::string& doc : m.documents) {
    const fs::path path = repository / doc;
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path.string());
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string rendered = RenderDocument(text, doc, m, fj);
    if (rendered != text) WriteText(path, rendered);
  }
}

int Check(const fs::path& repository, const Manifest& m, const fs::path& json_path) {
  const nlohmann::json fj = ReadJsonOrNull(json_path);
  if (fj.is_null()) {
    std::cerr << "plantscale figures: " << json_path.string() << " does not exist: run figures\n";
    return 1;
  }
  const std::vector<std::string> problems = CheckDocuments(repository, m, fj);
  for (const std::string& p : problems) std::cerr << "plantscale figures: " << p << '\n';
  if (problems.empty()) {
    std::cout << "plantscale figures: " << m.documents.size() << " document(s) agree with "
              << json_path.string() << '\n';
  }
  return problems.empty() ? 0 : 1;
}

int FiguresCommand(const FiguresArgs& a, const GlobalOptions& global) {
  const fs::path manifest_path = a.manifest;
  const Manifest m = ReadManifest(manifest_path);
  const fs::path config_dir = global.ConfigDir();
  ValidateManifest(m, config_dir);
  const std::vector<const ManifestRun*> runs = SelectRuns(m, a.only);  // --only's names, checked
  const fs::path repository = RepositoryOf(manifest_path);
  const fs::path json_path = FiguresJsonPath(manifest_path);
  if (a.list) {
    for (const ManifestRun& run : m.runs) {
      std::cout << run.name << ": " << RunCommandLine(m, run) << '\n';
      for (const ManifestFigure& f : m.figures) {
        if (f.run == run.name) std::cout << "  " << f.name << " = " << f.key << '\n';
      }
    }
    return 0;
  }
  if (a.check) return Check(repository, m, json_path);
  const nlohmann::json previous = ReadJsonOrNull(json_path);
  if (a.render) {
    if (previous.is_null()) {
      std::cerr << "plantscale figures: " << json_path.string() << " does not exist: run figures\n";
      return 1;
    }
    RenderDocuments(repository, m, previous);
    return 0;
  }
  FiguresRequest r;
  r.program = fs::read_symlink("/proc/self/exe");
  r.config_dir = fs::absolute(config_dir);
  r.repository = repository;
  r.work_dir = fs::absolute(a.work.empty() ? fs::path(r.program).parent_path() / "figures"
                                           : fs::path(a.work));
  r.only = a.only;
  const long cpus = ::sysconf(_SC_NPROCESSORS_ONLN);
  r.jobs = a.jobs > 0 ? a.jobs : static_cast<int>(cpus > 0 ? cpus : 1);
  r.progress = !a.quiet;
  std::cerr << "plantscale figures: " << runs.size() << " run(s) on seeds " << m.first_seed << "–"
            << m.first_seed + static_cast<uint64_t>(m.seeds) - 1 << ", " << r.jobs
            << " at a time; outputs kept in " << r.work_dir.string() << '\n';
  // The commit the runs are made from: read before they start, so that
  // editing the tree while they run does not change what is recorded.
  const Provenance provenance = CurrentProvenance(repository);
  const std::map<std::string, RunOutcome> outcomes = RunFigures(m, runs, r, std::cerr);
  const nlohmann::json fj = FiguresJson(m, outcomes, previous, provenance);
  WriteText(json_path, fj.dump(2) + "\n");
  RenderDocuments(repository, m, fj);
  int failed = 0, missed = 0;
  for (const auto& [name, o] : outcomes) failed += o.ok ? 0 : 1;
  for (const auto& [name, f] : fj["figures"].items()) {
    if (f.value("met", true) == false) ++missed;
  }
  std::cout << "plantscale figures: wrote " << json_path.string() << " (" << fj["figures"].size()
            << " figures, " << missed << " missing their target) and rewrote " << m.documents.size()
            << " document(s)";
  if (failed > 0) std::cout << "; " << failed << " run(s) FAILED, shown as failed";
  std::cout << '\n';
  return failed > 0 ? 1 : 0;
}

}  // namespace

void AddFiguresCommands(CommandRegistry& registry) {
  const GlobalOptions& global = registry.global();
  FiguresArgs& args = registry.Keep(FiguresArgs{});
  CLI::App* cmd = registry.Add(
      "figures",
      "run every figure of docs/results/figures.yaml on the report seeds, write figures.json and "
      "rewrite the documents' figure tables",
      [&args, &global] { return FiguresCommand(args, global); });
  cmd->add_option("--manifest", args.manifest, "the figures manifest")->capture_default_str();
  cmd->add_option("--only", args.only,
                  "run only these figures (names in the manifest); the others "
                  "keep their values in figures.json");
  cmd->add_option("--jobs", args.jobs,
                  "runs at a time (default: the number of CPUs; each run is one process)")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--work", args.work,
                  "where each run's output is kept, under a fingerprint of the binary, its "
                  "arguments and config/ (default: figures/ beside the binary); an interrupted "
                  "figures resumes from it");
  cmd->add_flag("--check", args.check,
                "run nothing: say where the documents disagree with figures.json, or quote a "
                "figure the manifest does not have (exit 1)");
  cmd->add_flag("--render", args.render, "run nothing: rewrite the documents from figures.json");
  cmd->add_flag("--list", args.list, "run nothing: print each run's command and its figures");
  cmd->add_flag("--quiet", args.quiet, "no progress bar");
}

}  // namespace plantscale::app
