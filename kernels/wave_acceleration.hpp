// The height field's acceleration (seeds: the wave equation with damping),
//   d2z/dt2 = c^2 (z_E + z_W + z_N + z_S - 4 z) / d^2 - mu dz/dt,
// at one interior cell of a row-major grid: the model's f (models/height_field.cpp), the float32 CPU
// reference of the second seed's scheme (verification/wave_modes.cpp) and the gpu-symplectic-euler shader
// (held to that reference bitwise by test_gpu_shader) share it, and the three-level scheme's cell
// (solvers/wave_step.hpp's wave_cell) sums the neighbours the same way.
#pragma once

#include <cstddef>

namespace stepwise {

// the four neighbours of cell j of a row-major grid with rows `n` apart, summed in one fixed order: the
// order every wave stencil keeps, so that they agree to the bit where they compute the same thing
template <class T>
inline T neighbour_sum(const T* u, std::ptrdiff_t j, std::ptrdiff_t n) {
  return (u[j - n] + u[j + n]) + (u[j - 1] + u[j + 1]);
}

// c^2 Lap z at a cell from the sum of its four neighbours, c2 = c^2 / d^2 (1/s^2)
template <class T>
inline T wave_laplacian(T c2, T neighbours, T z) {
  return c2 * (neighbours - 4 * z);
}

// dv/dt at a cell, c^2 Lap z - mu v, from the sum of its four neighbours
template <class T>
inline T wave_acceleration(T c2, T mu, T neighbours, T z, T v) {
  return wave_laplacian(c2, neighbours, z) - mu * v;
}

}  // namespace stepwise
