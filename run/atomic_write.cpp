#include "atomic_write.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

namespace stepwise {

unsigned default_mode(bool directory) {
  static const unsigned umask = [] {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
      if (line.starts_with("Umask:")) return static_cast<unsigned>(std::stoul(line.substr(6), nullptr, 8));
    return 022u;
  }();
  return (directory ? 0777u : 0666u) & ~umask;
}

void write_file_atomic(const std::filesystem::path& path, std::string_view content) {
  std::string tmp = (path.parent_path() / fmt::format(".{}.XXXXXX", path.filename().string())).string();
  const int fd = mkstemp(tmp.data());
  if (fd < 0) throw std::runtime_error(fmt::format("{}: cannot create a temporary file: {}", path.string(), std::strerror(errno)));
  bool ok = ::fchmod(fd, static_cast<mode_t>(default_mode(false))) == 0;
  const char* p = content.data();
  size_t left = content.size();
  while (left > 0 && ok) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) { p += n; left -= static_cast<size_t>(n); }
  }
  ok = ok && ::fsync(fd) == 0;
  const int saved = errno;
  ok = (::close(fd) == 0) && ok;
  if (!ok || std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = ok ? errno : saved;
    std::remove(tmp.c_str());
    throw std::runtime_error(fmt::format("{}: cannot write: {}", path.string(), std::strerror(err)));
  }
}

void ensure_writable_directory(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw std::runtime_error(fmt::format("{}: cannot create output directory: {}", dir.string(), ec ? ec.message() : "not a directory"));
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw std::runtime_error(fmt::format("{}: output directory is not writable: {}", dir.string(), std::strerror(errno)));
}

}  // namespace stepwise
