// Generated C source compiled once into a shared object, cached by the source's content hash in the user's cache
// directory, and loaded (the equations model's right-hand side and Jacobian, models/equations/).
//
// The cache: $STEPWISE_CACHE, else $XDG_CACHE_HOME/stepwise, else ~/.cache/stepwise (made 0700). The directory
// must be the user's own and writable by nobody else, or it is not used (a compiled object there would be code
// another user could replace). An entry is KEY.so and KEY.sum (the .so's size and hash, written after it); both
// are written to temporaries in the same directory and renamed, so two runs compiling the same source at once
// each rename a whole file over the other's. A file is loaded only after it is verified: a regular file (not a
// link) owned by this user and writable by nobody else, whose bytes (read from the descriptor that is then
// loaded) match its .sum; anything else is compiled anew. Temporaries carry their process's id
// (.tmp-PID-XXXXXX): those of a process that is gone are removed at the next compile.
//
// The compiler is `cc` (or $STEPWISE_CC: a program name or path, no arguments), started without a shell on the
// generated file; the user's text never reaches it except as that source. It runs in a process group of its
// own under a small guard process that dies with ours (PR_SET_PDEATHSIG) and then kills the whole group (the
// driver's cc1 and as with it): a stepwise killed by any signal leaves no compiler running. A compile has a
// time limit and can be cancelled; either kills the group.
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace stepwise {

class NativeCode {
 public:
  NativeCode(void* handle, std::string path, bool compiled) : handle_(handle), path_(std::move(path)), compiled_(compiled) {}
  ~NativeCode();
  NativeCode(const NativeCode&) = delete;
  NativeCode& operator=(const NativeCode&) = delete;
  // the address of an exported symbol, or null
  void* symbol(const char* name) const;
  const std::string& path() const { return path_; }  // the cache file it was loaded from
  bool compiled() const { return compiled_; }         // compiled by this call (else a verified cache entry)

 private:
  void* handle_;
  std::string path_;
  bool compiled_;
};

// C source in units: `common` opens each unit (includes, helpers, declarations); each unit is compiled apart,
// in parallel up to the machine's cores, and the objects linked into one shared object. One unit is compiled and
// linked in one call
struct NativeSource {
  std::string common;
  std::vector<std::string> units;
  std::string optimisation = "-O2";  // the compiler's -O flag (part of the cache key)
  size_t bytes() const;              // the C's size: common once per unit, and the units
};

// what a compile may take: past `seconds` of wall clock, or once `cancel` is set, the compiler's process group is
// killed and the compile fails saying which
struct CompileLimits {
  double seconds = 600;
  const std::atomic<bool>* cancel = nullptr;
};

// the object compiled from `source`, loaded from the cache or compiled into it first; null where it cannot be (no
// compiler, a compile error, the time limit, no usable cache directory), with the reason in `why`. The key it is
// filed under (a hash of the source, the compiler and its flags) is appended to the first unit as
// `const char stepwise_key[]` and checked after loading, so a file renamed into another's place is never used
std::shared_ptr<const NativeCode> load_native(const NativeSource& source, const CompileLimits& limits, std::string& why);
// the same for one unit with the default flags and limits
std::shared_ptr<const NativeCode> load_native(const std::string& source, std::string& why);
// `name` itself where it names a path, else the first executable of that name on PATH (the compiler here; the
// programs run/process starts)
std::optional<std::string> find_program(const std::string& name);

// only a verified entry already in the cache (or held by this process), never compiling: null if none
std::shared_ptr<const NativeCode> cached_native(const NativeSource& source);

}  // namespace stepwise
