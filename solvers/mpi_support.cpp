#include "mpi_support.hpp"

#include <mpi.h>

#include <fmt/format.h>

#include <stdexcept>
#include <string_view>

namespace stepwise {

void mpi_check(int code, const char* call) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  throw std::runtime_error(fmt::format("{} failed with code {}: {}", call, code, std::string_view(text, static_cast<size_t>(length))));
}

}  // namespace stepwise
