#include "app/log_eval_commands.h"

#include <iostream>
#include <string>

#include "app/segment_commands.h"
#include "evaluation/log_eval.h"
#include "evaluation/log_writer.h"
#include "evaluation/writer.h"

namespace plantscale::app {
namespace {

struct LogEvalArgs {
  std::string log;
  std::string config_dir;
  bool json = false;
};

int EvaluateLogCommand(const LogEvalArgs& a, const GlobalOptions& global) {
  LogEvalOptions o;
  o.log = a.log;
  // --config-dir here, else the global one when given, else the log's own.
  o.config_dir = !a.config_dir.empty() ? a.config_dir : global.config_dir;
  const LogEvaluation e = EvaluateLog(o);
  for (const std::string& p : e.problems) std::cerr << "evaluate log: warning: " << p << '\n';
  WriteEvaluation(e, a.json, std::cout);
  return 0;
}

}  // namespace

void AddLogEvalCommands(CommandRegistry& registry) {
  const GlobalOptions& global = registry.global();
  LogEvalArgs& args = registry.Keep(LogEvalArgs{});
  CLI::App* cmd = registry.Add(
      "log",
      "a simulated run's vehicle log (simulate --publish --log) against the truth in it: "
      "treatment and tracking as evaluate treatment and evaluate tracking score them",
      [&args, &global] { return EvaluateLogCommand(args, global); }, EvaluateCommand(registry));
  cmd->add_option("LOG", args.log, "LCM log of plantscale simulate --publish --log")->required();
  cmd->add_option("--config-dir", args.config_dir,
                  "folder with presets/ to rebuild the run from (default: the log's, else "
                  "built-in)");
  cmd->add_flag("--json", args.json, "print one JSON object");
}

}  // namespace plantscale::app
