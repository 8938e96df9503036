// Generated C source compiled once into a shared object, cached by the source's content hash in the user's cache
// directory, and loaded (the equations model's right-hand side and Jacobian, models/equations.cpp).
//
// The cache: $STEPWISE_CACHE, else $XDG_CACHE_HOME/stepwise, else ~/.cache/stepwise (made 0700). An entry is
// KEY.so and KEY.sum (the .so's size and hash, written after it); both are written to temporaries in the same
// directory and renamed, so two runs compiling the same source at once each rename a whole file over the other's.
// A file is loaded only after it is verified: a regular file owned by this user and writable by nobody else,
// whose bytes (read from the descriptor that is then loaded) match its .sum; anything else is compiled anew.
// The compiler is `cc` (or $STEPWISE_CC: a program name or path, no arguments), started without a shell on the
// generated file; the user's text never reaches it except as that source.
#pragma once

#include <memory>
#include <string>

namespace stepwise {

class NativeCode {
 public:
  NativeCode(void* handle, std::string path) : handle_(handle), path_(std::move(path)) {}
  ~NativeCode();
  NativeCode(const NativeCode&) = delete;
  NativeCode& operator=(const NativeCode&) = delete;
  // the address of an exported symbol, or null
  void* symbol(const char* name) const;
  const std::string& path() const { return path_; }  // the cache file it was loaded from

 private:
  void* handle_;
  std::string path_;
};

// the object compiled from `source` (C), loaded from the cache or compiled into it first; null where it cannot be
// (no compiler, a compile error, no cache directory), with the reason in `why`. The key it is filed under (a hash of
// the source, the compiler and its flags) is appended to the source as `const char stepwise_key[]` and checked
// after loading, so a file renamed into another's place is never used
std::shared_ptr<const NativeCode> load_native(const std::string& source, std::string& why);

}  // namespace stepwise
