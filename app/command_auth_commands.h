#pragma once
// Signed station commands on the command line (telemetry/command_auth.h):
// `plantscale keygen FILE`, and the vehicle's --command-key FILE and
// --accept-unsigned-commands (simulate --publish, run). Fail closed: a
// vehicle without a key refuses every station command unless
// --accept-unsigned-commands is given (demo and tests; it warns).

#include <CLI/CLI.hpp>
#include <string>

#include "app/command_registry.h"

namespace plantscale::vehicle {
struct CommandAuthOptions;  // app/vehicle/runner.h
}  // namespace plantscale::vehicle

namespace plantscale::app {

struct CommandKeyArgs {
  std::string file;              // --command-key; empty: none
  bool accept_unsigned = false;  // --accept-unsigned-commands
};

void AddVehicleCommandKeyOptions(CLI::App* command, CommandKeyArgs& args);

// Reads the key file (ConfigError naming the file and why: missing, mode
// other than 0600/0400, no key in it) and says on stderr what the vehicle
// will do with unsigned commands. Commands' timestamps are checked against
// the wall clock, which the station stamps them with (with --fast the
// message clock runs ahead of it).
vehicle::CommandAuthOptions VehicleCommandAuth(const CommandKeyArgs& args);

void AddCommandAuthCommands(CommandRegistry& registry);

}  // namespace plantscale::app
