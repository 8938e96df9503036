#include "blas_threads.hpp"

#include <dlfcn.h>

namespace stepwise {

void keep_blas_on_this_thread() {
  static const bool done = [] {
    using SetThreads = void (*)(int);
    if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(1);
    return true;
  }();
  (void)done;
}

}  // namespace stepwise
