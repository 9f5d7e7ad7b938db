#pragma once
// The subcommands of the plantscale command line.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <optional>
#include <string>

namespace plantscale::app {

class CommandLine {
 public:
  explicit CommandLine(CLI::App& cli);
  // Runs the parsed subcommand; returns the exit code.
  int Run() const;

 private:
  struct SimulateArgs {
    std::string preset = "field";
    std::optional<double> length_m;
    std::optional<int64_t> seed;
    std::string out;
    int every = 1;
    std::string image;
    bool quiet = false;
  };
  int Simulate() const;
  int Demo() const;
  int Presets() const;

  CLI::App* simulate_ = nullptr;
  CLI::App* demo_ = nullptr;
  CLI::App* presets_ = nullptr;
  std::string config_dir_;
  SimulateArgs sim_;
  SimulateArgs demo_args_;
};

}  // namespace plantscale::app
