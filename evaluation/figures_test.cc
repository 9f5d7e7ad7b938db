// plantscale figures (issue 59): the manifest, its refusals, the runner,
// figures.json and the documents' markers; and the repository's own
// documents against its figures.json.
#include "evaluation/figures.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <string>

#include "app/config/config_loader.h"

#ifndef PLANTSCALE_SOURCE_DIR
#define PLANTSCALE_SOURCE_DIR "."
#endif

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;

fs::path Source() { return PLANTSCALE_SOURCE_DIR; }

class Figures : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("figures_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "docs" / "results");
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path Write(const fs::path& relative, const std::string& text) {
    const fs::path p = dir_ / relative;
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p;
  }

  // A manifest of two runs: a tracking run on `field` and a classes run.
  fs::path Manifest(const std::string& runs_extra = "", const std::string& figures_extra = "") {
    return Write(
        "docs/results/figures.yaml",
        "report_seeds: {first: 700, count: 3}\n"
        "documents: [README.md]\n"
        "runs:\n"
        "  - name: track\n"
        "    command: evaluate tracking --preset field --baseline thesis\n" +
            runs_extra +
            "figures:\n"
            "  - {name: lateral, run: track, key: lateral_rmse_m, unit: mm, digits: 2, "
            "target: \"<= 5\"}\n"
            "  - {name: thesis, run: track, key: baseline_thesis.lateral_rmse_m, unit: mm, "
            "digits: 1}\n"
            "  - {name: nees, run: track, key: nees_in_bounds_fraction, digits: 2, target: "
            "\">= 0.85\"}\n" +
            figures_extra +
            "tables:\n"
            "  - name: t\n"
            "    header: ['', target, ours]\n"
            "    rows:\n"
            "      - [lateral RMSE, target:lateral, lateral]\n"
            "      - [NEES, target:nees, nees]\n");
  }

  std::string ErrorOf(const fs::path& manifest) {
    try {
      ValidateManifest(ReadManifest(manifest), DefaultConfigDir());
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
};

RunOutcome Ok(double lateral_m, double nees, double thesis_m) {
  RunOutcome o;
  o.ok = true;
  o.output = {{"lateral_rmse_m", lateral_m},
              {"nees_in_bounds_fraction", nees},
              {"baseline_thesis", {{"lateral_rmse_m", thesis_m}}},
              {"per_seed", {{{"seed", 700}}}}};
  return o;
}

TEST_F(Figures, TheRepositorysManifestIsValidAndOnTheReportSeeds) {
  const struct Manifest m = ReadManifest(Source() / "docs/results/figures.yaml");
  ValidateManifest(m, Source() / "config");
  EXPECT_EQ(m.first_seed, kReportFirstSeed);
  EXPECT_EQ(m.seeds, kReportSeeds);
  ASSERT_FALSE(m.runs.empty());
  for (const ManifestRun& run : m.runs) {
    const std::vector<std::string> args = RunArguments(m, run);
    EXPECT_EQ(args.back(), "--json");
    if (run.seeded) {
      const auto at = std::find(args.begin(), args.end(), "--seed");
      ASSERT_NE(at, args.end()) << run.name;
      EXPECT_EQ(*(at + 1), std::to_string(kReportFirstSeed)) << run.name;
    }
  }
}

TEST_F(Figures, RefusesABadEntryBeforeRunningNamingIt) {
  EXPECT_EQ(ErrorOf(Manifest()), "");
  const std::string unknown_command =
      ErrorOf(Manifest("  - name: bad\n    command: evaluate weather --preset field\n"));
  EXPECT_NE(unknown_command.find("run bad: command 'evaluate weather --preset field' is not an "
                                 "evaluation"),
            std::string::npos)
      << unknown_command;
  const std::string unknown_preset =
      ErrorOf(Manifest("  - name: bad\n    command: evaluate tracking --preset moon\n"));
  EXPECT_NE(unknown_preset.find("run bad: unknown preset 'moon'"), std::string::npos)
      << unknown_preset;
  const std::string own_seed =
      ErrorOf(Manifest("  - name: bad\n    command: evaluate tracking --preset field --seed 3\n"));
  EXPECT_NE(own_seed.find("run bad: names --seed or --seeds"), std::string::npos) << own_seed;
  const std::string unknown_key =
      ErrorOf(Manifest("", "  - {name: bad, run: track, key: lateral_rmse_mm, unit: mm}\n"));
  EXPECT_NE(unknown_key.find("figure bad: key 'lateral_rmse_mm' is not in what evaluate tracking "
                             "--json prints"),
            std::string::npos)
      << unknown_key;
  const std::string unknown_run =
      ErrorOf(Manifest("", "  - {name: bad, run: nowhere, key: losses}\n"));
  EXPECT_NE(unknown_run.find("figure bad: names run 'nowhere'"), std::string::npos) << unknown_run;
  const std::string bad_target =
      ErrorOf(Manifest("", "  - {name: bad, run: track, key: losses, target: about 3}\n"));
  EXPECT_NE(bad_target.find("target 'about 3'"), std::string::npos) << bad_target;
  // The line of the entry is named.
  EXPECT_NE(unknown_key.find("figures.yaml:"), std::string::npos) << unknown_key;
}

TEST_F(Figures, FiguresJsonSaysMetMissedAndFailedNeverTheOldValue) {
  const struct Manifest m = ReadManifest(Manifest());
  Provenance p{"abc", "2026-12-07T00:00:00Z", {{"cpus", 2}}};
  std::map<std::string, RunOutcome> outcomes{{"track", Ok(0.00612, 0.9, 0.0151)}};
  const nlohmann::json first = FiguresJson(m, outcomes, nullptr, p);
  EXPECT_EQ(first["figures"]["lateral"]["status"], "ok");
  EXPECT_NEAR(first["figures"]["lateral"]["value"].get<double>(), 6.12, 1e-9);
  EXPECT_FALSE(first["figures"]["lateral"]["met"].get<bool>());
  EXPECT_NEAR(first["figures"]["lateral"]["missed_by"].get<double>(), 1.12, 1e-9);
  EXPECT_TRUE(first["figures"]["nees"]["met"].get<bool>());
  EXPECT_EQ(first["runs"]["track"]["command"],
            "plantscale evaluate tracking --preset field --baseline thesis --seed 700 --seeds 3 "
            "--json");
  EXPECT_EQ(first["runs"]["track"]["per_seed"].size(), 1U);
  EXPECT_EQ(FigureText(first, *m.Figure("lateral")), "6.12 mm");
  EXPECT_EQ(FigureText(first, *m.Figure("thesis")), "15.1 mm");
  // The same outcomes: the same bytes.
  EXPECT_EQ(FiguresJson(m, outcomes, nullptr, p).dump(), first.dump());
  // A run that fails shows as failed, not as the value before.
  RunOutcome failed;
  failed.error = "exit 1: boom";
  const nlohmann::json second = FiguresJson(m, {{"track", failed}}, first, p);
  EXPECT_EQ(second["figures"]["lateral"]["status"], "failed");
  EXPECT_EQ(FigureText(second, *m.Figure("lateral")), "failed");
  EXPECT_EQ(second["runs"]["track"]["error"], "exit 1: boom");
  // A run not asked for this time keeps what it had.
  const nlohmann::json third = FiguresJson(m, {}, first, p);
  EXPECT_EQ(third["figures"]["lateral"], first["figures"]["lateral"]);
}

TEST_F(Figures, DocumentsAreRenderedBetweenTheirMarkersAndChecked) {
  const struct Manifest m = ReadManifest(Manifest());
  const Provenance p{"abc", "d", nullptr};
  const nlohmann::json fj = FiguresJson(m, {{"track", Ok(0.0040, 0.9, 0.0151)}}, nullptr, p);
  const std::string doc =
      "# x\n<!-- figures: quoted -->\n"
      "Ours <!-- figure: lateral -->old<!-- /figure -->, the thesis's "
      "<!-- figure: thesis --><!-- /figure --> (the thesis: <!-- cited -->15.3 mm<!-- /cited -->; "
      "[link](results/5%20mm.md)).\n"
      "<!-- figures-table: t -->\nold table\n<!-- /figures-table -->\n"
      "<!-- /figures: quoted -->\nOutside: 42 mm.\n";
  const std::string rendered = RenderDocument(doc, "README.md", m, fj);
  EXPECT_NE(rendered.find("Ours <!-- figure: lateral -->4.00 mm<!-- /figure -->"),
            std::string::npos)
      << rendered;
  EXPECT_NE(rendered.find("<!-- figure: thesis -->15.1 mm<!-- /figure -->"), std::string::npos);
  EXPECT_NE(rendered.find("| lateral RMSE | ≤ 5 mm | 4.00 mm |\n| NEES | ≥ 0.85 | 0.90 |\n"),
            std::string::npos)
      << rendered;
  // Rendering twice changes nothing.
  EXPECT_EQ(RenderDocument(rendered, "README.md", m, fj), rendered);
  Write("README.md", rendered);
  EXPECT_TRUE(CheckDocuments(dir_, m, fj).empty());
  // A value edited by hand, and a figure quoted with no marker.
  std::string edited = rendered;
  edited.replace(edited.find("4.00 mm<!-- /figure -->"), 7, "3.59 mm");
  edited.insert(edited.find("<!-- /figures: quoted -->"), "Also 7.3 % of the bed.\n");
  Write("README.md", edited);
  const std::vector<std::string> problems = CheckDocuments(dir_, m, fj);
  ASSERT_EQ(problems.size(), 2U);
  EXPECT_NE(problems[0].find("README.md:3: figure lateral says '3.59 mm', figures.json '4.00 mm'"),
            std::string::npos)
      << problems[0];
  EXPECT_NE(problems[1].find("'7.3 %' is quoted outside every figure marker"), std::string::npos)
      << problems[1];
  // A marker naming nothing in the manifest.
  EXPECT_THROW(RenderDocument("<!-- figure: nowhere -->x<!-- /figure -->", "README.md", m, fj),
               ConfigError);
  EXPECT_THROW(RenderDocument("<!-- figure: lateral -->x", "README.md", m, fj), ConfigError);
}

// The runner with a stand-in program: runs in parallel, a failing run is an
// outcome naming its exit and last line, and a second call resumes from
// the kept outputs.
TEST_F(Figures, RunsInParallelKeepsOutputsAndReportsFailures) {
  const fs::path program =
      Write("fake.sh",
            "#!/bin/sh\n"
            "echo \"$@\" >> \"$(dirname \"$0\")/calls.txt\"\n"
            "case \"$*\" in *moon*) echo 'no such preset' >&2; exit 2;; esac\n"
            "echo '{\"lateral_rmse_m\": 0.004, \"nees_in_bounds_fraction\": 0.9,"
            " \"baseline_thesis\": {\"lateral_rmse_m\": 0.02}}'\n");
  ::chmod(program.c_str(), 0755);
  const struct Manifest m =
      ReadManifest(Manifest("  - name: other\n    command: evaluate tracking --preset moon\n"));
  FiguresRequest r;
  r.program = program;
  r.config_dir = Source() / "config";
  r.work_dir = dir_ / "work";
  r.jobs = 2;
  r.progress = false;
  std::ostringstream log;
  std::map<std::string, RunOutcome> out = RunFigures(m, SelectRuns(m, {}), r, log);
  ASSERT_EQ(out.size(), 2U);
  EXPECT_TRUE(out["track"].ok);
  EXPECT_FALSE(out["track"].cached);
  EXPECT_NEAR(out["track"].output["lateral_rmse_m"].get<double>(), 0.004, 1e-12);
  EXPECT_FALSE(out["other"].ok);
  EXPECT_NE(out["other"].error.find("exit 2: no such preset"), std::string::npos)
      << out["other"].error;
  // Resumed: the good run is read back, the failed one runs again.
  out = RunFigures(m, SelectRuns(m, {}), r, log);
  EXPECT_TRUE(out["track"].cached);
  EXPECT_FALSE(out["other"].ok);
  std::ifstream calls(dir_ / "calls.txt");
  int lines = 0;
  for (std::string line; std::getline(calls, line);) {
    ++lines;
    EXPECT_NE(line.find("--json"), std::string::npos);
  }
  EXPECT_EQ(lines, 3);
  // --only: the runs of the figures named.
  EXPECT_EQ(SelectRuns(m, {"nees"}).size(), 1U);
  EXPECT_THROW(SelectRuns(m, {"nowhere"}), ConfigError);
}

// The repository's README and docs/results/figures.md against its
// figures.json: every marked figure as figures.json has it, and no figure
// quoted in the marked regions without a manifest entry.
TEST_F(Figures, TheRepositorysDocumentsAgreeWithItsFiguresJson) {
  const struct Manifest m = ReadManifest(Source() / "docs/results/figures.yaml");
  std::ifstream in(Source() / "docs/results/figures.json");
  ASSERT_TRUE(in) << "docs/results/figures.json is missing: run plantscale figures";
  const nlohmann::json fj = nlohmann::json::parse(in);
  const std::vector<std::string> problems = CheckDocuments(Source(), m, fj);
  for (const std::string& p : problems) ADD_FAILURE() << p;
  // Every figure of the manifest is in figures.json.
  for (const ManifestFigure& f : m.figures) {
    EXPECT_TRUE(fj["figures"].contains(f.name)) << f.name;
  }
}

}  // namespace
}  // namespace plantscale::app
