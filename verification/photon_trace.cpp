#include "photon_trace.hpp"

#include "render/water_optics.hpp"

#include <cmath>
#include <random>

namespace stepwise {

PhotonTrace trace_photons(const Shapes::Water& water, const Eigen::Vector3d& light, double depth, int bins, long rays,
                          std::uint64_t seed) {
  const int n = water.points;
  const double d = water.spacing, side = (n - 1) * d;
  const Eigen::Vector3d l = light.normalized();
  const auto normals = render::height_field_normals(water);
  const auto node = [&](int i, int j) { return Eigen::Vector3d(j * d, i * d, water.z[static_cast<Eigen::Index>(i) * n + j]); };
  const auto normal = [&](int i, int j) { return Eigen::Vector3d(normals.row(static_cast<Eigen::Index>(i) * n + j).transpose()); };

  std::vector<double> sum(static_cast<size_t>(bins) * bins, 0.0), sum2(sum.size(), 0.0);
  std::mt19937_64 rng(seed);
  const auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  for (long r = 0; r < rays; ++r) {
    const double x = uniform() * side, y = uniform() * side;
    const int j = std::min(static_cast<int>(x / d), n - 2), i = std::min(static_cast<int>(y / d), n - 2);
    const double u = x / d - j, v = y / d - i;
    // the cell's two triangles as the photon map draws them: (00, 01, 11) below the diagonal u = v, (00, 11, 10) above
    Eigen::Vector3d p[3], q[3];
    double w[3];
    if (u >= v) {
      p[0] = node(i, j), p[1] = node(i, j + 1), p[2] = node(i + 1, j + 1);
      q[0] = normal(i, j), q[1] = normal(i, j + 1), q[2] = normal(i + 1, j + 1);
      w[0] = 1 - u, w[1] = u - v, w[2] = v;
    } else {
      p[0] = node(i, j), p[1] = node(i + 1, j + 1), p[2] = node(i + 1, j);
      q[0] = normal(i, j), q[1] = normal(i + 1, j + 1), q[2] = normal(i + 1, j);
      w[0] = 1 - v, w[1] = u, w[2] = v - u;
    }
    Eigen::Vector3d face = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
    if (face.z() < 0) face = -face;
    const double cos_i = face.dot(l);
    if (cos_i <= 0) continue;
    const Eigen::Vector3d point = w[0] * p[0] + w[1] * p[1] + w[2] * p[2];
    const Eigen::Vector3d shading = (w[0] * q[0] + w[1] * q[1] + w[2] * q[2]).normalized();
    const Eigen::Vector3d t = render::refract(-l, shading, render::water_index);
    const Eigen::Vector3d hit = point + t * ((-depth - point.z()) / t.z());
    const int bx = static_cast<int>(std::floor(hit.x() / side * bins)), by = static_cast<int>(std::floor(hit.y() / side * bins));
    if (bx < 0 || by < 0 || bx >= bins || by >= bins) continue;
    const double power = cos_i / face.z() * render::fresnel_transmittance(cos_i, render::water_index);
    sum[static_cast<size_t>(by) * bins + bx] += power;
    sum2[static_cast<size_t>(by) * bins + bx] += power * power;
  }
  // each ray stands for side^2 / rays of the surface's horizontal area; a bin has area (side / bins)^2
  PhotonTrace trace{bins, std::vector<double>(sum.size()), std::vector<double>(sum.size())};
  const double scale = static_cast<double>(bins) * bins / static_cast<double>(rays);
  for (size_t b = 0; b < sum.size(); ++b) {
    trace.irradiance[b] = sum[b] * scale;
    // the bin's tally is a sum of rays i.i.d. power X_b (0 when the ray lands elsewhere): var = N (E X^2 - (E X)^2)
    const double mean = sum[b] / static_cast<double>(rays), mean2 = sum2[b] / static_cast<double>(rays);
    trace.sigma[b] = std::sqrt(std::max(0.0, (mean2 - mean * mean) / static_cast<double>(rays))) * static_cast<double>(bins) * bins;
  }
  return trace;
}

}  // namespace stepwise
