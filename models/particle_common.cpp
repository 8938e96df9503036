#include "particle_common.hpp"

#include "solvers/memory_budget.hpp"

#include <fmt/format.h>

#include <cmath>

namespace stepwise {

int particle_count(const Params& params, std::string_view key, double bytes_each, std::string_view what) {
  const double count = params.at(std::string(key));
  if (count != std::floor(count) || count < 1)
    throw BadParameter(std::string(key), fmt::format("parameter '{}' must be a whole number of {}, got {}", key, what, count));
  if (over_memory_budget(count * bytes_each) || count > 2e9)
    throw BadParameter(std::string(key), fmt::format("parameter '{}' = {:.0f} would not fit in memory: about {:.3g} GiB, {}", key, count,
                                                     count * bytes_each / 0x1p30, memory_budget_text()));
  return static_cast<int>(count);
}

std::pair<int, int> particle_grid(const Params& params, std::string_view rows, std::string_view columns, double bytes_each,
                                  std::string_view what) {
  const int r = particle_count(params, rows, bytes_each, what), c = particle_count(params, columns, bytes_each, what);
  const double count = static_cast<double>(r) * c;
  if (over_memory_budget(count * bytes_each) || count > 2e9)
    throw BadParameter(std::string(rows), fmt::format("parameters '{}' x '{}' = {:.0f} {} would not fit in memory: about {:.3g} GiB, {}", rows,
                                                      columns, count, what, count * bytes_each / 0x1p30, memory_budget_text()));
  return {r, c};
}

unsigned long particle_seed(const Params& params) {
  const double seed = params.at("seed");
  if (seed != std::floor(seed) || seed < 0 || seed > 9.007199254740992e15)
    throw BadParameter("seed", fmt::format("parameter 'seed' must be a whole number below 2^53, got {}", seed));
  return static_cast<unsigned long>(seed);
}

std::vector<Shapes::Ball> particle_balls(const Eigen::VectorXd& y, int n, bool trail) {
  std::vector<Shapes::Ball> balls(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) balls[static_cast<size_t>(i)] = Shapes::Ball{y.segment<3>(3 * i), 0, trail};
  return balls;
}

std::vector<std::string> particle_state_names(int n) {
  std::vector<std::string> names;
  for (const char* c : {"", "v"})
    for (int i = 0; i < n; ++i)
      for (const char* axis : {"x", "y", "z"}) names.push_back(fmt::format("{}{}[{}]", c, axis, i));
  return names;
}

double kinetic_and_gravity(const Eigen::VectorXd& y, double g) {
  const Eigen::Index n = y.size() / 6;
  double e = 0.5 * y.tail(3 * n).squaredNorm();
  for (Eigen::Index i = 0; i < n; ++i) e += g * y[3 * i + 2];
  return e;
}

}  // namespace stepwise
