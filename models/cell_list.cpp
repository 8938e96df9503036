#include "cell_list.hpp"

#include <algorithm>
#include <cmath>

namespace stepwise {

void CellList::build(const double* positions, int n, double cutoff) {
  cutoff_ = cutoff;
  const Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>> p(positions, 3, n);
  if (n == 0 || !p.allFinite()) {
    dims_ = {0, 0, 0};
    start_.assign(1, 0);
    order_.clear();
    sorted_.resize(3, 0);
    return;
  }
  const Eigen::Vector3d lo = p.rowwise().minCoeff(), extent = p.rowwise().maxCoeff() - lo;

  // cells of edge >= cutoff along every axis, grown until there are at most 2n + 8 of them
  const double max_cells = 2.0 * n + 8;
  double edge = cutoff;
  std::array<double, 3> d{};
  for (;;) {
    for (int a = 0; a < 3; ++a) d[a] = std::clamp(std::floor(extent[a] / edge), 1.0, max_cells);
    if (d[0] * d[1] * d[2] <= max_cells) break;
    edge *= 2;
  }
  Eigen::Vector3d inverse;  // cells per metre along each axis (the cells stretch to fill the box exactly)
  for (int a = 0; a < 3; ++a) {
    dims_[a] = static_cast<int>(d[a]);
    inverse[a] = extent[a] > 0 ? d[a] / extent[a] : 0;
  }

  std::vector<int> cell_of(static_cast<size_t>(n));
  start_.assign(static_cast<size_t>(cells()) + 1, 0);
  for (int i = 0; i < n; ++i) {
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(dims_[a] - 1, static_cast<int>((p(a, i) - lo[a]) * inverse[a]));
    cell_of[static_cast<size_t>(i)] = cell(c[0], c[1], c[2]);
    ++start_[static_cast<size_t>(cell_of[static_cast<size_t>(i)]) + 1];
  }
  for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  order_.resize(static_cast<size_t>(n));
  sorted_.resize(3, n);
  std::vector<int> next(start_.begin(), start_.end() - 1);
  for (int i = 0; i < n; ++i) {
    const int slot = next[static_cast<size_t>(cell_of[static_cast<size_t>(i)])]++;
    order_[static_cast<size_t>(slot)] = i;
    sorted_.col(slot) = p.col(i);
  }
}

}  // namespace stepwise
