#include "interrupt.hpp"

#include "ranks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <mutex>
#include <fcntl.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace stepwise::interrupt {
namespace {

namespace fs = std::filesystem;

struct Registry {
  std::recursive_mutex mutex;  // recursive: last words write files, and a file registers its temporary
  std::vector<fs::path> paths;
  std::vector<pid_t> children;
  std::vector<std::pair<const void*, std::function<void()>>> last_words;
};

Registry& registry() {
  static Registry r;
  return r;
}

const char* signal_name(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "a signal"; }

// on the signal thread: children first (they write into our staging directories), then the paths, newest first;
// a worker still writing can recreate an entry in a directory being removed, so each removal is tried again
[[noreturn]] void clean_up_and_exit(int sig) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  for (const pid_t child : r.children) ::kill(child, SIGTERM);
  for (const auto& [owner, words] : r.last_words) {
    try {
      words();
    } catch (...) {  // what could not be written is said by its absence
    }
  }
  for (auto it = r.paths.rbegin(); it != r.paths.rend(); ++it)
    for (int attempt = 0; attempt < 3; ++attempt) {
      std::error_code ec;
      fs::remove_all(*it, ec);
      if (!ec) break;
    }
  // under mpirun rank 0 speaks for all (mpirun stops the others when one exits with an error)
  if (ranks::rank() == 0)
    std::fprintf(stderr, "stepwise: interrupted (%s): its temporary files removed, earlier outputs left as they were\n", signal_name(sig));
  std::fflush(stderr);
  ::_exit(128 + sig);
}

// the handler only passes the signal's number down a pipe (write(2) is async-signal-safe); the thread reading
// the other end does the work. A handler rather than a blocked mask: libraries start threads before main
// (OpenBLAS's pool), and a signal can be delivered to any of them
int signal_pipe[2] = {-1, -1};

// set by the handler before it writes (a lock-free atomic store is async-signal-safe): from then on the process
// ends only by the cleaning thread's _exit (settle)
std::atomic<bool> interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free);
std::atomic<std::thread::id> cleaner{};

extern "C" void pass_signal(int sig) {
  interrupted.store(true);
  const unsigned char byte = static_cast<unsigned char>(sig);
  [[maybe_unused]] const ssize_t n = ::write(signal_pipe[1], &byte, 1);
}

}  // namespace

void install() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (::pipe2(signal_pipe, O_CLOEXEC) != 0) return;
    std::thread([] {
      cleaner.store(std::this_thread::get_id());
      unsigned char byte = 0;
      while (::read(signal_pipe[0], &byte, 1) != 1) {
      }
      clean_up_and_exit(byte);
    }).detach();
  });
  // (again at each call: a library started since, MPI's, may have taken a signal for itself)
  if (signal_pipe[1] < 0) return;
  struct sigaction action {};
  action.sa_handler = pass_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &action, nullptr);
}

void settle() {
  if (!interrupted.load() || std::this_thread::get_id() == cleaner.load()) return;
  for (;;) ::pause();
}

Temporary::Temporary(fs::path path) : path_(std::move(path)) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.paths.push_back(path_);
}

Temporary::~Temporary() {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  if (const auto it = std::find(r.paths.rbegin(), r.paths.rend(), path_); it != r.paths.rend()) r.paths.erase(std::next(it).base());
}

OnInterrupt::OnInterrupt(std::function<void()> last_words) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.last_words.emplace_back(this, std::move(last_words));
}

OnInterrupt::~OnInterrupt() {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  std::erase_if(r.last_words, [this](const auto& entry) { return entry.first == this; });
}

Uninterrupted::Uninterrupted() { registry().mutex.lock(); }
Uninterrupted::~Uninterrupted() { registry().mutex.unlock(); }

void add_child(pid_t pid) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.children.push_back(pid);
}

void remove_child(pid_t pid) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  std::erase(r.children, pid);
}

std::string temporary_tag() { return fmt::format(".stepwise-{}.", ::getpid()); }

int remove_stale(const fs::path& dir) {
  constexpr std::string_view marker = ".stepwise-";
  int removed = 0;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const auto at = name.find(marker);
    if (name.empty() || name[0] != '.' || at == std::string::npos) continue;
    const char* first = name.data() + at + marker.size();
    const char* last = name.data() + name.size();
    pid_t pid = 0;
    const auto [end_of_pid, parsed] = std::from_chars(first, last, pid);
    if (parsed != std::errc() || end_of_pid == last || *end_of_pid != '.' || pid <= 0 || pid == ::getpid()) continue;
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;  // alive (or not ours to signal): kept
    std::error_code removal;
    fs::remove_all(it->path(), removal);
    if (!removal) ++removed;
  }
  return removed;
}

}  // namespace stepwise::interrupt
