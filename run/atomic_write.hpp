// Nothing half-written: files go to a temporary sibling and are renamed over the target. The temporary's name
// carries interrupt::temporary_tag(), so an interrupted run removes it and a run killed outright has it
// removed by the next (interrupt::remove_stale).
#pragma once

#include <filesystem>
#include <memory>
#include <string_view>

namespace stepwise {

namespace interrupt {
class Temporary;
}

// a file written in pieces (a trajectory streamed as it is computed) and renamed into place by commit();
// destroyed uncommitted, the temporary is removed. Errors throw std::runtime_error naming the target
class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  void write(std::string_view content);  // buffered
  void commit();                         // flush, fsync, rename over the target

 private:
  void flush();
  void write_through(std::string_view content);
  std::filesystem::path target_;
  std::string temporary_;
  std::unique_ptr<interrupt::Temporary> guard_;
  std::string buffer_;
  int fd_ = -1;
};

// write `content` to `path` through a temporary file in the same directory and rename(2), with the
// permissions a file created the usual way gets (default_mode(false)); throws std::runtime_error naming the
// path on failure
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

// 0666 (a file) or 0777 (a directory) less the process's umask: what mkstemp's 0600 and mkdtemp's 0700
// are widened to. The umask is read from /proc/self/status (setting it to read it would race with other
// threads creating files); 022 where that is unreadable
unsigned default_mode(bool directory);

// whether `dir` could be made and written, without making it: it is a writable directory, or its nearest
// existing ancestor is; throws std::runtime_error naming it otherwise
void check_writable_directory(const std::filesystem::path& dir);

// create `dir` if needed and prove it writable; throws std::runtime_error naming it otherwise
void ensure_writable_directory(const std::filesystem::path& dir);

// whether a file could be renamed over `path`: nothing is there, or a file (or a link to one); throws
// std::runtime_error naming it otherwise (a directory where trajectory.csv goes), before any work is done
void check_replaceable_file(const std::filesystem::path& path);

}  // namespace stepwise
