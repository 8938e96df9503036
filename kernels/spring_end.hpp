// The seeds' spring (kernels/spring_force.hpp) seen from one of its ends, as a per-node solver reads it (vbd): r the
// vector from this end to the other, l its rest length, c its stiffness,
//   energy      c (|r| - l)^2 / 2
//   force       c (|r| - l) u on this end,   u = r / |r|   (spring_force's elastic part, at zero closing speed)
//   stiffness   c u u^T + c (1 - l / |r|) (I - u u^T)      (dF/dr: minus the force's derivative by this end's place;
//               definite: the transverse part clamped at zero where the spring is compressed, Choi & Ko's remedy)
// and the energy's change when this end moves by d (r becomes r - d), written as a difference,
//   c / 2 (L' - L) (L' + L - 2 l),   L' - L = (|d|^2 - 2 r.d) / (L' + L),
// so that the last sweeps' small decreases are not lost in the energies' round-off. The mass-spring models
// (models/springs.cpp) and vbd's sweep over a network of springs (solvers/vertex_block_descent.cpp) share it; the
// gpu-vbd-compute shader writes the same lines in GLSL. D: 2 (in the plane) or 3.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>

namespace stepwise {

template <int D>
using SpringVector = Eigen::Matrix<double, D, 1>;
template <int D>
using SpringBlock = Eigen::Matrix<double, D, D>;

// a symmetric D x D sum kept as its lower triangle's entries, column by column ((0, 0), (1, 0), .., (D - 1, 0), (1, 1),
// ..): scalars a compiler keeps in registers (an Eigen block summed in place was stored and read back in halves, and
// stalled a sweep's store forwarding)
template <int D>
struct LowerSum {
  std::array<double, D*(D + 1) / 2> entry{};
  SpringBlock<D> full() const {
    SpringBlock<D> m;
    for (int j = 0, k = 0; j < D; ++j)
      for (int i = j; i < D; ++i, ++k) m(i, j) = m(j, i) = entry[static_cast<size_t>(k)];
    return m;
  }
};

// the stiffness block dF/dr of a spring along u, c t I + c (1 - t) u u^T, t = 1 - l / |r| (the transverse part;
// definite: at least zero), added into `sum`
template <int D>
inline void add_spring_stiffness(const SpringVector<D>& u, double rest_over_length, double stiffness, bool definite, LowerSum<D>& sum) {
  const double transverse = definite ? std::max(0.0, 1 - rest_over_length) : 1 - rest_over_length;
  const double along = stiffness * (1 - transverse), across = stiffness * transverse;
  for (int j = 0, k = 0; j < D; ++j)
    for (int i = j; i < D; ++i, ++k) {
      sum.entry[static_cast<size_t>(k)] += along * u[i] * u[j];
      if (i == j) sum.entry[static_cast<size_t>(k)] += across;
    }
}
// the whole block
template <int D>
inline SpringBlock<D> spring_stiffness(const SpringVector<D>& u, double length, double rest, double stiffness, bool definite) {
  LowerSum<D> sum;
  add_spring_stiffness<D>(u, rest / length, stiffness, definite, sum);
  return sum.full();
}

// this end's energy
template <int D>
inline double spring_end_energy(const SpringVector<D>& r, double rest, double stiffness) {
  const double stretch = r.norm() - rest;
  return stiffness * stretch * stretch / 2;
}

// this end's force and stiffness block added into the sums given (length = |r|)
template <int D>
inline void add_spring_end(const SpringVector<D>& r, double length, double rest, double stiffness, bool definite, SpringVector<D>& force,
                           LowerSum<D>& block) {
  const double inverse = 1 / length;
  const SpringVector<D> u = r * inverse;
  force += (stiffness * (length - rest)) * u;
  add_spring_stiffness<D>(u, rest * inverse, stiffness, definite, block);
}

// the energy's change when this end moves by d (length = |r|)
template <int D>
inline double spring_end_change(const SpringVector<D>& r, double length, const SpringVector<D>& d, double rest, double stiffness) {
  const double moved = (r - d).norm();
  const double lengthening = (d.squaredNorm() - 2 * r.dot(d)) / (moved + length);
  return stiffness / 2 * lengthening * (moved + length - 2 * rest);
}

}  // namespace stepwise
