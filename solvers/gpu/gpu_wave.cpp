#include "gpu_wave.hpp"

#include "solvers/method.hpp"
#include "solvers/three_level_wave.hpp"

#include <fmt/format.h>

#include <cmath>
#include <vector>

namespace stepwise::gpu {

using gl::GlError;

namespace {

// how a pass reaches the grid: its size, z at a cell (the red channel of the state), and its output. Cell
// (x, y) is i * points + j with x = j, y = i: rows (i) apart along y, as z[j -+ n] on the CPU. The fragment
// pass reads the state texture; the compute pass reads z from a tile in shared memory, the work group's
// 16 x 16 cells and a one-cell halo, loaded once (each z is read by five cells; TILED 0 reads the buffer). With
// STEPS > 1 the tile holds both channels of a 16 x 16 block with a halo of STEPS cells, twice (ping-pong in
// shared memory), and a dispatch takes up to STEPS steps on it, the region it gets right shrinking by a cell a
// step, before writing its 16 x 16 block: a block's cells are read from memory once every STEPS steps
const char* const fragment_access = R"(#version 450
layout(binding = 0) uniform sampler2D state;
layout(location = 0) out vec4 next;
ivec2 grid_size() { return textureSize(state, 0); }
float z_at(ivec2 p) { return texelFetch(state, p, 0).r; }
)";

const char* const compute_access = R"(
layout(std430, binding = 0) readonly buffer State { vec4 state[]; };
layout(std430, binding = 4) writeonly buffer Next { vec4 next[]; };
#if STEPS > 1
#define T (16 + 2 * STEPS)
shared vec2 levels[2][T][T];
uniform int pass_steps;
int level = 0;
ivec2 tile_origin() { return ivec2(gl_WorkGroupID.xy) * 16 - STEPS; }
float z_at(ivec2 p) {
  ivec2 t = p - tile_origin();
  return levels[level][t.y][t.x].x;
}
#else
shared float tile_z[18][18];
float z_at(ivec2 p) {
#if TILED
  ivec2 t = p - ivec2(gl_WorkGroupID.xy) * 16 + 1;
  return tile_z[t.y][t.x];
#else
  return state[p.y * size.x + p.x].r;
#endif
}
#endif
)";

// what every wave pass shares: whether a cell is on the grid's boundary, and the sum of its four neighbours
// in neighbour_sum's order
const char* const grid_cell = R"(
bool on_boundary(ivec2 p) {
  ivec2 size = grid_size();
  return p.x == 0 || p.y == 0 || p.x == size.x - 1 || p.y == size.y - 1;
}
float neighbour_sum(ivec2 p) {
  precise float down_up = z_at(p - ivec2(0, 1)) + z_at(p + ivec2(0, 1));
  precise float left_right = z_at(p - ivec2(1, 0)) + z_at(p + ivec2(1, 0));
  precise float sum = down_up + left_right;
  return sum;
}
)";

// the passes' main: the fragment pass's cell is its pixel's; the compute pass's invocation loads its share of
// the tile (324 values by 256 invocations; a halo cell past the grid is clamped in: only a boundary cell, which
// holds, would read it), waits for the rest, and steps its cell if it is on the grid
const char* const fragment_main = R"(
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  next = step_cell(p, texelFetch(state, p, 0));
}
)";

const char* const compute_main = R"(
#if STEPS > 1
void main() {
  ivec2 origin = tile_origin();
  for (uint k = gl_LocalInvocationIndex; k < uint(T * T); k += 256u) {
    ivec2 t = ivec2(int(k % uint(T)), int(k / uint(T)));
    ivec2 q = clamp(origin + t, ivec2(0), size - 1);
    levels[0][t.y][t.x] = state[q.y * size.x + q.x].rg;
  }
  memoryBarrierShared();
  barrier();
  for (int s = 1; s <= pass_steps; ++s) {
    for (uint k = gl_LocalInvocationIndex; k < uint(T * T); k += 256u) {
      ivec2 t = ivec2(int(k % uint(T)), int(k / uint(T)));
      ivec2 p = origin + t;
      vec2 here = levels[level][t.y][t.x];
      bool inner = all(greaterThanEqual(t, ivec2(s))) && all(lessThan(t, ivec2(T - s)));
      bool on_grid = all(greaterThanEqual(p, ivec2(0))) && all(lessThan(p, size));
      levels[1 - level][t.y][t.x] = inner && on_grid ? step_cell(p, vec4(here, 0.0, 0.0)).rg : here;
    }
    memoryBarrierShared();
    barrier();
    level = 1 - level;
  }
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= size.x || p.y >= size.y) return;
  ivec2 t = p - origin;
  next[p.y * size.x + p.x] = vec4(levels[level][t.y][t.x], 0.0, 0.0);
}
#else
void main() {
#if TILED
  ivec2 origin = ivec2(gl_WorkGroupID.xy) * 16 - 1;
  for (uint k = gl_LocalInvocationIndex; k < 18u * 18u; k += 256u) {
    ivec2 t = ivec2(int(k % 18u), int(k / 18u));
    ivec2 q = clamp(origin + t, ivec2(0), size - 1);
    tile_z[t.y][t.x] = state[q.y * size.x + q.x].r;
  }
  memoryBarrierShared();
  barrier();
#endif
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= size.x || p.y >= size.y) return;
  int i = p.y * size.x + p.x;
  next[i] = step_cell(p, state[i]);
}
#endif
)";

// the three-level step of a cell: R = z^k, G = z^{k-1} in, (z^{k+1}, z^k) out; the boundary holds
const char* const wave_cell = R"(
uniform float k_self, k_previous, k_neighbours;
vec4 step_cell(ivec2 p, vec4 here) {
  if (on_boundary(p)) return vec4(here.r, here.r, 0.0, 0.0);
  precise float sum = neighbour_sum(p);
  precise float a = k_self * here.r;
  precise float b = k_previous * here.g;
  precise float c = k_neighbours * sum;
  precise float z1 = (a + b) + c;
  return vec4(z1, here.r, 0.0, 0.0);
}
)";

// the second seed's step of a cell: v1 = v + dt a, a = c2 ((down + up) + (left + right) - 4 z) - mu v, z1 = z + dt v1
const char* const symplectic_cell = R"(
uniform float c2, mu, dt;
vec4 step_cell(ivec2 p, vec4 here) {
  if (on_boundary(p)) return here;
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
  return vec4(z1, v1, 0.0, 0.0);
}
)";

// a wave pass's GLSL: the access of its kind, the shared cell functions, the scheme's step, the kind's main
std::string wave_source(Pass pass, const char* cell, Tiling tiling) {
  if (pass == Pass::fragment) return std::string(fragment_access) + grid_cell + cell + fragment_main;
  return compute_prelude() + fmt::format("#define TILED {}\n#define STEPS {}\n", tiling == Tiling::none ? 0 : 1, steps_per_dispatch(tiling)) +
         compute_access + grid_cell + cell + compute_main;
}

}  // namespace

int steps_per_dispatch(Tiling tiling) { return tiling == Tiling::four_steps ? 4 : 1; }

GpuWaveGrid::GpuWaveGrid(const Context& context, int points, Pass pass, const char* cell, const std::string& name, Tiling tiling)
    : GpuGrid(context, points, points, 1, pass, wave_source(pass, cell, tiling), name, pass == Pass::compute ? steps_per_dispatch(tiling) : 1) {}

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

GpuWave::GpuWave(const Context& context, int points, const BasicWaveCoefficients<float>& k, Pass pass, Tiling tiling)
    : GpuWaveGrid(context, points, pass, wave_cell, pass == Pass::fragment ? "wave pass" : "wave compute pass", tiling) {
  set_coefficients(k);
}

void GpuWave::set_coefficients(const BasicWaveCoefficients<float>& k) {
  uniform("k_self", k.self);
  uniform("k_previous", k.previous);
  uniform("k_neighbours", k.neighbours);
}

GpuSymplecticWave::GpuSymplecticWave(const Context& context, int points, float c2, float mu, float dt, Pass pass, Tiling tiling)
    : GpuWaveGrid(context, points, pass, symplectic_cell, pass == Pass::fragment ? "symplectic wave pass" : "symplectic wave compute pass", tiling) {
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
  GpuWaveStepper(const CountedSystem& s, Pass pass, std::string_view name) : ThreeLevelWaveStepper(s), pass_(pass), name_(name) {}

 private:
  bool advance(const WaveCoefficients& k, const double* z_prev, const double* z, double* z_next, bool fresh, std::string& failure) override {
    const int n = grid().points;
    const Eigen::Index cells = static_cast<Eigen::Index>(n) * n;
    try {
      if (!context_) context_ = make_device_context();
      if (!gpu_) gpu_ = std::make_unique<GpuWave>(*context_, n, to_float(k), pass_);
      if (fresh) {
        gpu_->set_coefficients(to_float(k));
        gpu_->upload(Eigen::Map<const Eigen::VectorXd>(z_prev, cells).cast<float>(), Eigen::Map<const Eigen::VectorXd>(z, cells).cast<float>());
      }
      gpu_->step(1);
      gpu_->download(level_prev_, level_);
    } catch (const GlError& e) {
      failure = fmt::format("{}: {}", name_, e.what());
      return false;
    }
    Eigen::Map<Eigen::VectorXd>(z_next, cells) = level_.cast<double>();
    return true;
  }
  Pass pass_;
  std::string_view name_;
  std::unique_ptr<Context> context_;
  std::unique_ptr<GpuWave> gpu_;
  Eigen::VectorXf level_prev_, level_;
};

// gpu-symplectic-euler: (z, v) live on the device between steps that continue one another; each step is
// one pass, read back for the run's state
class GpuSymplecticStepper final : public FixedStepper {
 public:
  GpuSymplecticStepper(const CountedSystem& s, Pass pass, std::string_view name)
      : system_(s), grid_(*s.as<WaveGridView>()), cells_(static_cast<Eigen::Index>(grid_.points) * grid_.points), pass_(pass), name_(name) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    ++system_.stats().rhs_evals;
    const bool continuing = gpu_ && h == h_ && std::abs(t - t_last_) <= 1e-9 * h && y.data() == last_;
    try {
      if (!context_) context_ = make_device_context();
      if (!gpu_) {
        const double c2 = grid_.c * grid_.c / (grid_.spacing * grid_.spacing);
        gpu_ = std::make_unique<GpuSymplecticWave>(*context_, grid_.points, static_cast<float>(c2), static_cast<float>(grid_.mu), static_cast<float>(h), pass_);
      }
      if (!continuing) {
        gpu_->set_step(static_cast<float>(h));
        gpu_->upload(y.head(cells_).cast<float>(), y.tail(cells_).cast<float>());
      }
      gpu_->step(1);
      gpu_->download(z_, v_);
    } catch (const GlError& e) {
      failure = fmt::format("{}: {}", name_, e.what());
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
  Pass pass_;
  std::string_view name_;
  std::unique_ptr<Context> context_;
  std::unique_ptr<GpuSymplecticWave> gpu_;
  Eigen::VectorXf z_, v_;
  double h_ = 0, t_last_ = 0;
  const double* last_ = nullptr;  // the buffer the last step wrote
};

}  // namespace

void register_wave_methods(MethodTable& table) {
  add_shader_methods(table, {"gpu-wave", "gpu-wave-compute",
                             "the seeds' three-level scheme as a fragment-shader pass on float32 textures (OpenGL: llvmpipe, or a GPU "
                             "through EGL), fixed step",
                             "gpu-wave as an OpenGL 4.3 compute pass on float32 storage buffers, 16 x 16 work "
                             "groups sharing a tile of z (the same bits), fixed step",
                             {2, 2, "2"}, needs_wave_grid, {.wave_dt = wave_stable_dt},
                             [](const CountedSystem& system, Pass pass, std::string_view name) {
                               return std::make_unique<GpuWaveStepper>(system, pass, name);
                             }});
  add_shader_methods(table, {"gpu-symplectic-euler", "gpu-symplectic-euler-compute",
                             "the second seed's scheme, symplectic Euler with the damping explicit, as a fragment-shader pass on "
                             "float32 textures (OpenGL), fixed step",
                             "gpu-symplectic-euler as an OpenGL 4.3 compute pass on float32 "
                             "storage buffers, 16 x 16 work groups sharing a tile of z (the same bits), fixed step",
                             {1, 1, "1"}, needs_wave_grid, {.wave_dt = symplectic_euler_wave_dt},
                             [](const CountedSystem& system, Pass pass, std::string_view name) {
                               return std::make_unique<GpuSymplecticStepper>(system, pass, name);
                             }});
}

}  // namespace stepwise::gpu
