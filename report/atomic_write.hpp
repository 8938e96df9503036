// Nothing half-written: files go to a temporary sibling and are renamed over the target.
#pragma once

#include <filesystem>
#include <string_view>

namespace stepwise {

// write `content` to `path` through a temporary file in the same directory and rename(2);
// throws std::runtime_error naming the path on failure
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

// create `dir` if needed and prove it writable; throws std::runtime_error naming it otherwise
void ensure_writable_directory(const std::filesystem::path& dir);

}  // namespace stepwise
