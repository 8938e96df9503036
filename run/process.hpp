// Running another program (plot.py, ffmpeg) and waiting for it.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace stepwise {

// runs args[0] (looked up on PATH when it has no slash) with args, stdin/stdout/stderr inherited, and waits;
// its exit status, -1 if a signal ended it, nothing if it could not be started (the reason in *why)
std::optional<int> run_process(const std::vector<std::string>& args, std::string* why = nullptr);

// whether `name` is an executable file in a directory on PATH
bool on_path(const std::string& name);

}  // namespace stepwise
