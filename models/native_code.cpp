#include "native_code.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include <dlfcn.h>
#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace stepwise {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// what the compiler is given besides the file names and the -O level: position-independent, strict IEEE
// arithmetic (no contraction into fused multiply-adds, no fast math), so the compiled code computes what the
// interpreter does
constexpr const char* compile_flags[] = {"-std=c99", "-fPIC", "-ffp-contract=off", "-fno-math-errno"};
constexpr std::string_view format_version = "stepwise-native-2";

// FNV-1a, 64 bits: names a cache entry and checks its bytes (a cache is the user's own: the check is against
// corruption and stray files, not an adversary who can write there)
std::uint64_t fnv1a(std::string_view bytes, std::uint64_t h = 0xcbf29ce484222325ull) {
  for (const unsigned char c : bytes) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

std::string compiler() {
  const char* cc = std::getenv("STEPWISE_CC");
  return cc && *cc ? cc : "cc";
}

std::string key_of(const NativeSource& s) {
  std::string flags;
  for (const char* f : compile_flags) flags += std::string(f) + " ";
  std::uint64_t h = fnv1a(fmt::format("{} {} {}{}", format_version, compiler(), flags, s.optimisation));
  h = fnv1a(s.common, h);
  for (const auto& unit : s.units) h = fnv1a(unit, fnv1a(fmt::format("\n/* unit of {} bytes */\n", unit.size()), h));
  return fmt::format("eq-{:016x}", h);
}

std::optional<fs::path> cache_directory(std::string& why) {
  fs::path dir;
  if (const char* c = std::getenv("STEPWISE_CACHE"); c && *c) dir = c;
  else if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) dir = fs::path(x) / "stepwise";
  else if (const char* h = std::getenv("HOME"); h && *h) dir = fs::path(h) / ".cache" / "stepwise";
  else {
    why = "no cache directory (neither $STEPWISE_CACHE, $XDG_CACHE_HOME nor $HOME is set)";
    return std::nullopt;
  }
  std::error_code ec;
  // made private: the compiled objects are code this user's runs load
  if (fs::create_directories(dir, ec) && !ec) fs::permissions(dir, fs::perms::owner_all, ec);
  if (ec || !fs::is_directory(dir)) {
    why = fmt::format("cannot make the cache directory {}: {}", dir.string(), ec ? ec.message() : "not a directory");
    return std::nullopt;
  }
  // a directory another user can write to could have its entries swapped for theirs between check and load
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || st.st_uid != ::getuid() || (st.st_mode & (S_IWGRP | S_IWOTH))) {
    why = fmt::format("the cache directory {} is {}: code there could be replaced by another user, so none is compiled into it or loaded "
                      "from it (make it yours, mode 0700)",
                      dir.string(), st.st_uid != ::getuid() ? "not yours" : "writable by others");
    return std::nullopt;
  }
  if (::access(dir.c_str(), W_OK) != 0) {
    why = fmt::format("cannot write to the cache directory {}: {}", dir.string(), std::strerror(errno));
    return std::nullopt;
  }
  return dir;
}

std::string read_all(int fd) {
  std::string bytes;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    bytes.append(buffer, static_cast<size_t>(n));
  }
  return bytes;
}

std::string sum_line(std::string_view so_bytes) { return fmt::format("{} {} {:016x}\n", format_version, so_bytes.size(), fnv1a(so_bytes)); }

// the verified entry opened, or nothing: a regular file of this user's, written by nobody else, whose bytes match
// its .sum. The descriptor returned is the one the bytes were read from (loaded as /proc/self/fd/N)
struct Opened {
  int fd = -1;
  ~Opened() { if (fd >= 0) ::close(fd); }
};
bool open_verified(const fs::path& so, const fs::path& sum, Opened& opened) {
  std::ifstream sum_in(sum);
  std::string expected((std::istreambuf_iterator<char>(sum_in)), std::istreambuf_iterator<char>());
  if (expected.empty()) return false;
  const int fd = ::open(so.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return false;
  opened.fd = fd;
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != ::getuid() || (st.st_mode & (S_IWGRP | S_IWOTH))) return false;
  return sum_line(read_all(fd)) == expected;
}

// ---- temporaries beside the cache entries: .tmp-PID-XXXXXX<suffix>, made with mkstemps (the suffix kept for
// the compiler's sake); each removed when its owner goes, and those of a process that is gone at the next compile
class Temporaries {
 public:
  explicit Temporaries(fs::path dir) : dir_(std::move(dir)) {}
  ~Temporaries() {
    for (const auto& f : files_) ::unlink(f.c_str());
  }
  // a new empty file's name, or empty
  std::string make(const char* suffix) {
    std::string name = (dir_ / fmt::format(".tmp-{}-XXXXXX", ::getpid())).string() + suffix;
    const int fd = ::mkstemps(name.data(), static_cast<int>(std::strlen(suffix)));
    if (fd < 0) return {};
    ::close(fd);
    files_.push_back(name);
    return name;
  }

 private:
  fs::path dir_;
  std::vector<std::string> files_;
};

void remove_stale_temporaries(const fs::path& dir) {
  constexpr std::string_view prefix = ".tmp-";
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!name.starts_with(prefix)) continue;
    pid_t pid = 0;
    const char* first = name.data() + prefix.size();
    const auto [stop, parsed] = std::from_chars(first, name.data() + name.size(), pid);
    if (parsed != std::errc() || stop == name.data() + name.size() || *stop != '-' || pid <= 0) continue;
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to ask
    ::unlink(it->path().c_str());
  }
}

// ---- the compiler under its guard. The guard is a child of ours that leads a process group of its own, starts
// the compiler in it and waits for it: SIGTERM (sent by us on a time limit or a cancel, or by the kernel when the
// thread that forked it ends: PR_SET_PDEATHSIG) makes it kill the whole group, the driver's own children with
// it. Between fork and exec only async-signal-safe calls
extern "C" void kill_own_group(int) { ::kill(0, SIGKILL); }

pid_t start_guarded(const std::string& program, std::vector<std::string> args, const std::string& input, const std::string& log) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  const pid_t guard = ::fork();
  if (guard != 0) return guard;
  ::setpgid(0, 0);
  struct sigaction action {};
  action.sa_handler = kill_own_group;
  sigemptyset(&action.sa_mask);
  for (const int sig : {SIGTERM, SIGINT, SIGHUP}) ::sigaction(sig, &action, nullptr);
  sigset_t none;
  sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (::getppid() != parent) kill_own_group(0);  // we died before the request took hold
  const pid_t cc = ::fork();
  if (cc == 0) {
    const int in = ::open(input.c_str(), O_RDONLY), out = ::open(log.c_str(), O_WRONLY | O_TRUNC);
    if (in < 0 || out < 0 || ::dup2(in, STDIN_FILENO) < 0 || ::dup2(out, STDOUT_FILENO) < 0 || ::dup2(out, STDERR_FILENO) < 0) ::_exit(126);
    ::execve(program.c_str(), argv.data(), environ);
    ::_exit(127);
  }
  if (cc < 0) ::_exit(126);
  int status = 0;
  while (::waitpid(cc, &status, 0) < 0)
    if (errno != EINTR) ::_exit(126);
  ::_exit(WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status));
}

struct Job {
  std::vector<std::string> args;  // after the program
  std::string input, log;         // standard input; standard output and error
};

// the first line a failed job wrote, its exit in words
std::string failure(const std::string& cc, const Job& job, int status) {
  std::ifstream log(job.log);
  std::string first;
  std::getline(log, first);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127) return fmt::format("no C compiler: {} could not be started", cc);
  const std::string how = WIFEXITED(status) ? fmt::format("exit {}", WEXITSTATUS(status)) : fmt::format("signal {}", WTERMSIG(status));
  return fmt::format("{} failed ({}){}{}", cc, how, first.empty() ? "" : ": ", first);
}

// runs the jobs, up to the machine's cores at once; empty when all succeed, else why not. On the limits (time,
// cancel) or a failure the running guards are told to stop, and waited for
std::string run_jobs(const std::string& cc, const std::string& program, const std::vector<Job>& jobs, const CompileLimits& limits) {
  const size_t width = std::max(1u, std::thread::hardware_concurrency());
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(limits.seconds));
  std::vector<std::pair<pid_t, size_t>> running;  // guard, job
  std::string why;
  size_t next = 0;
  while (why.empty() && (next < jobs.size() || !running.empty())) {
    while (next < jobs.size() && running.size() < width) {
      std::vector<std::string> args{cc};
      args.insert(args.end(), jobs[next].args.begin(), jobs[next].args.end());
      const pid_t guard = start_guarded(program, args, jobs[next].input, jobs[next].log);
      if (guard < 0) return fmt::format("cannot start {}: fork: {}", cc, std::strerror(errno));
      running.emplace_back(guard, next++);
    }
    for (auto it = running.begin(); it != running.end() && why.empty();) {
      int status = 0;
      const pid_t done = ::waitpid(it->first, &status, WNOHANG);
      if (done == 0 || (done < 0 && errno == EINTR)) {
        ++it;
        continue;
      }
      if (done < 0) why = fmt::format("waitpid on {}: {}", cc, std::strerror(errno));
      else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) why = failure(cc, jobs[it->second], status);
      it = running.erase(it);
    }
    if (!why.empty()) break;
    if (limits.cancel && limits.cancel->load()) why = "the compile was cancelled";
    else if (Clock::now() > deadline) why = fmt::format("the compiler took longer than its {:g} s limit", limits.seconds);
    else if (!running.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  for (const auto& [guard, job] : running) {
    ::kill(guard, SIGTERM);
    int status = 0;
    while (::waitpid(guard, &status, 0) < 0 && errno == EINTR) {
    }
  }
  return why;
}

// compiles the source into `so_file` (units apart, then linked); empty on success, else why not
std::string compile(const NativeSource& source, const std::string& key_line, const std::string& so_file, Temporaries& temporaries,
                    const CompileLimits& limits) {
  const std::string cc = compiler();
  const auto program = find_program(cc);
  if (!program) return fmt::format("no C compiler: {} not found", cc);
  const bool one = source.units.size() == 1;
  std::vector<Job> jobs;
  std::vector<std::string> objects;
  for (size_t k = 0; k < source.units.size(); ++k) {
    const std::string c_file = temporaries.make(".c"), log = temporaries.make(".log"), object = one ? so_file : temporaries.make(".o");
    if (c_file.empty() || log.empty() || object.empty()) return fmt::format("cannot make a temporary file: {}", std::strerror(errno));
    std::ofstream out(c_file, std::ios::binary);
    out << source.common << source.units[k] << (k == 0 ? key_line : "");
    if (!out.flush()) return fmt::format("cannot write {}", c_file);
    Job job{{}, c_file, log};
    for (const char* f : compile_flags) job.args.emplace_back(f);
    job.args.push_back(source.optimisation);
    // the source on standard input, so no file name of ours enters the object: two runs compiling the same
    // source make the same bytes, and either's rename leaves a matching pair
    for (const char* a : {one ? "-shared" : "-c", "-o"}) job.args.emplace_back(a);
    job.args.push_back(object);
    for (const char* a : {"-x", "c", "-"}) job.args.emplace_back(a);
    if (one) job.args.emplace_back("-lm");
    jobs.push_back(std::move(job));
    objects.push_back(object);
  }
  if (std::string why = run_jobs(cc, *program, jobs, limits); !why.empty() || one) return why;
  // the objects linked into one
  Job link{{"-shared", "-o", so_file}, "/dev/null", temporaries.make(".log")};
  if (link.log.empty()) return fmt::format("cannot make a temporary file: {}", std::strerror(errno));
  link.args.insert(link.args.end(), objects.begin(), objects.end());
  link.args.emplace_back("-lm");
  return run_jobs(cc, *program, {link}, limits);
}

std::mutex loaded_mutex;
std::map<std::string, std::weak_ptr<const NativeCode>, std::less<>> loaded;  // key -> the object this process holds
std::map<std::string, std::shared_ptr<std::mutex>, std::less<>> compiling;    // key -> held while it is compiled

std::shared_ptr<const NativeCode> held(const std::string& key) {
  std::lock_guard lock(loaded_mutex);
  const auto it = loaded.find(key);
  return it != loaded.end() ? it->second.lock() : nullptr;
}

// a verified entry loaded, its key checked; null if anything is amiss
std::shared_ptr<const NativeCode> try_load(const fs::path& so, const fs::path& sum, const std::string& key, bool compiled, std::string* why) {
  Opened opened;
  if (!open_verified(so, sum, opened)) {
    if (why) *why = fmt::format("the compiled object {} failed its check", so.string());
    return nullptr;
  }
  void* handle = ::dlopen(fmt::format("/proc/self/fd/{}", opened.fd).c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    const char* error = ::dlerror();  // read once: a second call returns null
    if (why) *why = fmt::format("the compiled object {} did not load: {}", so.string(), error ? error : "dlopen failed");
    return nullptr;
  }
  auto code = std::make_shared<const NativeCode>(handle, so.string(), compiled);
  const auto* held_key = static_cast<const char*>(code->symbol("stepwise_key"));
  if (!held_key || key != held_key) {
    if (why) *why = fmt::format("the compiled object {} holds another key", so.string());
    return nullptr;
  }
  return code;
}

}  // namespace

std::optional<std::string> find_program(const std::string& name) {
  if (name.find('/') != std::string::npos) return ::access(name.c_str(), X_OK) == 0 ? std::optional(name) : std::nullopt;
  const char* path = std::getenv("PATH");
  if (!path) return std::nullopt;
  std::stringstream dirs(path);
  for (std::string dir; std::getline(dirs, dir, ':');)
    if (const auto file = (fs::path(dir.empty() ? "." : dir) / name).string(); ::access(file.c_str(), X_OK) == 0) return file;
  return std::nullopt;
}

NativeCode::~NativeCode() { if (handle_) ::dlclose(handle_); }

void* NativeCode::symbol(const char* name) const { return ::dlsym(handle_, name); }

size_t NativeSource::bytes() const {
  size_t total = 0;
  for (const auto& unit : units) total += common.size() + unit.size();
  return total;
}

std::shared_ptr<const NativeCode> cached_native(const NativeSource& source) {
  const std::string key = key_of(source);
  if (auto code = held(key)) return code;
  std::string why;
  const auto dir = cache_directory(why);
  if (!dir) return nullptr;
  auto code = try_load(*dir / (key + ".so"), *dir / (key + ".sum"), key, false, nullptr);
  if (code) {
    std::lock_guard lock(loaded_mutex);
    loaded[key] = code;
  }
  return code;
}

std::shared_ptr<const NativeCode> load_native(const NativeSource& source, const CompileLimits& limits, std::string& why) {
  const std::string key = key_of(source);
  std::shared_ptr<std::mutex> key_mutex;
  {
    std::lock_guard lock(loaded_mutex);
    auto& m = compiling[key];
    if (!m) m = std::make_shared<std::mutex>();
    key_mutex = m;
  }
  // one compile of a key at a time in this process (a sweep's threads make the same model at once)
  std::lock_guard compile_lock(*key_mutex);
  if (auto code = held(key)) return code;
  const auto dir = cache_directory(why);
  if (!dir) return nullptr;
  const fs::path so = *dir / (key + ".so"), sum = *dir / (key + ".sum");
  std::shared_ptr<const NativeCode> code = try_load(so, sum, key, false, nullptr);
  if (!code) {
    remove_stale_temporaries(*dir);
    Temporaries temporaries(*dir);
    const std::string so_tmp = temporaries.make(".so"), sum_tmp = temporaries.make(".sum");
    if (so_tmp.empty() || sum_tmp.empty()) {
      why = fmt::format("cannot make a temporary file in {}: {}", dir->string(), std::strerror(errno));
      return nullptr;
    }
    if (why = compile(source, fmt::format("\nconst char stepwise_key[] = \"{}\";\n", key), so_tmp, temporaries, limits); !why.empty()) return nullptr;
    ::chmod(so_tmp.c_str(), 0600);
    {
      const int fd = ::open(so_tmp.c_str(), O_RDONLY | O_CLOEXEC);
      const std::string bytes = fd >= 0 ? read_all(fd) : std::string();
      if (fd >= 0) ::close(fd);
      std::ofstream out(sum_tmp);
      out << sum_line(bytes);
      if (bytes.empty() || !out.flush()) {
        why = fmt::format("cannot read back or record {}", so_tmp);
        return nullptr;
      }
    }
    // the object first, then its sum: a reader finding the sum finds the object it describes
    if (std::rename(so_tmp.c_str(), so.c_str()) != 0 || std::rename(sum_tmp.c_str(), sum.c_str()) != 0) {
      why = fmt::format("cannot file the compiled object in {}: {}", dir->string(), std::strerror(errno));
      return nullptr;
    }
    if (code = try_load(so, sum, key, true, &why); !code) return nullptr;
  }
  std::lock_guard lock(loaded_mutex);
  loaded[key] = code;
  return code;
}

std::shared_ptr<const NativeCode> load_native(const std::string& source, std::string& why) {
  NativeSource s;
  s.units.push_back(source);
  return load_native(s, CompileLimits{}, why);
}

}  // namespace stepwise
