// The weight of stage i in an embedded pair's interpolant, y(t0 + theta h) = y0 + h sum_i b_i(theta) k_i,
// from the tableau's coefficients in powers of theta - 1/2 (T::w, degree T::dense_degree), by Horner's rule.
#pragma once

namespace stepwise::tableau {

template <class T>
constexpr double dense_weight(int i, double theta) {
  double p = 0;
  for (int d = T::dense_degree; d >= 0; --d) p = p * (theta - 0.5) + T::w[i][d];
  return p;
}

}  // namespace stepwise::tableau
