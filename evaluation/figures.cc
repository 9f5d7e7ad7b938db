#include "evaluation/figures.h"

#include <fcntl.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <deque>
#include <fstream>
#include <iomanip>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "app/config/config_loader.h"
#include "app/config/progress.h"

namespace plantscale::app {
namespace fs = std::filesystem;

namespace {

// FNV-1a, 64 bits.
struct Fingerprint {
  uint64_t h = 1469598103934665603ULL;
  void Add(const char* data, size_t n) {
    for (size_t i = 0; i < n; ++i) {
      h ^= static_cast<unsigned char>(data[i]);
      h *= 1099511628211ULL;
    }
  }
  void Add(const std::string& s) { Add(s.data(), s.size() + 1); }
  void AddFile(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::vector<char> buffer(1 << 16);
    while (in) {
      in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      Add(buffer.data(), static_cast<size_t>(in.gcount()));
    }
  }
  std::string Hex() const {
    char out[17];
    std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(h));
    return out;
  }
};

// The binary and every file of the configuration: what a run's output
// depends on besides its arguments.
Fingerprint BaseFingerprint(const FiguresRequest& r) {
  Fingerprint f;
  f.AddFile(r.program);
  std::vector<fs::path> files;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(r.config_dir, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (it->is_regular_file()) files.push_back(it->path());
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& p : files) {
    f.Add(fs::relative(p, r.config_dir).string());
    f.AddFile(p);
  }
  return f;
}

std::string LastLine(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  }
  return last;
}

struct Job {
  const ManifestRun* run;
  std::vector<std::string> args;
  fs::path output, log;
  std::chrono::steady_clock::time_point start;
};

pid_t Start(const FiguresRequest& r, const Job& job) {
  std::vector<std::string> argv{r.program.string(), "--config-dir", r.config_dir.string()};
  argv.insert(argv.end(), job.args.begin(), job.args.end());
  const fs::path part = job.output.string() + ".part";
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  const int out = ::open(part.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const int err = ::open(job.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (out < 0 || err < 0) ::_exit(126);
  if (!r.repository.empty() && ::chdir(r.repository.c_str()) != 0) ::_exit(126);
  ::dup2(out, STDOUT_FILENO);
  ::dup2(err, STDERR_FILENO);
  std::vector<char*> c;
  for (std::string& a : argv) c.push_back(a.data());
  c.push_back(nullptr);
  ::execv(c[0], c.data());
  ::_exit(127);
}

RunOutcome Finish(const Job& job, int status) {
  RunOutcome o;
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - job.start).count();
  const fs::path part = job.output.string() + ".part";
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    try {
      std::ifstream in(part);
      o.output = nlohmann::json::parse(in);
      std::error_code ec;
      fs::rename(part, job.output, ec);
      o.ok = !ec;
      if (ec) o.error = "cannot keep " + job.output.string() + ": " + ec.message();
    } catch (const nlohmann::json::exception& e) {
      o.error = "its output is not JSON (" + std::string(e.what()) + ")";
    }
    return o;
  }
  o.error = WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                              : "killed by signal " + std::to_string(WTERMSIG(status));
  const std::string last = LastLine(job.log);
  if (!last.empty()) o.error += ": " + last;
  o.error += " (log: " + job.log.string() + ")";
  return o;
}

}  // namespace

std::map<std::string, RunOutcome> RunFigures(const Manifest& m,
                                             const std::vector<const ManifestRun*>& runs,
                                             const FiguresRequest& r, std::ostream& log) {
  std::map<std::string, RunOutcome> outcomes;
  fs::create_directories(r.work_dir);
  const Fingerprint base = BaseFingerprint(r);
  std::deque<Job> pending;
  for (const ManifestRun* run : runs) {
    Job job{run, RunArguments(m, *run), {}, {}, {}};
    Fingerprint f = base;
    for (const std::string& a : job.args) f.Add(a);
    job.output = r.work_dir / (run->name + "-" + f.Hex() + ".json");
    job.log = r.work_dir / (run->name + "-" + f.Hex() + ".log");
    std::ifstream kept(job.output);
    if (kept) {
      try {
        RunOutcome o;
        o.output = nlohmann::json::parse(kept);
        o.ok = o.cached = true;
        outcomes[run->name] = o;
        log << "figures: " << run->name << ": kept from an earlier run (" << job.output.string()
            << ")\n";
        continue;
      } catch (const nlohmann::json::exception&) {
        // Run it again.
      }
    }
    pending.push_back(job);
  }
  const int total = static_cast<int>(pending.size());
  ProgressBar bar(log, "figures", total, r.progress && total > 0);
  std::map<pid_t, Job> running;
  int done = 0;
  while (!pending.empty() || !running.empty()) {
    while (!pending.empty() && static_cast<int>(running.size()) < std::max(1, r.jobs)) {
      Job job = pending.front();
      pending.pop_front();
      job.start = std::chrono::steady_clock::now();
      const pid_t pid = Start(r, job);
      if (pid < 0) {
        outcomes[job.run->name] = RunOutcome{false, false, {}, "cannot start (fork failed)", 0.0};
        ++done;
        continue;
      }
      running.emplace(pid, job);
    }
    if (running.empty()) break;
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;
    }
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    RunOutcome o = Finish(it->second, status);
    log << (r.progress && ::isatty(STDERR_FILENO) ? "\n" : "")
        << "figures: " << it->second.run->name << ": " << (o.ok ? "done" : "FAILED, " + o.error)
        << " in " << std::fixed << std::setprecision(0) << o.seconds << " s\n";
    outcomes[it->second.run->name] = std::move(o);
    running.erase(it);
    bar.Update(++done);
  }
  bar.Finish();
  return outcomes;
}

namespace {

double DisplayValue(double v, const std::string& unit) {
  if (unit == "mm") return v * 1000.0;
  if (unit == "%") return v * 100.0;
  return v;
}

std::string UnitSuffix(const std::string& unit) {
  if (unit == "mm") return " mm";
  if (unit == "%") return " %";
  if (unit == "deg") return "°";
  return "";
}

std::string Fixed(double v, int digits) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  std::string s = o.str();
  if (s == "-0" || s.rfind("-0.", 0) == 0) {
    if (s.find_first_not_of("-0.") == std::string::npos) s = s.substr(1);
  }
  return s;
}

// Six significant digits: what figures.json keeps of a value (its text has
// fewer), so that the file does not change with the last bit of a sum.
double Significant(double v) {
  if (v == 0.0 || !std::isfinite(v)) return v;
  std::ostringstream o;
  o << std::setprecision(6) << v;
  return std::stod(o.str());
}

bool Meets(double v, const FigureTarget& t) {
  const double x = t.absolute ? std::abs(v) : v;
  if (t.op == "<=") return x <= t.value;
  if (t.op == ">=") return x >= t.value;
  if (t.op == "<") return x < t.value;
  return x > t.value;
}

std::string OpText(const FigureTarget& t) {
  std::string op = t.op == "<=" ? "≤" : t.op == ">=" ? "≥" : t.op;
  return t.absolute ? "|x| " + op : op;
}

nlohmann::json FigureEntry(const ManifestFigure& f, const RunOutcome& o) {
  nlohmann::json e{{"run", f.run}, {"key", f.key}, {"unit", f.unit}};
  if (f.target) e["target"] = TargetText(f);
  if (!o.ok) {
    e["status"] = "failed";
    return e;
  }
  const nlohmann::json* v = JsonAtPath(o.output, f.key);
  if (!v || !(v->is_number() || v->is_null())) {
    e["status"] = "failed";
    e["error"] = "the run's JSON has no number at '" + f.key + "'";
    return e;
  }
  if (v->is_null()) {
    e["status"] = "failed";
    e["error"] = "the run's JSON has null at '" + f.key + "' (nothing scored)";
    return e;
  }
  const double shown = Significant(DisplayValue(v->get<double>(), f.unit));
  e["status"] = "ok";
  e["value"] = shown;
  if (f.target) {
    const bool met = Meets(shown, *f.target);
    e["met"] = met;
    if (!met) {
      const double x = f.target->absolute ? std::abs(shown) : shown;
      e["missed_by"] = Significant(std::abs(x - f.target->value));
    }
  }
  return e;
}

}  // namespace

std::string TargetText(const ManifestFigure& f) {
  if (!f.target) return "";
  std::ostringstream o;
  o << std::setprecision(6) << f.target->value;
  return OpText(*f.target) + " " + o.str() + UnitSuffix(f.unit);
}

nlohmann::json FiguresJson(const Manifest& m, const std::map<std::string, RunOutcome>& outcomes,
                           const nlohmann::json& previous, const Provenance& p) {
  nlohmann::json j;
  j["manifest"] = m.file.filename().string();
  j["commit"] = p.commit;
  j["date"] = p.date;
  j["machine"] = p.machine;
  j["report_seeds"] = {{"first", m.first_seed}, {"count", m.seeds}};
  nlohmann::json runs = nlohmann::json::object();
  nlohmann::json figures = nlohmann::json::object();
  for (const ManifestRun& run : m.runs) {
    const auto it = outcomes.find(run.name);
    const std::string command = RunCommandLine(m, run);
    if (it == outcomes.end()) {
      // Not run this time: what an earlier figures run of the same command found.
      const nlohmann::json* before = previous.is_object() ? JsonAtPath(previous, "runs") : nullptr;
      if (before && before->contains(run.name) &&
          (*before)[run.name].value("command", "") == command) {
        runs[run.name] = (*before)[run.name];
        for (const ManifestFigure& f : m.figures) {
          if (f.run == run.name && previous["figures"].contains(f.name)) {
            figures[f.name] = previous["figures"][f.name];
          }
        }
      } else {
        runs[run.name] = {{"command", command}, {"status", "not run"}};
      }
      continue;
    }
    const RunOutcome& o = it->second;
    nlohmann::json r{
        {"command", command}, {"status", o.ok ? "ok" : "failed"}, {"commit", p.commit}};
    if (!o.ok) r["error"] = o.error;
    if (o.ok && o.output.contains("per_seed")) r["per_seed"] = o.output["per_seed"];
    if (o.ok && o.output.contains("baseline_thesis") &&
        o.output["baseline_thesis"].contains("per_seed")) {
      r["baseline_thesis_per_seed"] = o.output["baseline_thesis"]["per_seed"];
    }
    runs[run.name] = r;
    for (const ManifestFigure& f : m.figures) {
      if (f.run == run.name) figures[f.name] = FigureEntry(f, o);
    }
  }
  for (const ManifestFigure& f : m.figures) {
    if (!figures.contains(f.name)) {
      figures[f.name] = {{"run", f.run}, {"key", f.key}, {"unit", f.unit}, {"status", "not run"}};
    }
  }
  j["runs"] = runs;
  j["figures"] = figures;
  return j;
}

namespace {

std::string Capture(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return out;
  char buffer[512];
  while (std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
  ::pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

std::string Quoted(const fs::path& p) {
  std::string s = "'";
  for (char c : p.string()) s += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return s + "'";
}

std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
    }
  }
  return "unknown";
}

std::string OsName() {
  std::ifstream in("/etc/os-release");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("PRETTY_NAME=", 0) == 0) {
      std::string v = line.substr(12);
      if (v.size() >= 2 && v.front() == '"') v = v.substr(1, v.size() - 2);
      return v;
    }
  }
  return "unknown";
}

}  // namespace

Provenance CurrentProvenance(const fs::path& repository) {
  Provenance p;
  const std::string git = "git -C " + Quoted(repository) + " ";
  p.commit = Capture(git + "rev-parse HEAD 2>/dev/null");
  if (p.commit.empty()) {
    p.commit = "unknown";
  } else if (!Capture(git + "status --porcelain --untracked-files=no 2>/dev/null").empty()) {
    p.commit += "+changes";
  }
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  p.date = date;
  utsname u{};
  ::uname(&u);
  p.machine = {{"cpus", std::thread::hardware_concurrency()},
               {"cpu", CpuModel()},
               {"os", OsName()},
               {"kernel", std::string(u.sysname) + " " + u.release}};
  return p;
}

std::string FigureText(const nlohmann::json& fj, const ManifestFigure& f) {
  const nlohmann::json* e = JsonAtPath(fj, "figures");
  if (!e || !e->contains(f.name)) return "not run";
  const nlohmann::json& entry = (*e)[f.name];
  const std::string status = entry.value("status", "not run");
  if (status != "ok") return status;
  return Fixed(entry["value"].get<double>(), f.digits) + UnitSuffix(f.unit);
}

namespace {

std::string CellText(const nlohmann::json& fj, const Manifest& m, const std::string& cell) {
  if (cell.size() >= 2 && cell.front() == '\'' && cell.back() == '\'') {
    return cell.substr(1, cell.size() - 2);
  }
  if (cell.rfind("target:", 0) == 0) return TargetText(*m.Figure(cell.substr(7)));
  const ManifestFigure& f = *m.Figure(cell);
  std::string text = FigureText(fj, f);
  const nlohmann::json& entry = fj["figures"][f.name];
  if (entry.value("status", "") == "ok" && entry.contains("met") && !entry["met"].get<bool>()) {
    text += " (missed by " + Fixed(entry["missed_by"].get<double>(), f.digits) +
            UnitSuffix(f.unit) + ")";
  }
  return text;
}

// A table cell's text with its pipes escaped ("|x| ≤ 3 mm" would end the cell).
std::string Cell(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

std::string TableText(const nlohmann::json& fj, const Manifest& m, const ManifestTable& t) {
  std::string out = "|";
  for (const std::string& h : t.header) out += " " + Cell(h) + " |";
  out += "\n|";
  for (size_t i = 0; i < t.header.size(); ++i) out += "---|";
  out += "\n";
  for (const ManifestTable::Row& row : t.rows) {
    out += "| " + Cell(row.label);
    for (const std::string& c : row.cells) out += " | " + Cell(CellText(fj, m, c));
    out += " |\n";
  }
  return out;
}

const ManifestTable* TableOf(const Manifest& m, const std::string& name) {
  for (const ManifestTable& t : m.tables) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

// A marked place in a document: [begin, end) is its content.
struct Marker {
  bool table = false;
  std::string name;
  size_t begin = 0, end = 0;
  int line = 0;
};

int LineAt(const std::string& text, size_t pos) {
  return 1 +
         static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(pos), '\n'));
}

std::vector<Marker> FindMarkers(const std::string& text, const std::string& where) {
  std::vector<Marker> out;
  const struct {
    bool table;
    std::string open, close;
  } kinds[] = {{true, "<!-- figures-table: ", "<!-- /figures-table -->"},
               {false, "<!-- figure: ", "<!-- /figure -->"}};
  for (const auto& k : kinds) {
    size_t at = 0;
    while ((at = text.find(k.open, at)) != std::string::npos) {
      const size_t name_end = text.find(" -->", at);
      if (name_end == std::string::npos) {
        throw ConfigError(where + ":" + std::to_string(LineAt(text, at)), "marker",
                          "not closed by -->");
      }
      Marker mk;
      mk.table = k.table;
      mk.name = text.substr(at + k.open.size(), name_end - at - k.open.size());
      mk.line = LineAt(text, at);
      mk.begin = name_end + 4;
      mk.end = text.find(k.close, mk.begin);
      const size_t next_open = text.find(k.open, mk.begin);
      if (mk.end == std::string::npos || (next_open != std::string::npos && next_open < mk.end)) {
        throw ConfigError(where + ":" + std::to_string(mk.line), mk.name,
                          "no " + k.close + " before the next marker");
      }
      out.push_back(mk);
      at = mk.end + k.close.size();
    }
  }
  std::sort(out.begin(), out.end(),
            [](const Marker& a, const Marker& b) { return a.begin < b.begin; });
  return out;
}

std::string Expected(const Marker& mk, const Manifest& m, const nlohmann::json& fj,
                     const std::string& where) {
  if (mk.table) {
    const ManifestTable* t = TableOf(m, mk.name);
    if (!t) {
      throw ConfigError(where + ":" + std::to_string(mk.line), mk.name,
                        "names no table in the manifest");
    }
    return "\n" + TableText(fj, m, *t);
  }
  const ManifestFigure* f = m.Figure(mk.name);
  if (!f) {
    throw ConfigError(where + ":" + std::to_string(mk.line), mk.name,
                      "names no figure in the manifest");
  }
  return FigureText(fj, *f);
}

}  // namespace

std::string RenderDocument(const std::string& text, const std::string& where, const Manifest& m,
                           const nlohmann::json& fj) {
  std::string out;
  size_t at = 0;
  for (const Marker& mk : FindMarkers(text, where)) {
    out += text.substr(at, mk.begin - at);
    out += Expected(mk, m, fj, where);
    at = mk.end;
  }
  out += text.substr(at);
  return out;
}

std::vector<std::string> CheckDocuments(const fs::path& repository, const Manifest& m,
                                        const nlohmann::json& fj) {
  std::vector<std::string> problems;
  static const std::regex quoted_number(
      R"((?:^|[^\w.])(\d+(?:\.\d+)?\s?(?:mm|cm|%|°|km|MB|fps|ms))(?![A-Za-z]))");
  for (const std::string& doc : m.documents) {
    const fs::path path = repository / doc;
    std::ifstream in(path);
    if (!in) {
      problems.push_back(doc + ": cannot be read");
      continue;
    }
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<Marker> markers;
    try {
      markers = FindMarkers(text, doc);
      for (const Marker& mk : markers) {
        const std::string want = Expected(mk, m, fj, doc);
        const std::string have = text.substr(mk.begin, mk.end - mk.begin);
        if (want != have) {
          problems.push_back(
              doc + ":" + std::to_string(mk.line) + ": " + (mk.table ? "table " : "figure ") +
              mk.name + " says '" + (mk.table ? "…" : have) + "', figures.json '" +
              (mk.table ? "…" : want) + "' (plantscale figures --render rewrites it)");
        }
      }
    } catch (const ConfigError& e) {
      problems.push_back(e.what());
      continue;
    }
    // Numbers with a unit in the quoted region, outside every marker.
    const std::string open = "<!-- figures: quoted -->", close = "<!-- /figures: quoted -->";
    for (size_t q = text.find(open); q != std::string::npos; q = text.find(open, q + 1)) {
      const size_t qe = text.find(close, q);
      const size_t stop = qe == std::string::npos ? text.size() : qe;
      std::string region = text.substr(q, stop - q);
      for (auto it = markers.rbegin(); it != markers.rend(); ++it) {
        if (it->begin >= q && it->end <= stop) {
          region.replace(it->begin - q, it->end - it->begin, std::string(it->end - it->begin, ' '));
        }
      }
      // Figures of the literature, marked <!-- cited -->…<!-- /cited -->,
      // are not ours to make.
      for (size_t c = region.find("<!-- cited -->"); c != std::string::npos;
           c = region.find("<!-- cited -->", c + 1)) {
        const size_t ce = region.find("<!-- /cited -->", c);
        if (ce == std::string::npos) break;
        for (size_t k = c; k < ce; ++k) {
          if (region[k] != '\n') region[k] = ' ';
        }
      }
      // Link targets are addresses, not figures (blanked, keeping positions).
      static const std::regex link(R"(\]\([^)]*\))");
      for (std::sregex_iterator i(region.begin(), region.end(), link), e; i != e; ++i) {
        for (size_t k = static_cast<size_t>(i->position()) + 1;
             k < static_cast<size_t>(i->position() + i->length()); ++k) {
          if (region[k] != '\n') region[k] = ' ';
        }
      }
      for (std::sregex_iterator i(region.begin(), region.end(), quoted_number), e; i != e; ++i) {
        const size_t pos = q + static_cast<size_t>(i->position(1));
        problems.push_back(doc + ":" + std::to_string(LineAt(text, pos)) + ": '" + (*i)[1].str() +
                           "' is quoted outside every figure marker (a figure with no manifest "
                           "entry)");
      }
    }
  }
  return problems;
}

}  // namespace plantscale::app
