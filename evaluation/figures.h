#pragma once
// `plantscale figures`: every figure the README and docs quote, from one
// manifest (docs/results/figures.yaml, docs/cli/figures.md). The manifest
// is read and checked against the evaluations' JSON shapes in
// figures_manifest.cc; the runs, figures.json and the documents in
// figures.cc.
//
// The manifest names runs (an evaluation command line of this program) and
// figures (a JSON key of a run's output, its unit and target), the tables
// built from them, and the documents whose marked places show them. Runs
// on the simulator are given the report seeds (5000–5019), which nothing
// else in the tree may name. Each run is this binary started again with
// `--json`, so a figure is exactly what the command prints for anyone who
// types it; runs go `jobs` at a time and their outputs are kept under a
// fingerprint of the binary, the arguments and config/ (an interrupted
// `figures` resumes). figures.json holds every figure with the commit,
// date and machine; the documents' tables and inline figures are rewritten
// between their markers, and `Check` finds a document that disagrees.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace plantscale::app {

// The report seeds: every simulated figure is made on seeds
// kReportFirstSeed … kReportFirstSeed + kReportSeeds − 1 and nothing else
// names them (ctest seeds.report_range).
inline constexpr uint64_t kReportFirstSeed = 5000;
inline constexpr int kReportSeeds = 20;

struct FigureTarget {
  std::string op;         // "<=", ">=", "<", ">"
  double value = 0.0;     // in the figure's display unit
  bool absolute = false;  // the target bounds |value| ("|<=|")
};

struct ManifestRun {
  std::string name;
  std::vector<std::string> command;  // e.g. evaluate tracking --preset field ...
  bool seeded = true;                // --seed FIRST --seeds COUNT appended (the report seeds)
  int line = 0;
};

struct ManifestFigure {
  std::string name;
  std::string run;
  std::string key;   // a dotted path into the run's JSON ("baseline_thesis.lateral_rmse_m")
  std::string unit;  // "mm" (the key in metres), "%" (a fraction), "deg", "" (as is)
  int digits = 2;
  std::optional<FigureTarget> target;
  int line = 0;
};

struct ManifestTable {
  struct Row {
    std::string label;
    std::vector<std::string> cells;  // figure names, or text in quotes: "'—'"
  };
  std::string name;
  std::vector<std::string> header;
  std::vector<Row> rows;
  int line = 0;
};

struct Manifest {
  std::filesystem::path file;
  uint64_t first_seed = kReportFirstSeed;
  int seeds = kReportSeeds;
  std::vector<ManifestRun> runs;
  std::vector<ManifestFigure> figures;
  std::vector<ManifestTable> tables;
  std::vector<std::string> documents;  // relative to the repository

  const ManifestRun* Run(const std::string& name) const;
  const ManifestFigure* Figure(const std::string& name) const;
};

// Reads the manifest. Throws ConfigError naming the file, the entry and the
// reason (malformed YAML, a missing field, a figure of an unknown run, a
// unit or target that does not parse, a table cell naming no figure).
Manifest ReadManifest(const std::filesystem::path& file);

// What a command's JSON can hold: the command words ("evaluate tracking"),
// whether it takes --preset, --seed and --seeds, and the JSON its writer
// prints for an empty result with every optional part present.
struct EvaluationShape {
  std::string command;
  bool simulated = true;
  std::function<nlohmann::json()> shape;
};
const std::vector<EvaluationShape>& EvaluationShapes();

// Refuses, before anything runs, a run whose command is not an evaluation
// figures knows, whose --preset is not in `config_dir`/presets, that names
// --seed or --seeds itself, or a figure whose key the command never prints.
// Throws ConfigError naming the manifest and the entry.
void ValidateManifest(const Manifest& manifest, const std::filesystem::path& config_dir);

// The argument list of a run (without the program): its command, the report
// seeds when seeded, --json.
std::vector<std::string> RunArguments(const Manifest& manifest, const ManifestRun& run);
// The same as one line, "plantscale evaluate ... --json" (figures.json's).
std::string RunCommandLine(const Manifest& manifest, const ManifestRun& run);

// The value at a dotted path of object keys ("baseline_thesis.lateral_rmse_m"),
// or null when there is none.
const nlohmann::json* JsonAtPath(const nlohmann::json& j, const std::string& path);

struct RunOutcome {
  bool ok = false;
  bool cached = false;
  nlohmann::json output;  // the command's JSON when ok
  std::string error;      // why not (its exit code and last line of standard error)
  double seconds = 0.0;
};

struct FiguresRequest {
  std::filesystem::path program;  // this binary
  std::filesystem::path config_dir;
  std::filesystem::path repository;  // runs start here (relative paths in commands)
  std::filesystem::path work_dir;    // the runs' outputs and logs, kept for resuming
  std::vector<std::string> only;     // figure names (empty: all); their runs run
  int jobs = 1;
  bool progress = true;
};

// The runs the figures in `only` need (all when empty). Throws ConfigError
// naming an unknown figure.
std::vector<const ManifestRun*> SelectRuns(const Manifest& manifest,
                                           const std::vector<std::string>& only);

// Runs `runs`, `jobs` at a time; an output kept from an earlier call with
// the same fingerprint is read instead of running again. Never throws for
// a failing run: it is an outcome.
std::map<std::string, RunOutcome> RunFigures(const Manifest& manifest,
                                             const std::vector<const ManifestRun*>& runs,
                                             const FiguresRequest& request, std::ostream& log);

// figures.json: `previous` (an earlier figures.json, or null) with the
// figures of `outcomes` replaced; the commit, date and machine given.
struct Provenance {
  std::string commit, date;
  nlohmann::json machine;
};
nlohmann::json FiguresJson(const Manifest& manifest,
                           const std::map<std::string, RunOutcome>& outcomes,
                           const nlohmann::json& previous, const Provenance& provenance);
Provenance CurrentProvenance(const std::filesystem::path& repository);

// A figure's text as the documents show it ("4.06 mm", "99.9 %", "failed",
// "not run"), and a target's ("≤ 5 mm").
std::string FigureText(const nlohmann::json& figures_json, const ManifestFigure& figure);
std::string TargetText(const ManifestFigure& figure);

// `text` (a document) with every marked table and inline figure rendered
// from figures.json:
//   <!-- figures-table: NAME --> ... <!-- /figures-table -->
//   <!-- figure: NAME -->TEXT<!-- /figure -->
// Throws ConfigError naming `where` and the marker for an unknown name or an
// unclosed marker.
std::string RenderDocument(const std::string& text, const std::string& where,
                           const Manifest& manifest, const nlohmann::json& figures_json);

// Problems of the documents against figures.json, one sentence each
// (empty: they agree): a table or inline figure that differs from its
// rendering, a marker naming no figure, or, between
// `<!-- figures: quoted -->` and `<!-- /figures: quoted -->`, a number with
// a unit outside every marker (a figure quoted with no manifest entry;
// the literature's figures are marked `<!-- cited -->…<!-- /cited -->`).
std::vector<std::string> CheckDocuments(const std::filesystem::path& repository,
                                        const Manifest& manifest,
                                        const nlohmann::json& figures_json);

}  // namespace plantscale::app
