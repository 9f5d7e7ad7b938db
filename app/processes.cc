#include "app/processes.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>

#include "ui/display.h"

extern char** environ;

namespace plantscale::app {

bool OnPath(const std::string& program) {
  return std::system(("command -v " + program + " >/dev/null 2>&1").c_str()) == 0;
}

void RerunUnderXvfb() {
  if (ui::DisplayAvailable() || std::getenv("PLANTSCALE_XVFB") != nullptr || !OnPath("xvfb-run")) return;
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  const std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::string> args{"xvfb-run", "-a", "-s", "-screen 0 1280x1024x24 -noreset"};
  args.push_back(std::filesystem::read_symlink("/proc/self/exe").string());
  size_t at = raw.find('\0');  // skip argv[0]: the path of this executable instead
  while (at != std::string::npos && at + 1 < raw.size()) {
    const size_t end = raw.find('\0', at + 1);
    args.push_back(raw.substr(at + 1, end - at - 1));
    at = end;
  }
  std::vector<char*> argv;
  for (std::string& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);
  setenv("PLANTSCALE_XVFB", "1", 1);
  std::cout.flush();
  execvp(argv[0], argv.data());
}

pid_t Spawn(const std::vector<std::string>& args, const std::filesystem::path& output) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = -1;
  const int error = posix_spawnp(&pid, argv[0], &files, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  return error == 0 ? pid : -1;
}

int Wait(pid_t pid) {
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace plantscale::app
