// the package's version, as the installed library reports it (the CMake project's)
#include "stepwise/stepwise.hpp"

namespace stepwise {

std::string_view version() { return STEPWISE_VERSION; }

}  // namespace stepwise
