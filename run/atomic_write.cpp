#include "atomic_write.hpp"

#include "interrupt.hpp"

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

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  check_replaceable_file(target_);
  temporary_ = (target_.parent_path() / fmt::format(".{}{}XXXXXX", target_.filename().string(), interrupt::temporary_tag())).string();
  {
    // made and registered as one: an interruption between the two would leave the file unlisted, and one
    // already under way stops this thread here before the file exists
    const interrupt::Uninterrupted registering;
    fd_ = mkstemp(temporary_.data());
    if (fd_ < 0) throw std::runtime_error(fmt::format("{}: cannot create a temporary file: {}", target_.string(), std::strerror(errno)));
    guard_ = std::make_unique<interrupt::Temporary>(temporary_);
  }
  if (::fchmod(fd_, static_cast<mode_t>(default_mode(false))) != 0)
    throw std::runtime_error(fmt::format("{}: cannot write: {}", target_.string(), std::strerror(errno)));
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) {
    ::close(fd_);
    std::remove(temporary_.c_str());
  }
}

void AtomicFile::flush() {
  write_through(buffer_);
  buffer_.clear();
}

void AtomicFile::write_through(std::string_view content) {
  const char* p = content.data();
  size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error(fmt::format("{}: cannot write: {}", target_.string(), std::strerror(n < 0 ? errno : ENOSPC)));
    p += n;
    left -= static_cast<size_t>(n);
  }
}

void AtomicFile::write(std::string_view content) {
  if (content.size() >= (1u << 20)) {
    flush();
    write_through(content);
    return;
  }
  buffer_ += content;
  if (buffer_.size() >= (1u << 20)) flush();
}

void AtomicFile::commit() {
  flush();
  if (::fsync(fd_) != 0) throw std::runtime_error(fmt::format("{}: cannot write: {}", target_.string(), std::strerror(errno)));
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0 || std::rename(temporary_.c_str(), target_.c_str()) != 0) {
    const int err = errno;
    std::remove(temporary_.c_str());
    throw std::runtime_error(fmt::format("{}: cannot write: {}", target_.string(), std::strerror(err)));
  }
}

void write_file_atomic(const std::filesystem::path& path, std::string_view content) {
  AtomicFile file(path);
  file.write(content);
  file.commit();
}

void check_writable_directory(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  fs::path at = fs::absolute(dir).lexically_normal();
  std::error_code ec;
  while (!fs::exists(at, ec) && at.has_parent_path() && at != at.parent_path()) at = at.parent_path();
  if (!fs::is_directory(at, ec))
    throw std::runtime_error(fmt::format("{}: cannot create output directory: {} is not a directory", dir.string(), at.string()));
  if (::access(at.c_str(), W_OK | X_OK) != 0)
    throw std::runtime_error(fmt::format("{}: {} is not writable: {}", dir.string(), at.string(), std::strerror(errno)));
}

void check_replaceable_file(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || status.type() == std::filesystem::file_type::not_found || status.type() == std::filesystem::file_type::regular) return;
  throw std::runtime_error(fmt::format("{}: {} is there, where the output file goes: move it away or choose another --out", path.string(),
                                       std::filesystem::is_directory(status) ? "a directory" : "something other than a file"));
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
