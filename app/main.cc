// plantscale: the command line. The only place that parses configuration
// and decides exit codes: 0 success, 1 runtime failure (I/O), 2 bad input
// (unknown preset, invalid option, malformed YAML, bad command line).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <optional>

#include "app/commands.h"
#include "app/config/config_loader.h"
#include "engine/common/options.h"

int main(int argc, char** argv) {
  using plantscale::app::CommandLine;
  CLI::App cli{"plantscale: plant-scale crop husbandry (crop-grid tracking, crop/weed, spraying)"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", "plantscale 0.1.0");
  CommandLine commands(cli);
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = cli.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    return commands.Run();
  } catch (const plantscale::app::ConfigError& e) {
    std::cerr << "plantscale: error: " << e.what() << '\n';
    return 2;
  } catch (const plantscale::InvalidOptionsError& e) {
    std::cerr << "plantscale: error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "plantscale: error: " << e.what() << '\n';
    return 1;
  }
}
