#include "process.hpp"

#include "interrupt.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>

extern char** environ;

namespace stepwise {
namespace {

// args[0] itself when it names a path, else the first executable of that name on PATH
std::optional<std::string> resolve(const std::string& name) {
  if (name.find('/') != std::string::npos) return ::access(name.c_str(), X_OK) == 0 ? std::optional(name) : std::nullopt;
  const char* path = std::getenv("PATH");
  if (!path) return std::nullopt;
  std::stringstream dirs(path);
  for (std::string dir; std::getline(dirs, dir, ':');)
    if (const auto file = (std::filesystem::path(dir.empty() ? "." : dir) / name).string(); ::access(file.c_str(), X_OK) == 0) return file;
  return std::nullopt;
}

}  // namespace

std::optional<int> run_process(const std::vector<std::string>& args, std::string* why) {
  const std::optional<std::string> program = resolve(args[0]);
  if (!program) {
    if (why) *why = std::strerror(ENOENT);
    return std::nullopt;
  }
  std::vector<std::string> copy = args;
  std::vector<char*> argv;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  // fork and exec rather than posix_spawn: the child asks to die with us (PR_SET_PDEATHSIG: a parent killed
  // outright leaves no child writing on); between fork and exec only async-signal-safe calls (our signal
  // handlers go back to the defaults at exec)
  const pid_t pid = ::fork();
  if (pid < 0) {
    if (why) *why = std::strerror(errno);
    return std::nullopt;
  }
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(127);  // the parent died before the request took hold
    ::execve(program->c_str(), argv.data(), environ);
    ::_exit(127);
  }
  interrupt::add_child(pid);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  interrupt::remove_child(pid);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool on_path(const std::string& name) { return name.find('/') == std::string::npos && resolve(name).has_value(); }

}  // namespace stepwise
