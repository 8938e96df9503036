#include "water_optics.hpp"

#include <algorithm>
#include <cmath>

namespace stepwise::render {

Eigen::Matrix<double, Eigen::Dynamic, 3> height_field_normals(const Shapes::Water& water) {
  const int n = water.points;
  const double d = water.spacing;
  Eigen::Matrix<double, Eigen::Dynamic, 3> normals(static_cast<Eigen::Index>(n) * n, 3);
  const auto z = [&](int i, int j) { return water.z[static_cast<Eigen::Index>(i) * n + j]; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int j0 = std::max(j - 1, 0), j1 = std::min(j + 1, n - 1), i0 = std::max(i - 1, 0), i1 = std::min(i + 1, n - 1);
      const double dzdx = (z(i, j1) - z(i, j0)) / ((j1 - j0) * d), dzdy = (z(i1, j) - z(i0, j)) / ((i1 - i0) * d);
      normals.row(static_cast<Eigen::Index>(i) * n + j) = Eigen::Vector3d(-dzdx, -dzdy, 1).normalized().transpose();
    }
  return normals;
}

Eigen::Vector3d refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double index) {
  const double eta = 1 / index, cos_i = -n.dot(d);
  const double cos_t = std::sqrt(std::max(0.0, 1 - eta * eta * (1 - cos_i * cos_i)));
  return eta * d + (eta * cos_i - cos_t) * n;
}

double fresnel_transmittance(double cos_i, double index) {
  const double sin_t = std::sqrt(std::max(0.0, 1 - cos_i * cos_i)) / index;
  const double cos_t = std::sqrt(std::max(0.0, 1 - sin_t * sin_t));
  const double rs = (cos_i - index * cos_t) / (cos_i + index * cos_t), rp = (cos_t - index * cos_i) / (cos_t + index * cos_i);
  return 1 - (rs * rs + rp * rp) / 2;
}

const char* const glsl_fresnel = R"(
float fresnel_transmittance(float cos_i, float index) {
  float sin_t = sqrt(max(0.0, 1.0 - cos_i * cos_i)) / index;
  float cos_t = sqrt(max(0.0, 1.0 - sin_t * sin_t));
  float rs = (cos_i - index * cos_t) / (cos_i + index * cos_t), rp = (cos_t - index * cos_i) / (cos_t + index * cos_i);
  return 1.0 - (rs * rs + rp * rp) / 2.0;
}
)";

}  // namespace stepwise::render
