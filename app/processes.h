#pragma once
// Child processes and the virtual X display of the commands that render:
// starting a program with its output to a file and waiting for it (the
// demo's vehicle, station, report and exports), whether a program is on
// PATH, and this very command run again under `xvfb-run -a` when there is
// no display (station screenshots and tours, the report's camera views).

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace plantscale::app {

// `program` is found on PATH.
bool OnPath(const std::string& program);

// Starts `args` (args[0] looked up on PATH) with stdout and stderr to
// `output` (created or truncated); returns the child's pid, or -1.
pid_t Spawn(const std::vector<std::string>& args, const std::filesystem::path& output);

// The exit status of `pid` (128 + the signal when killed); -1 for pid < 0
// or when it cannot be waited for.
int Wait(pid_t pid);

// Without DISPLAY, runs this very command again under its own virtual X
// server (`xvfb-run -a`, as demo does) when xvfb-run is installed; returns
// only when that is not possible (then the caller goes on without one).
// PLANTSCALE_XVFB set in the environment stops a second re-run.
void RerunUnderXvfb();

}  // namespace plantscale::app
