#include "process.hpp"

#include "interrupt.hpp"

#include "models/native_code.hpp"  // find_program

#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

extern char** environ;

namespace stepwise {
namespace {

// forks and execs `program` with args, its standard input `input` where given (-1: ours); the child's pid, or
// -1 with errno set
pid_t spawn(const std::string& program, const std::vector<std::string>& args, int input) {
  std::vector<std::string> copy = args;
  std::vector<char*> argv;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  // fork and exec rather than posix_spawn: the child asks to die with us (PR_SET_PDEATHSIG: a parent killed
  // outright leaves no child writing on); between fork and exec only async-signal-safe calls (our signal
  // handlers go back to the defaults at exec)
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (::getppid() != parent) ::_exit(127);  // the parent died before the request took hold
  if (input >= 0 && ::dup2(input, STDIN_FILENO) < 0) ::_exit(127);
  ::execve(program.c_str(), argv.data(), environ);
  ::_exit(127);
}

// waits for a child spawn() started; its exit status, -1 if a signal ended it
int wait_for(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  interrupt::remove_child(pid);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

std::optional<int> run_process(const std::vector<std::string>& args, std::string* why) {
  const std::optional<std::string> program = find_program(args[0]);
  if (!program) {
    if (why) *why = std::strerror(ENOENT);
    return std::nullopt;
  }
  const pid_t pid = spawn(*program, args, -1);
  if (pid < 0) {
    if (why) *why = std::strerror(errno);
    return std::nullopt;
  }
  interrupt::add_child(pid);
  return wait_for(pid);
}

FedProcess::FedProcess(const std::vector<std::string>& args) {
  const std::optional<std::string> program = find_program(args[0]);
  if (!program) throw std::runtime_error(fmt::format("{}: {}", args[0], std::strerror(ENOENT)));
  int ends[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, ends) < 0)
    throw std::runtime_error(fmt::format("{}: socketpair: {}", args[0], std::strerror(errno)));
  // the child reads ends[1] as its standard input (dup2 clears close-on-exec on the copy); we write ends[0]
  pid_ = spawn(*program, args, ends[1]);
  const int error = errno;
  ::close(ends[1]);
  if (pid_ < 0) {
    ::close(ends[0]);
    throw std::runtime_error(fmt::format("{}: fork: {}", args[0], std::strerror(error)));
  }
  ::shutdown(ends[0], SHUT_RD);
  input_ = ends[0];
  interrupt::add_child(pid_);
}

FedProcess::~FedProcess() {
  if (pid_ >= 0) finish();
}

bool FedProcess::write(std::span<const std::uint8_t> bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::send(input_, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes = bytes.subspan(static_cast<size_t>(n));
  }
  return true;
}

int FedProcess::finish() {
  if (input_ >= 0) ::close(input_);
  input_ = -1;
  const int status = wait_for(pid_);
  pid_ = -1;
  return status;
}

bool on_path(const std::string& name) { return name.find('/') == std::string::npos && find_program(name).has_value(); }

}  // namespace stepwise
