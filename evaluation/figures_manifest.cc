#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <set>
#include <sstream>

#include "app/config/config_loader.h"
#include "evaluation/class_eval.h"
#include "evaluation/figures.h"
#include "evaluation/rows_writer.h"
#include "evaluation/tracking_writer.h"
#include "evaluation/treatment_writer.h"

namespace plantscale::app {
namespace fs = std::filesystem;

namespace {

std::string Where(const Manifest& m, int line) {
  return m.file.string() + (line > 0 ? ":" + std::to_string(line) : "");
}

int LineOf(const YAML::Node& n) { return n.Mark().line >= 0 ? n.Mark().line + 1 : 0; }

std::vector<std::string> Words(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string w;
  while (in >> w) out.push_back(w);
  return out;
}

std::string Join(const std::vector<std::string>& words, const std::string& sep = " ") {
  std::string out;
  for (size_t i = 0; i < words.size(); ++i) out += (i ? sep : "") + words[i];
  return out;
}

std::string Scalar(const YAML::Node& node, const std::string& key, const Manifest& m,
                   const std::string& entry) {
  const YAML::Node v = node[key];
  if (!v || !v.IsScalar()) {
    throw ConfigError(Where(m, LineOf(node)), entry, "needs `" + key + ":` (a value)");
  }
  return v.as<std::string>();
}

FigureTarget ParseTarget(const std::string& text, const std::string& where,
                         const std::string& entry) {
  static const std::regex form(R"(^\s*(\|?)\s*(<=|>=|<|>)\s*([-+]?[0-9]*\.?[0-9]+)\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, form)) {
    throw ConfigError(where, entry,
                      "target '" + text +
                          "' is not '<= N', '>= N', '< N', '> N' or '|<= N' "
                          "(N in the figure's unit)");
  }
  FigureTarget t;
  t.absolute = !m[1].str().empty();
  t.op = m[2].str();
  t.value = std::stod(m[3].str());
  return t;
}

const std::set<std::string>& Units() {
  static const std::set<std::string> units{"mm", "%", "deg", ""};
  return units;
}

void ReadRuns(const YAML::Node& root, Manifest& m) {
  const YAML::Node runs = root["runs"];
  if (!runs || !runs.IsSequence()) {
    throw ConfigError(m.file.string(), "runs", "needs a list of runs (name, command)");
  }
  for (const YAML::Node& r : runs) {
    ManifestRun run;
    run.line = LineOf(r);
    run.name = Scalar(r, "name", m, "runs");
    const YAML::Node c = r["command"];
    if (c && c.IsSequence()) {
      for (const YAML::Node& w : c) run.command.push_back(w.as<std::string>());
    } else {
      run.command = Words(Scalar(r, "command", m, "run " + run.name));
    }
    if (r["seeded"]) run.seeded = r["seeded"].as<bool>();
    if (m.Run(run.name)) {
      throw ConfigError(Where(m, run.line), "run " + run.name, "is named twice");
    }
    m.runs.push_back(run);
  }
}

void ReadFigures(const YAML::Node& root, Manifest& m) {
  const YAML::Node figures = root["figures"];
  if (!figures || !figures.IsSequence()) {
    throw ConfigError(m.file.string(), "figures", "needs a list of figures (name, run, key)");
  }
  for (const YAML::Node& f : figures) {
    ManifestFigure fig;
    fig.line = LineOf(f);
    fig.name = Scalar(f, "name", m, "figures");
    const std::string entry = "figure " + fig.name;
    fig.run = Scalar(f, "run", m, entry);
    fig.key = Scalar(f, "key", m, entry);
    if (f["unit"]) fig.unit = f["unit"].as<std::string>();
    if (!Units().count(fig.unit)) {
      throw ConfigError(Where(m, fig.line), entry,
                        "unit '" + fig.unit + "' is not mm, %, deg or empty");
    }
    if (f["digits"]) fig.digits = f["digits"].as<int>();
    if (fig.digits < 0 || fig.digits > 6) {
      throw ConfigError(Where(m, fig.line), entry, "digits must be 0 to 6");
    }
    if (f["target"])
      fig.target = ParseTarget(f["target"].as<std::string>(), Where(m, fig.line), entry);
    if (!m.Run(fig.run)) {
      throw ConfigError(Where(m, fig.line), entry,
                        "names run '" + fig.run + "', which is not in runs");
    }
    if (m.Figure(fig.name)) throw ConfigError(Where(m, fig.line), entry, "is named twice");
    m.figures.push_back(fig);
  }
}

// A table cell: a figure's name, "target:NAME" (its target's text) or text
// in single quotes.
void CheckCell(const Manifest& m, const std::string& cell, int line, const std::string& table) {
  if (cell.size() >= 2 && cell.front() == '\'' && cell.back() == '\'') return;
  const std::string name = cell.rfind("target:", 0) == 0 ? cell.substr(7) : cell;
  const ManifestFigure* f = m.Figure(name);
  if (!f) {
    throw ConfigError(Where(m, line), "table " + table,
                      "cell '" + cell + "' names no figure (quote text as 'text')");
  }
  if (cell.rfind("target:", 0) == 0 && !f->target) {
    throw ConfigError(Where(m, line), "table " + table, "figure " + name + " has no target");
  }
}

void ReadTables(const YAML::Node& root, Manifest& m) {
  const YAML::Node tables = root["tables"];
  if (!tables) return;
  for (const YAML::Node& t : tables) {
    ManifestTable table;
    table.line = LineOf(t);
    table.name = Scalar(t, "name", m, "tables");
    for (const YAML::Node& h : t["header"]) table.header.push_back(h.as<std::string>());
    for (const YAML::Node& r : t["rows"]) {
      ManifestTable::Row row;
      if (!r.IsSequence() || r.size() != table.header.size()) {
        throw ConfigError(Where(m, LineOf(r)), "table " + table.name,
                          "a row needs as many cells as the header (" +
                              std::to_string(table.header.size()) + ")");
      }
      row.label = r[0].as<std::string>();
      for (size_t i = 1; i < r.size(); ++i) {
        row.cells.push_back(r[i].as<std::string>());
        CheckCell(m, row.cells.back(), LineOf(r), table.name);
      }
      table.rows.push_back(row);
    }
    m.tables.push_back(table);
  }
}

}  // namespace

const ManifestRun* Manifest::Run(const std::string& name) const {
  for (const ManifestRun& r : runs) {
    if (r.name == name) return &r;
  }
  return nullptr;
}

const ManifestFigure* Manifest::Figure(const std::string& name) const {
  for (const ManifestFigure& f : figures) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

Manifest ReadManifest(const fs::path& file) {
  Manifest m;
  m.file = file;
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    throw ConfigError(file.string(), "manifest", "cannot be read");
  } catch (const YAML::Exception& e) {
    throw ConfigError(file.string() + ":" + std::to_string(e.mark.line + 1), "manifest", e.msg);
  }
  try {
    if (const YAML::Node s = root["report_seeds"]) {
      m.first_seed = s["first"].as<uint64_t>();
      m.seeds = s["count"].as<int>();
    }
    if (m.seeds < 1) throw ConfigError(file.string(), "report_seeds", "count must be >= 1");
    for (const YAML::Node& d : root["documents"]) m.documents.push_back(d.as<std::string>());
    ReadRuns(root, m);
    ReadFigures(root, m);
    ReadTables(root, m);
  } catch (const YAML::Exception& e) {
    throw ConfigError(file.string() + ":" + std::to_string(e.mark.line + 1), "manifest", e.msg);
  }
  return m;
}

const std::vector<EvaluationShape>& EvaluationShapes() {
  static const std::vector<EvaluationShape> shapes{
      {"evaluate tracking", true, TrackingJsonShape},
      {"evaluate treatment", true, TreatmentJsonShape},
      {"evaluate classes", false, ClassEvaluationJsonShape},
      {"evaluate rows", false, PhotoRowsJsonShape},
  };
  return shapes;
}

namespace {

const EvaluationShape* ShapeOf(const ManifestRun& run) {
  const std::string words = Join(run.command);
  for (const EvaluationShape& s : EvaluationShapes()) {
    if (words == s.command || words.rfind(s.command + " ", 0) == 0) return &s;
  }
  return nullptr;
}

std::optional<std::string> OptionValue(const std::vector<std::string>& command,
                                       const std::string& option) {
  for (size_t i = 0; i + 1 < command.size(); ++i) {
    if (command[i] == option) return command[i + 1];
    if (command[i].rfind(option + "=", 0) == 0) return command[i].substr(option.size() + 1);
  }
  if (!command.empty() && command.back().rfind(option + "=", 0) == 0) {
    return command.back().substr(option.size() + 1);
  }
  return std::nullopt;
}

bool Names(const std::vector<std::string>& command, const std::string& option) {
  return std::any_of(command.begin(), command.end(), [&](const std::string& w) {
    return w == option || w.rfind(option + "=", 0) == 0;
  });
}

}  // namespace

const nlohmann::json* JsonAtPath(const nlohmann::json& j, const std::string& path) {
  const nlohmann::json* at = &j;
  std::istringstream in(path);
  std::string part;
  while (std::getline(in, part, '.')) {
    if (!at->is_object() || !at->contains(part)) return nullptr;
    at = &(*at)[part];
  }
  return at;
}

namespace {

void ValidateRun(const Manifest& m, const ManifestRun& run, const fs::path& config_dir) {
  const std::string entry = "run " + run.name;
  const EvaluationShape* shape = ShapeOf(run);
  if (!shape) {
    std::string known;
    for (const EvaluationShape& s : EvaluationShapes())
      known += (known.empty() ? "" : ", ") + s.command;
    throw ConfigError(
        Where(m, run.line), entry,
        "command '" + Join(run.command) + "' is not an evaluation figures runs (" + known + ")");
  }
  if (Names(run.command, "--json")) {
    throw ConfigError(Where(m, run.line), entry, "--json is added by figures; leave it out");
  }
  if (!shape->simulated) {
    if (run.seeded) {
      throw ConfigError(Where(m, run.line), entry,
                        shape->command + " takes no seeds: say `seeded: false`");
    }
    return;
  }
  if (!run.seeded) {
    throw ConfigError(Where(m, run.line), entry,
                      "a simulated run is on the report seeds (leave out `seeded: false`)");
  }
  if (Names(run.command, "--seed") || Names(run.command, "--seeds")) {
    throw ConfigError(Where(m, run.line), entry,
                      "names --seed or --seeds: figures gives every run the report seeds");
  }
  const std::optional<std::string> preset = OptionValue(run.command, "--preset");
  if (!preset) throw ConfigError(Where(m, run.line), entry, "needs --preset");
  const bool file =
      preset->find('/') != std::string::npos || fs::path(*preset).extension() == ".yaml";
  if (!file && !fs::exists(config_dir / "presets" / (*preset + ".yaml"))) {
    throw ConfigError(Where(m, run.line), entry,
                      "unknown preset '" + *preset + "' (presets: " +
                          Join(ListConfigNames(config_dir / "presets"), ", ") + ")");
  }
}

}  // namespace

void ValidateManifest(const Manifest& m, const fs::path& config_dir) {
  for (const ManifestRun& run : m.runs) ValidateRun(m, run, config_dir);
  for (const ManifestFigure& f : m.figures) {
    const EvaluationShape* shape = ShapeOf(*m.Run(f.run));
    const nlohmann::json j = shape->shape();
    const nlohmann::json* v = JsonAtPath(j, f.key);
    if (!v) {
      throw ConfigError(Where(m, f.line), "figure " + f.name,
                        "key '" + f.key + "' is not in what " + shape->command + " --json prints");
    }
    if (!v->is_number() && !v->is_null()) {
      throw ConfigError(Where(m, f.line), "figure " + f.name,
                        "key '" + f.key + "' is not a number in " + shape->command + " --json");
    }
  }
}

std::vector<std::string> RunArguments(const Manifest& m, const ManifestRun& run) {
  std::vector<std::string> args = run.command;
  if (run.seeded) {
    args.insert(args.end(),
                {"--seed", std::to_string(m.first_seed), "--seeds", std::to_string(m.seeds)});
  }
  args.push_back("--json");
  return args;
}

std::vector<const ManifestRun*> SelectRuns(const Manifest& m,
                                           const std::vector<std::string>& only) {
  std::vector<const ManifestRun*> runs;
  if (only.empty()) {
    for (const ManifestRun& r : m.runs) runs.push_back(&r);
    return runs;
  }
  std::set<std::string> wanted;
  for (const std::string& name : only) {
    const ManifestFigure* f = m.Figure(name);
    if (!f) throw ConfigError(m.file.string(), "--only " + name, "names no figure in the manifest");
    wanted.insert(f->run);
  }
  for (const ManifestRun& r : m.runs) {
    if (wanted.count(r.name)) runs.push_back(&r);
  }
  return runs;
}

std::string RunCommandLine(const Manifest& m, const ManifestRun& run) {
  return "plantscale " + Join(RunArguments(m, run));
}

}  // namespace plantscale::app
