// Fourier analysis on a periodic square: n x n real values (row-major, row i at y = i d, column j at
// x = j d, d = L / n) and their n x (n/2 + 1) complex modes (FFTW's real-to-complex layout: mode
// m = r (n/2 + 1) + c has wavenumbers kx = 2 pi c / L and ky = 2 pi r' / L, r' = r or r - n).
//
// The spectral operators the fluid model and `stable-fluids` share, each written here once:
//   derivative:  d/dx <-> i kx, d/dy <-> i ky (the Nyquist row and column have no derivative: zero)
//   Laplacian:   -|k|^2
//   2/3 rule:    keep modes with |c|, |r'| <= K = floor((n - 1) / 3), i.e. 3 K < n (Orszag): a product of two kept
//                fields has modes up to 2 K, which alias to 2 K - n < -K, onto dropped modes only. (K = n/3, where
//                n divides by 3, aliases onto the kept +-K: the inviscid energy drifted 3e-6 over the thin shear
//                layer's roll-up on 48^2, against 2e-12 on 64^2)
//   Leray:       P(a) = a - k (k . a) / |k|^2, the divergence-free part (the mean, k = 0, kept)
//
// FFTW's plans are made once per size, with FFTW_MEASURE (FFTW_ESTIMATE beyond 512^2), and kept for the process (its wisdom); every
// transform runs them on the caller's arrays (fftw_execute_dft_r2c/c2r: thread-safe).
#pragma once

#include <complex>
#include <string>
#include <vector>

namespace stepwise {

class PeriodicFft {
 public:
  using Complex = std::complex<double>;

  PeriodicFft(int n, double length);

  // FFTW's version ("fftw-3.3.10-sse2-avx"), for the record of what ran
  static std::string library_version();

  int n() const { return n_; }
  double length() const { return length_; }
  double spacing() const { return length_ / n_; }
  int points() const { return n_ * n_; }
  int modes() const { return n_ * half_; }
  double kx(int m) const { return k_[m % half_]; }
  double ky(int m) const { return k_row_[m / half_]; }
  // |k|^2 of the Laplacian (the Nyquist wavenumber n pi / L included)
  double k2(int m) const { return k2_col_[m % half_] + k2_row_[m / half_]; }
  // kept by the 2/3 rule
  bool kept(int m) const { return keep_[m / half_] && keep_[m % half_ + n_]; }
  // K, the largest whole wavenumber (in units of 2 pi / L) the 2/3 rule keeps on n points: floor((n - 1) / 3)
  static int largest_kept(int n) { return (n - 1) / 3; }

  // modes = FFT(grid), unnormalised
  void forward(const double* grid, Complex* modes) const;
  // grid = inverse FFT(modes) / n^2: the values whose forward() is `modes`. `modes` is overwritten
  void inverse(Complex* modes, double* grid) const;

  // the modes the 2/3 rule drops set to zero
  void dealias(Complex* a) const;
  // (u, v) <- P(u, v), the Leray projection
  void project(Complex* u, Complex* v) const;
  // d/dx and d/dy of one mode, and the divergence i (kx u + ky v)
  Complex d_dx(int m, Complex a) const { return Complex(0, kx(m)) * a; }
  Complex d_dy(int m, Complex a) const { return Complex(0, ky(m)) * a; }
  Complex divergence(int m, Complex u, Complex v) const { return d_dx(m, u) + d_dy(m, v); }
  // one implicit Euler step of a' = c Lap a (c = diffusivity x step): a^ <- a^ / (1 + c |k|^2)
  void diffuse(Complex* a, double c) const;

 private:
  int n_, half_;
  double length_;
  std::vector<double> k_, k_row_;  // kx by column (half_ entries), ky by row (n entries); Nyquist: 0
  std::vector<double> k2_col_, k2_row_;  // their squares, the Nyquist's included
  std::vector<char> keep_;         // by row (n entries), then by column (half_ entries)
  const void* plans_;              // the size's FFTW plans (periodic_fft.cpp)
};

}  // namespace stepwise
