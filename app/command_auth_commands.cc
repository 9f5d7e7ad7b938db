#include "app/command_auth_commands.h"

#include <iostream>

#include "app/config/config_loader.h"
#include "app/vehicle/runner.h"
#include "telemetry/command_auth.h"
#include "telemetry/transport.h"

namespace plantscale::app {

namespace tm = plantscale::telemetry;

void AddVehicleCommandKeyOptions(CLI::App* cmd, CommandKeyArgs& a) {
  cmd->add_option("--command-key", a.file,
                  "shared key file (plantscale keygen, mode 0600) that station commands must be signed "
                  "with; without it every command is refused");
  cmd->add_flag("--accept-unsigned-commands", a.accept_unsigned,
                "obey unsigned station commands from anyone on the LCM group (demo and tests only)");
}

vehicle::CommandAuthOptions VehicleCommandAuth(const CommandKeyArgs& a) {
  vehicle::CommandAuthOptions auth;
  auth.accept_unsigned = a.accept_unsigned;
  auth.clock = tm::WallUtime;
  if (!a.file.empty()) {
    try {
      auth.key = tm::ReadCommandKey(a.file);
    } catch (const tm::CommandAuthError& e) {
      throw ConfigError("command line", "--command-key", e.what());
    }
  }
  if (a.accept_unsigned) {
    std::cerr << "plantscale: warning: --accept-unsigned-commands: unsigned station commands from anyone on "
                 "the LCM group will be obeyed"
              << (auth.key ? " (signed ones are still checked)" : "") << '\n';
  } else if (!auth.key) {
    std::cerr << "plantscale: note: no --command-key: every station command will be refused\n";
  }
  return auth;
}

void AddCommandAuthCommands(CommandRegistry& registry) {
  std::string& file = registry.Keep(std::string{});
  CLI::App* keygen = registry.Add(
      "keygen", "write a new random key for signed station commands (mode 0600; never overwrites)", [&file] {
        tm::WriteNewCommandKey(file);  // CommandAuthError: the file exists or cannot be written
        std::cout << "keygen: " << file << " (32 random bytes as hex, mode 0600): give it to the vehicle "
                  << "and the station with --command-key\n";
        return 0;
      });
  keygen->add_option("FILE", file, "key file to create")->required();
}

}  // namespace plantscale::app
