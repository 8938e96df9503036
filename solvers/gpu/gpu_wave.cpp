#include "gpu_wave.hpp"

#include "solvers/method.hpp"
#include "solvers/three_level_wave.hpp"

#include <fmt/format.h>

#include <cmath>
#include <vector>

namespace stepwise::gpu {

using gl::GlError;

namespace {

// what every grid pass shares: the state, its output, whether a texel is on the grid's boundary, and the
// sum of a texel's four neighbours in neighbour_sum's order. Texel (x, y) is cell i * points + j with
// x = j, y = i: rows (i) apart along y, as z[j -+ n] on the CPU
const char* const grid_pass = R"(#version 450
layout(binding = 0) uniform sampler2D state;
layout(location = 0) out vec4 next;
bool on_boundary(ivec2 p) {
  ivec2 size = textureSize(state, 0);
  return p.x == 0 || p.y == 0 || p.x == size.x - 1 || p.y == size.y - 1;
}
float neighbour_sum(ivec2 p) {
  precise float down_up = texelFetch(state, p - ivec2(0, 1), 0).r + texelFetch(state, p + ivec2(0, 1), 0).r;
  precise float left_right = texelFetch(state, p - ivec2(1, 0), 0).r + texelFetch(state, p + ivec2(1, 0), 0).r;
  precise float sum = down_up + left_right;
  return sum;
}
)";

// the three-level pass: R = z^k, G = z^{k-1} in, (z^{k+1}, z^k) out; the boundary holds
const char* const wave_pass = R"(
uniform float k_self, k_previous, k_neighbours;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 here = texelFetch(state, p, 0);
  if (on_boundary(p)) {
    next = vec4(here.r, here.r, 0.0, 0.0);
    return;
  }
  precise float sum = neighbour_sum(p);
  precise float a = k_self * here.r;
  precise float b = k_previous * here.g;
  precise float c = k_neighbours * sum;
  precise float z1 = (a + b) + c;
  next = vec4(z1, here.r, 0.0, 0.0);
}
)";

// the second seed's pass: v1 = v + dt a, a = c2 ((down + up) + (left + right) - 4 z) - mu v, z1 = z + dt v1
const char* const symplectic_pass = R"(
uniform float c2, mu, dt;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 here = texelFetch(state, p, 0);
  if (on_boundary(p)) {
    next = here;
    return;
  }
  precise float sum = neighbour_sum(p);
  precise float four_z = 4.0 * here.r;
  precise float curvature = sum - four_z;
  precise float spring = c2 * curvature;
  precise float drag = mu * here.g;
  precise float a = spring - drag;
  precise float kick = dt * a;
  precise float v1 = here.g + kick;
  precise float drift = dt * v1;
  precise float z1 = here.r + drift;
  next = vec4(z1, v1, 0.0, 0.0);
}
)";

}  // namespace

GpuWaveGrid::GpuWaveGrid(const Context& context, int points, const char* pass, const std::string& name)
    : GpuGrid(context, points, points, 1, std::string(grid_pass) + pass, name) {}

void GpuWaveGrid::upload_channels(const Eigen::VectorXf& red, const Eigen::VectorXf& green) {
  std::vector<float> texels(4 * static_cast<size_t>(red.size()));
  for (Eigen::Index c = 0; c < red.size(); ++c) {
    texels[4 * c] = red[c];
    texels[4 * c + 1] = green[c];
  }
  upload_plane(0, texels);
}

void GpuWaveGrid::download_channels(Eigen::VectorXf& red, Eigen::VectorXf& green) const {
  std::vector<float> texels;
  download_plane(0, texels);
  const Eigen::Index cells = static_cast<Eigen::Index>(texels.size() / 4);
  red.resize(cells);
  green.resize(cells);
  for (Eigen::Index c = 0; c < cells; ++c) {
    red[c] = texels[4 * c];
    green[c] = texels[4 * c + 1];
  }
}

GpuWave::GpuWave(const Context& context, int points, const BasicWaveCoefficients<float>& k) : GpuWaveGrid(context, points, wave_pass, "wave pass") {
  set_coefficients(k);
}

void GpuWave::set_coefficients(const BasicWaveCoefficients<float>& k) {
  uniform("k_self", k.self);
  uniform("k_previous", k.previous);
  uniform("k_neighbours", k.neighbours);
}

GpuSymplecticWave::GpuSymplecticWave(const Context& context, int points, float c2, float mu, float dt)
    : GpuWaveGrid(context, points, symplectic_pass, "symplectic wave pass") {
  uniform("c2", c2);
  uniform("mu", mu);
  set_step(dt);
}

void GpuSymplecticWave::set_step(float dt) { uniform("dt", dt); }

namespace {

// gpu-wave: the levels live on the GL device between steps; each step is one pass, and the new level is
// read back for the state the run samples (z^{k+1}, and the velocity from it on the CPU)
class GpuWaveStepper final : public ThreeLevelWaveStepper {
 public:
  using ThreeLevelWaveStepper::ThreeLevelWaveStepper;

 private:
  bool advance(const WaveCoefficients& k, const double* z_prev, const double* z, double* z_next, bool fresh, std::string& failure) override {
    const int n = grid().points;
    const Eigen::Index cells = static_cast<Eigen::Index>(n) * n;
    try {
      if (!context_) context_ = make_device_context();
      if (!gpu_) gpu_ = std::make_unique<GpuWave>(*context_, n, to_float(k));
      if (fresh) {
        gpu_->set_coefficients(to_float(k));
        gpu_->upload(Eigen::Map<const Eigen::VectorXd>(z_prev, cells).cast<float>(), Eigen::Map<const Eigen::VectorXd>(z, cells).cast<float>());
      }
      gpu_->step(1);
      gpu_->download(level_prev_, level_);
    } catch (const GlError& e) {
      failure = fmt::format("gpu-wave: {}", e.what());
      return false;
    }
    Eigen::Map<Eigen::VectorXd>(z_next, cells) = level_.cast<double>();
    return true;
  }
  std::unique_ptr<Context> context_;
  std::unique_ptr<GpuWave> gpu_;
  Eigen::VectorXf level_prev_, level_;
};

// gpu-symplectic-euler: (z, v) live on the device between steps that continue one another; each step is
// one pass, read back for the run's state
class GpuSymplecticStepper final : public FixedStepper {
 public:
  explicit GpuSymplecticStepper(const CountedSystem& s)
      : system_(s), grid_(*s.as<WaveGridView>()), cells_(static_cast<Eigen::Index>(grid_.points) * grid_.points) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    ++system_.stats().rhs_evals;
    const bool continuing = gpu_ && h == h_ && std::abs(t - t_last_) <= 1e-9 * h && y.data() == last_;
    try {
      if (!context_) context_ = make_device_context();
      if (!gpu_) {
        const double c2 = grid_.c * grid_.c / (grid_.spacing * grid_.spacing);
        gpu_ = std::make_unique<GpuSymplecticWave>(*context_, grid_.points, static_cast<float>(c2), static_cast<float>(grid_.mu), static_cast<float>(h));
      }
      if (!continuing) {
        gpu_->set_step(static_cast<float>(h));
        gpu_->upload(y.head(cells_).cast<float>(), y.tail(cells_).cast<float>());
      }
      gpu_->step(1);
      gpu_->download(z_, v_);
    } catch (const GlError& e) {
      failure = fmt::format("gpu-symplectic-euler: {}", e.what());
      return false;
    }
    y_next.head(cells_) = z_.cast<double>();
    y_next.tail(cells_) = v_.cast<double>();
    h_ = h;
    t_last_ = t + h;
    last_ = y_next.data();
    return true;
  }
  void reset() override { last_ = nullptr; }

 private:
  const CountedSystem& system_;
  WaveGridView grid_;
  Eigen::Index cells_;
  std::unique_ptr<Context> context_;
  std::unique_ptr<GpuSymplecticWave> gpu_;
  Eigen::VectorXf z_, v_;
  double h_ = 0, t_last_ = 0;
  const double* last_ = nullptr;  // the buffer the last step wrote
};

}  // namespace

void register_wave_methods(MethodTable& table) {
  table.add({
      .name = "gpu-wave",
      .family = "gpu",
      .source = "OpenGL shader",
      .description = "the seeds' three-level scheme as a fragment-shader pass on float32 textures (OpenGL: llvmpipe, or a GPU "
                     "through EGL), fixed step",
      .order = {2, 2, "2"},
      .stepping = Stepping::fixed,
      .needs = needs_wave_grid,
      .make = fixed_steps([](const CountedSystem& system) { return std::make_unique<GpuWaveStepper>(system); }),
      .stability = {.wave_dt = wave_stable_dt},
      .device_problem = device_problem,
  });
  table.add({
      .name = "gpu-symplectic-euler",
      .family = "gpu",
      .source = "OpenGL shader",
      .description = "the second seed's scheme, symplectic Euler with the damping explicit, as a fragment-shader pass on "
                     "float32 textures (OpenGL), fixed step",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .needs = needs_wave_grid,
      .make = fixed_steps([](const CountedSystem& system) { return std::make_unique<GpuSymplecticStepper>(system); }),
      .stability = {.wave_dt = symplectic_euler_wave_dt},
      .device_problem = device_problem,
  });
}

}  // namespace stepwise::gpu
