// Nothing half-written: files go to a temporary sibling and are renamed over the target.
#pragma once

#include <filesystem>
#include <string_view>

namespace stepwise {

// write `content` to `path` through a temporary file in the same directory and rename(2), with the
// permissions a file created the usual way gets (default_mode(false)); throws std::runtime_error naming the
// path on failure
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

// 0666 (a file) or 0777 (a directory) less the process's umask: what mkstemp's 0600 and mkdtemp's 0700
// are widened to. The umask is read from /proc/self/status (setting it to read it would race with other
// threads creating files); 022 where that is unreadable
unsigned default_mode(bool directory);

// create `dir` if needed and prove it writable; throws std::runtime_error naming it otherwise
void ensure_writable_directory(const std::filesystem::path& dir);

}  // namespace stepwise
