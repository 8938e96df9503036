// What an interruption (SIGINT, SIGTERM, SIGHUP) leaves: nothing of ours. The signals wake one thread that stops the children we started, removes the temporary files and staging directories registered here, and
// ends the process with the shell's status for the signal (128 + its number). A run killed outright (SIGKILL)
// cannot clean up: its temporaries carry the process id in their names, and the next run in the same directory
// removes those whose process is gone (remove_stale).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <sys/types.h>

namespace stepwise::interrupt {

// take the signals (a handler that wakes the cleaning thread); call first in main, and again after a library
// that may install handlers of its own (MPI) has started
void install();

// once a signal has come, wait for the cleaning thread to end the process (never returns); else return at once.
// Called before an error is said and before main returns: an interruption removes the temporaries a run is
// writing into, its threads then fail, and a main returning meanwhile would run the static destructors (Mesa's,
// FFTW's) under threads still drawing, and say a failure where the interruption is the news (SIGTERM during
// the report's pictures died of SIGSEGV one try in three). The cleaning thread itself returns at once
void settle();

// a path removed (recursively) if the process is interrupted while the guard lives
class Temporary {
 public:
  explicit Temporary(std::filesystem::path path);
  ~Temporary();
  Temporary(const Temporary&) = delete;
  Temporary& operator=(const Temporary&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// while one lives, `last_words` runs on an interruption before the temporaries go (render writes render.json
// for the frames it finished); it must take its own lock on what it reads, and no thread may make or drop a
// Temporary (write a file) while holding that lock: the cleaning thread runs the last words holding the
// registry's lock, which a Temporary takes
class OnInterrupt {
 public:
  explicit OnInterrupt(std::function<void()> last_words);
  ~OnInterrupt();
  OnInterrupt(const OnInterrupt&) = delete;
  OnInterrupt& operator=(const OnInterrupt&) = delete;
};

// while one lives, an interruption waits (a report's swap: two renames that must both happen)
class Uninterrupted {
 public:
  Uninterrupted();
  ~Uninterrupted();
  Uninterrupted(const Uninterrupted&) = delete;
  Uninterrupted& operator=(const Uninterrupted&) = delete;
};

// a child process stopped (SIGTERM) if we are interrupted while it runs
void add_child(pid_t pid);
void remove_child(pid_t pid);

// the part of a temporary's name that marks it ours and names its process: ".stepwise-<pid>."
std::string temporary_tag();

// remove the entries of `dir` whose names carry a temporary tag of a process that no longer exists (a run
// killed outright); returns how many were removed. Entries of live processes and everything else are kept
int remove_stale(const std::filesystem::path& dir);

}  // namespace stepwise::interrupt
