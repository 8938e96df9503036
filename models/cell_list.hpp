// Short-range pairs of points through a uniform grid: a cell list (Allen & Tildesley, Computer Simulation
// of Liquids, 1987, section 5.3.2; Hockney & Eastwood 1981).
//
// The points' bounding box is cut into cells no smaller than the cut-off r_c along any axis, so two points
// closer than r_c lie in the same cell or in adjacent ones. Points are sorted by cell (a counting sort,
// positions copied in that order so a cell's points are contiguous), and each cell is paired with itself and
// its 13 "forward" neighbours (offsets lexicographically after (0, 0, 0)), so every pair is visited once.
// The work is O(N + cells + pairs within reach): never all pairs. When the points spread so far that cells
// of size r_c would outnumber 2N + 8, the cells grow (doubling) instead: still correct, only coarser.
#pragma once

#include <Eigen/Dense>

#include <array>
#include <vector>

namespace stepwise {

class CellList {
 public:
  // sorts n points given as x0 y0 z0 x1 y1 z1 ... into cells for the cut-off; a non-finite coordinate
  // leaves the list empty (a diverging state has no meaningful neighbours)
  void build(const double* positions, int n, double cutoff);

  // calls f(i, j, d, r2) once for every pair i != j with r2 = |d|^2 < cutoff^2, d = p_i - p_j
  template <class F>
  void for_each_pair(F&& f) const {
    const double c2 = cutoff_ * cutoff_;
    for (int cz = 0; cz < dims_[2]; ++cz)
      for (int cy = 0; cy < dims_[1]; ++cy)
        for (int cx = 0; cx < dims_[0]; ++cx) {
          const int a = cell(cx, cy, cz);
          const int a0 = start_[a], a1 = start_[a + 1];
          if (a0 == a1) continue;
          for (const auto& o : forward_offsets) {
            const int nx = cx + o[0], ny = cy + o[1], nz = cz + o[2];
            if (nx < 0 || ny < 0 || nz < 0 || nx >= dims_[0] || ny >= dims_[1] || nz >= dims_[2]) continue;
            const int b = cell(nx, ny, nz);
            const bool self = b == a;
            for (int p = a0; p < a1; ++p) {
              const Eigen::Vector3d pp = sorted_.col(p);
              for (int q = self ? p + 1 : start_[b]; q < start_[b + 1]; ++q) {
                const Eigen::Vector3d d = pp - sorted_.col(q);
                const double r2 = d.squaredNorm();
                if (r2 < c2) f(order_[p], order_[q], d, r2);
              }
            }
          }
        }
  }

  int cells() const { return dims_[0] * dims_[1] * dims_[2]; }

 private:
  // the cell itself, then the 13 neighbours after it in (z, y, x) order: each adjacent pair of cells once
  static constexpr std::array<std::array<int, 3>, 14> forward_offsets{{{0, 0, 0},
                                                                        {1, 0, 0},
                                                                        {-1, 1, 0},
                                                                        {0, 1, 0},
                                                                        {1, 1, 0},
                                                                        {-1, -1, 1},
                                                                        {0, -1, 1},
                                                                        {1, -1, 1},
                                                                        {-1, 0, 1},
                                                                        {0, 0, 1},
                                                                        {1, 0, 1},
                                                                        {-1, 1, 1},
                                                                        {0, 1, 1},
                                                                        {1, 1, 1}}};

  int cell(int x, int y, int z) const { return (z * dims_[1] + y) * dims_[0] + x; }

  double cutoff_ = 0;
  std::array<int, 3> dims_{0, 0, 0};
  std::vector<int> start_;                        // points of cell c: sorted_ columns start_[c] .. start_[c + 1]
  std::vector<int> order_;                        // original index of each sorted point
  Eigen::Matrix<double, 3, Eigen::Dynamic> sorted_;  // positions in cell order
};

// the same pairs by testing all n (n - 1) / 2 of them: the reference the cell list is tested against
template <class F>
void for_each_pair_brute_force(const double* positions, int n, double cutoff, F&& f) {
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const Eigen::Vector3d d = Eigen::Vector3d::Map(positions + 3 * i) - Eigen::Vector3d::Map(positions + 3 * j);
      const double r2 = d.squaredNorm();
      if (r2 < cutoff * cutoff) f(i, j, d, r2);
    }
}

}  // namespace stepwise
