// Observed order of convergence: the least-squares slope of log(error) against log(dt).
#pragma once

#include <span>

namespace stepwise {

// slope of the least-squares line through (log x_i, log y_i); x and y positive, same length >= 2
double loglog_slope(std::span<const double> x, std::span<const double> y);

}  // namespace stepwise
