// Running another program (plot.py, ffmpeg) and waiting for it.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <sys/types.h>
#include <vector>

namespace stepwise {

// runs args[0] (looked up on PATH when it has no slash) with args, stdin/stdout/stderr inherited, and waits;
// its exit status, -1 if a signal ended it, nothing if it could not be started (the reason in *why)
std::optional<int> run_process(const std::vector<std::string>& args, std::string* why = nullptr);

// a program started with its standard input ours to write (ffmpeg reading raw frames from "-"), its
// stdout/stderr inherited. The input is a socket written with MSG_NOSIGNAL: a program that exits early makes
// write() return false, never a SIGPIPE
class FedProcess {
 public:
  // std::runtime_error naming the program and the reason if it cannot be started
  explicit FedProcess(const std::vector<std::string>& args);
  ~FedProcess();  // closes the input and waits, if finish() was not called
  FedProcess(const FedProcess&) = delete;
  FedProcess& operator=(const FedProcess&) = delete;
  // all of `bytes` written; false if the program has stopped reading
  bool write(std::span<const std::uint8_t> bytes);
  // closes the input and waits: the exit status, -1 if a signal ended it
  int finish();

 private:
  pid_t pid_ = -1;
  int input_ = -1;
};

// whether `name` is an executable file in a directory on PATH
bool on_path(const std::string& name);

}  // namespace stepwise
