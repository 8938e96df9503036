#include "native_code.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <vector>

#include <dlfcn.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace stepwise {
namespace {

namespace fs = std::filesystem;

// what the compiler is given besides the file names: optimised, position-independent, strict IEEE arithmetic
// (no contraction into fused multiply-adds, no fast math), so the compiled code computes what the interpreter does
constexpr const char* compile_flags[] = {"-std=c99", "-O2", "-fPIC", "-shared", "-ffp-contract=off", "-fno-math-errno"};
constexpr std::string_view format_version = "stepwise-native-1";

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

// a temporary file beside the cache entries, made with mkstemps (suffix kept for the compiler's sake)
std::string temporary(const fs::path& dir, const char* suffix) {
  std::string name = (dir / ".tmp-XXXXXX").string() + suffix;
  const int fd = ::mkstemps(name.data(), static_cast<int>(std::strlen(suffix)));
  if (fd < 0) return {};
  ::close(fd);
  return name;
}

// run the compiler on `c_file` into `so_file`, its messages into `log_file`; empty on success, else why not
std::string compile(const std::string& c_file, const std::string& so_file, const std::string& log_file) {
  const std::string cc = compiler();
  std::vector<std::string> args{cc};
  for (const char* f : compile_flags) args.emplace_back(f);
  // the source on standard input, so no file name of ours enters the object: two runs compiling the same source
  // make the same bytes, and either's rename leaves a matching pair
  for (const char* a : {"-o", so_file.c_str(), "-x", "c", "-", "-lm"}) args.emplace_back(a);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, c_file.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_file.c_str(), O_WRONLY | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = 0;
  const int spawned = ::posix_spawnp(&pid, cc.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return fmt::format("no C compiler: cannot start {}: {}", cc, std::strerror(spawned));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return fmt::format("waitpid on {}: {}", cc, std::strerror(errno));
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return {};
  std::ifstream log(log_file);
  std::string first;
  std::getline(log, first);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127) return fmt::format("no C compiler: {} not found", cc);
  return fmt::format("{} failed ({}){}{}", cc, WIFEXITED(status) ? fmt::format("exit {}", WEXITSTATUS(status)) : fmt::format("signal {}", WTERMSIG(status)),
                     first.empty() ? "" : ": ", first);
}

std::mutex loaded_mutex;
std::map<std::string, std::weak_ptr<const NativeCode>, std::less<>> loaded;  // key -> the object this process holds

}  // namespace

NativeCode::~NativeCode() { if (handle_) ::dlclose(handle_); }

void* NativeCode::symbol(const char* name) const { return ::dlsym(handle_, name); }

std::shared_ptr<const NativeCode> load_native(const std::string& body, std::string& why) {
  std::string flags;
  for (const char* f : compile_flags) flags += std::string(f) + " ";
  const std::string key = fmt::format("eq-{:016x}", fnv1a(body, fnv1a(fmt::format("{} {} {}", format_version, compiler(), flags))));
  const std::string source = body + fmt::format("\nconst char stepwise_key[] = \"{}\";\n", key);
  std::lock_guard lock(loaded_mutex);
  if (const auto it = loaded.find(key); it != loaded.end())
    if (auto held = it->second.lock()) return held;
  const auto dir = cache_directory(why);
  if (!dir) return nullptr;
  const fs::path so = *dir / (key + ".so"), sum = *dir / (key + ".sum");
  // load a verified entry, checking the key it holds; false (and the handle closed) if anything is amiss
  const auto try_load = [&]() -> std::shared_ptr<const NativeCode> {
    Opened opened;
    if (!open_verified(so, sum, opened)) return nullptr;
    void* handle = ::dlopen(fmt::format("/proc/self/fd/{}", opened.fd).c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) return nullptr;
    auto code = std::make_shared<const NativeCode>(handle, so.string());
    const auto* held_key = static_cast<const char*>(code->symbol("stepwise_key"));
    if (!held_key || key != held_key) return nullptr;
    return code;
  };
  std::shared_ptr<const NativeCode> code = try_load();
  if (!code) {
    const std::string c_file = temporary(*dir, ".c"), so_tmp = temporary(*dir, ".so"), log = temporary(*dir, ".log"), sum_tmp = temporary(*dir, ".sum");
    const auto clean = [&] {
      for (const auto& f : {c_file, so_tmp, log, sum_tmp})
        if (!f.empty()) ::unlink(f.c_str());
    };
    if (c_file.empty() || so_tmp.empty() || log.empty() || sum_tmp.empty()) {
      why = fmt::format("cannot make a temporary file in {}: {}", dir->string(), std::strerror(errno));
      clean();
      return nullptr;
    }
    {
      std::ofstream out(c_file, std::ios::binary);
      out << source;
      if (!out.flush()) {
        why = fmt::format("cannot write {}", c_file);
        clean();
        return nullptr;
      }
    }
    if (why = compile(c_file, so_tmp, log); !why.empty()) {
      clean();
      return nullptr;
    }
    ::chmod(so_tmp.c_str(), 0600);
    {
      const int fd = ::open(so_tmp.c_str(), O_RDONLY | O_CLOEXEC);
      const std::string bytes = fd >= 0 ? read_all(fd) : std::string();
      if (fd >= 0) ::close(fd);
      std::ofstream out(sum_tmp);
      out << sum_line(bytes);
      if (bytes.empty() || !out.flush()) {
        why = fmt::format("cannot read back or record {}", so_tmp);
        clean();
        return nullptr;
      }
    }
    // the object first, then its sum: a reader finding the sum finds the object it describes
    if (std::rename(so_tmp.c_str(), so.c_str()) != 0 || std::rename(sum_tmp.c_str(), sum.c_str()) != 0) {
      why = fmt::format("cannot file the compiled object in {}: {}", dir->string(), std::strerror(errno));
      clean();
      return nullptr;
    }
    clean();
    code = try_load();
    if (!code) {
      why = fmt::format("the compiled object {} did not load: {}", so.string(), ::dlerror() ? ::dlerror() : "its check failed");
      return nullptr;
    }
  }
  loaded[key] = code;
  return code;
}

}  // namespace stepwise
