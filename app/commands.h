#pragma once
// The subcommands of the plantscale command line: every command family adds
// itself to one CommandRegistry here.

#include <CLI/CLI.hpp>

#include "app/command_registry.h"

namespace plantscale::app {

class CommandLine {
 public:
  explicit CommandLine(CLI::App& cli);
  // Runs the parsed subcommand; returns the exit code.
  int Run() const { return registry_.Run(); }

 private:
  CommandRegistry registry_;
};

}  // namespace plantscale::app
