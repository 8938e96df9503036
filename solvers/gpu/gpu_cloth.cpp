#include "gpu_cloth.hpp"

#include "solvers/fixed_step.hpp"
#include "solvers/stability.hpp"
#include "solvers/run_support.hpp"

#include <fmt/format.h>

#include <memory>

namespace stepwise::gpu {

using gl::GlError;

namespace {

// cloth_grid.hpp's step in GLSL: the same operations in the same order, every one `precise`. Texel (x, y)
// is node (row y, column x); the tables are cloth_grid.hpp's with (row, column) offsets written (x, y)
// how a pass reaches the grid: its size, a node's position (w = 1 where pinned) and velocity, and its outputs
const char* const cloth_fragment_access = R"(#version 450
layout(binding = 0) uniform sampler2D positions;
layout(binding = 1) uniform sampler2D velocities;
layout(location = 0) out vec4 x_next;
layout(location = 1) out vec4 v_next;
ivec2 grid_size() { return textureSize(positions, 0); }
vec4 position_at(ivec2 q) { return texelFetch(positions, q, 0); }
vec3 v_at(ivec2 q) { return texelFetch(velocities, q, 0).xyz; }
)";

const char* const cloth_compute_access = R"(
layout(std430, binding = 0) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = 1) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = 4) writeonly buffer NextPositions { vec4 x_next[]; };
layout(std430, binding = 5) writeonly buffer NextVelocities { vec4 v_next[]; };
vec4 position_at(ivec2 q) { return positions[q.y * size.x + q.x]; }
vec3 v_at(ivec2 q) { return velocities[q.y * size.x + q.x].xyz; }
)";

const char* const cloth_fragment_main = R"(
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  step_node(p, x_next, v_next);
}
)";

const char* const cloth_compute_main = R"(
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= size.x || p.y >= size.y) return;
  int i = p.y * size.x + p.x;
  vec4 x1, v1;
  step_node(p, x1, v1);
  x_next[i] = x1;
  v_next[i] = v1;
}
)";

const char* const cloth_node = R"(
uniform float rest[5];
uniform float stiffness[3];
uniform int family_on[3];
uniform float damping, node_mass, drag, g, wind_coefficient, h;
uniform vec3 wind, pick_force;
uniform ivec2 picked;
uniform float sphere_radius;
uniform vec3 sphere_centre;
uniform int ground;
uniform float ground_y, friction;

// (column offset, row offset, family, rest length)
const ivec4 neighbours[12] = ivec4[12](ivec4(1, 0, 0, 0), ivec4(0, 1, 0, 1), ivec4(-1, 0, 0, 0), ivec4(0, -1, 0, 1),
                                       ivec4(1, 1, 1, 2), ivec4(-1, 1, 1, 2), ivec4(-1, -1, 1, 2), ivec4(1, -1, 1, 2),
                                       ivec4(2, 0, 2, 3), ivec4(0, 2, 2, 4), ivec4(-2, 0, 2, 3), ivec4(0, -2, 2, 4));
// (cell column offset, cell row offset, which of its triangles)
const ivec3 triangles[6] = ivec3[6](ivec3(-1, -1, 1), ivec3(0, -1, 0), ivec3(0, -1, 1), ivec3(-1, 0, 0), ivec3(-1, 0, 1), ivec3(0, 0, 0));

float dot3(vec3 a, vec3 b) {
  precise float d = (a.x * b.x + a.y * b.y) + a.z * b.z;
  return d;
}
float norm3(vec3 a) {
  precise float n = sqrt(dot3(a, a));
  return n;
}
vec3 cross3(vec3 a, vec3 b) {
  precise vec3 c = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
  return c;
}
bool inside(ivec2 q) { return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, grid_size())); }
vec3 x_at(ivec2 q) { return position_at(q).xyz; }

vec3 spring_force(vec3 x, vec3 v, vec3 xq, vec3 vq, float rest_length, float c) {
  precise vec3 r = xq - x;
  precise float len = norm3(r);
  precise vec3 u = r / len;
  precise float magnitude = c * (len - rest_length) + damping * dot3(u, vq - v);
  precise vec3 f = magnitude * u;
  return f;
}

vec3 wind_share(ivec2 a, ivec2 b, ivec2 c) {
  precise vec3 xa = x_at(a);
  precise vec3 n = 0.5 * cross3(x_at(b) - xa, x_at(c) - xa);
  precise vec3 mean = ((v_at(a) + v_at(b)) + v_at(c)) / 3.0;
  precise float flow = wind_coefficient * dot3(wind - mean, n);
  precise vec3 share = (flow * n) / (3.0 * norm3(n));
  return share;
}

vec3 stop_approach(vec3 v, vec3 n) {
  precise float vn = dot3(v, n);
  precise vec3 tangential = v - vn * n;
  precise float speed = norm3(tangential);
  precise float kept = speed > 0.0 ? max(0.0, speed - friction * abs(vn)) / speed : 0.0;
  precise vec3 stopped = kept * tangential;
  return stopped;
}

void step_node(ivec2 p, out vec4 x_out, out vec4 v_out) {
  vec4 here = position_at(p);
  precise vec3 x = here.xyz;
  precise vec3 v = v_at(p);
  if (here.w != 0.0) {
    x_out = here;
    v_out = vec4(v, 0.0);
    return;
  }
  precise vec3 f = vec3(0.0);
  for (int i = 0; i < 12; ++i) {
    ivec4 n = neighbours[i];
    ivec2 q = p + n.xy;
    if (family_on[n.z] != 0 && inside(q)) f = f + spring_force(x, v, x_at(q), v_at(q), rest[n.w], stiffness[n.z]);
  }
  if (wind_coefficient != 0.0)
    for (int i = 0; i < 6; ++i) {
      ivec2 cell = p + triangles[i].xy;
      if (!inside(cell) || !inside(cell + ivec2(1))) continue;
      if (triangles[i].z == 0) f = f + wind_share(cell, cell + ivec2(0, 1), cell + ivec2(1, 0));
      else f = f + wind_share(cell + ivec2(0, 1), cell + ivec2(1, 1), cell + ivec2(1, 0));
    }
  if (p == picked) f = f + pick_force;
  precise vec3 a = f / node_mass - drag * v;
  a.y = a.y - g;
  precise vec3 v1 = v + h * a;
  precise vec3 x1 = x + h * v1;
  if (sphere_radius > 0.0) {
    precise vec3 offset = x1 - sphere_centre;
    precise float distance = norm3(offset);
    if (distance < sphere_radius && distance > 0.0) {
      precise vec3 n = offset / distance;
      x1 = sphere_centre + sphere_radius * n;
      if (dot3(v1, n) < 0.0) v1 = stop_approach(v1, n);
    }
  }
  if (ground != 0 && x1.y < ground_y) {
    x1.y = ground_y;
    if (v1.y < 0.0) v1 = stop_approach(v1, vec3(0.0, 1.0, 0.0));
  }
  x_out = vec4(x1, 0.0);
  v_out = vec4(v1, 0.0);
}
)";

}  // namespace

namespace {

std::string cloth_source(Pass pass) {
  return pass == Pass::fragment ? std::string(cloth_fragment_access) + cloth_node + cloth_fragment_main : compute_prelude() + cloth_compute_access + cloth_node + cloth_compute_main;
}

}  // namespace

GpuCloth::GpuCloth(const Context& context, const ClothGridView& view, Pass pass)
    : GpuGrid(context, view.columns, view.rows, 2, pass, cloth_source(pass), pass == Pass::fragment ? "cloth pass" : "cloth compute pass"),
      pinned_(view.free_index.size()) {
  for (size_t k = 0; k < pinned_.size(); ++k) pinned_[k] = view.free_index[k] < 0 ? 1.0f : 0.0f;
}

void GpuCloth::set_constants(const cloth_grid::Constants<float>& k) {
  const unsigned program = use_program();
  const auto at = [&](const char* name) { return gl().GetUniformLocation(program, name); };
  const int on[3] = {k.on[0], k.on[1], k.on[2]};
  gl().Uniform1fv(at("rest"), 5, k.rest.data());
  gl().Uniform1fv(at("stiffness"), 3, k.stiffness.data());
  gl().Uniform1iv(at("family_on"), 3, on);
  for (const auto& [name, value] : {std::pair{"damping", k.damping}, {"node_mass", k.node_mass}, {"drag", k.drag}, {"g", k.g},
                                    {"wind_coefficient", k.wind_coefficient}, {"h", k.h}, {"sphere_radius", k.sphere_radius},
                                    {"ground_y", k.ground_y}, {"friction", k.friction}})
    gl().Uniform1f(at(name), value);
  for (const auto& [name, value] : {std::pair{"wind", k.wind}, {"pick_force", k.pick_force}, {"sphere_centre", k.sphere_centre}}) {
    const float v[3] = {value.x, value.y, value.z};
    gl().Uniform3fv(at(name), 1, v);
  }
  gl().Uniform2i(at("picked"), k.picked < 0 ? -1 : k.picked % k.columns, k.picked < 0 ? -1 : k.picked / k.columns);
  gl().Uniform1i(at("ground"), k.ground ? 1 : 0);
}

void GpuCloth::upload(const cloth_grid::State<float>& s) {
  std::vector<float> x(4 * s.x.size()), v(4 * s.v.size());
  for (size_t k = 0; k < s.x.size(); ++k) {
    x[4 * k] = s.x[k].x, x[4 * k + 1] = s.x[k].y, x[4 * k + 2] = s.x[k].z, x[4 * k + 3] = pinned_[k];
    v[4 * k] = s.v[k].x, v[4 * k + 1] = s.v[k].y, v[4 * k + 2] = s.v[k].z;
  }
  upload_plane(0, x);
  upload_plane(1, v);
}

void GpuCloth::download(cloth_grid::State<float>& s) const {
  std::vector<float> x, v;
  download_plane(0, x);
  download_plane(1, v);
  const size_t nodes = x.size() / 4;
  s.x.resize(nodes);
  s.v.resize(nodes);
  for (size_t k = 0; k < nodes; ++k) {
    s.x[k] = {x[4 * k], x[4 * k + 1], x[4 * k + 2]};
    s.v[k] = {v[4 * k], v[4 * k + 1], v[4 * k + 2]};
  }
}

namespace {

// gpu-cloth: the state lives on the device between steps; each step is one pass, read back for the run's
// state. The device's state is uploaded afresh whenever the run's y is not what the last step read back (the
// first step, an obstacle's projection on the CPU changing a node by a rounding, an event)
class GpuClothStepper final : public FixedStepper {
 public:
  GpuClothStepper(const CountedSystem& s, Pass pass, std::string_view name) : system_(s), view_(*s.as<ClothGridView>()), pass_(pass), name_(name) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    ++system_.stats().rhs_evals;
    try {
      if (!context_) context_ = make_device_context();
      if (!gpu_) gpu_ = std::make_unique<GpuCloth>(*context_, view_, pass_);
      if (!read_back(y)) gpu_->upload(cloth_grid::spread<float>(view_, y));
      gpu_->set_constants(cloth_grid::constants<float>(view_, t, h));
      gpu_->step(1);
      gpu_->download(state_);
    } catch (const GlError& e) {
      failure = fmt::format("{}: {}", name_, e.what());
      return false;
    }
    cloth_grid::gather(view_, state_, y_next);
    return true;
  }
  void reset() override { state_.x.clear(); }

 private:
  // whether y is the state the last step read back
  bool read_back(const Eigen::VectorXd& y) const {
    if (state_.x.empty()) return false;
    const Eigen::Index free = y.size() / 6;
    for (size_t k = 0; k < view_.free_index.size(); ++k)
      if (const int i = view_.free_index[k]; i >= 0) {
        const auto& x = state_.x[k];
        const auto& v = state_.v[k];
        if (y[3 * i] != x.x || y[3 * i + 1] != x.y || y[3 * i + 2] != x.z || y[3 * (free + i)] != v.x || y[3 * (free + i) + 1] != v.y ||
            y[3 * (free + i) + 2] != v.z)
          return false;
      }
    return true;
  }

  const CountedSystem& system_;
  const ClothGridView& view_;
  Pass pass_;
  std::string_view name_;
  std::unique_ptr<Context> context_;
  std::unique_ptr<GpuCloth> gpu_;
  cloth_grid::State<float> state_;
};

}  // namespace

void register_cloth_methods(MethodTable& table) {
  add_shader_methods(table, {"gpu-cloth", "gpu-cloth-compute",
                             "the explicit mass-spring cloth (twelve springs a node, pins, gravity, wind, pick force, sphere and ground) "
                             "as symplectic Euler in a fragment-shader pass on float32 textures (OpenGL), fixed step",
                             "gpu-cloth as an "
                             "OpenGL 4.3 compute pass on float32 storage buffers, a node an invocation in 16 x 16 work groups (the same "
                             "bits), fixed step",
                             {1, 1, "1"}, needs_cloth_grid, {.oscillator_dt = symplectic_euler_oscillator_dt},
                             [](const CountedSystem& system, Pass pass, std::string_view name) {
                               return std::make_unique<GpuClothStepper>(system, pass, name);
                             }});
}

}  // namespace stepwise::gpu
