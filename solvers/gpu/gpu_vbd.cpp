#include "gpu_vbd.hpp"

#include "solvers/method.hpp"
#include "solvers/run_support.hpp"
#include "solvers/vertex_block_descent.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <memory>

namespace stepwise::gpu {

using gl::GlError;
using gl::check_gl;

namespace {

// a work group's invocations: one node each
constexpr int group = 64;

enum Binding { displacements, inertial, forces, ranges, springs, blocks, order, bindings };

// one node of the colour dispatched moved, as vbd's sweep moves it (gpu_vbd.hpp)
const char* const sweep_source = R"(
layout(local_size_x = {group}) in;
// a spring seen from a node: where its other end is fixed (xyz) and its rest length; the other node (its bits; -1: the
// fixed end) and the stiffness
struct NodeSpring {{ vec4 anchor_rest; vec4 other_stiffness; }};
// a 3 x 3 block of D0 at (this node, node j), by columns; j's bits in c0.w
struct Block {{ vec4 c0, c1, c2; }};
layout(std430, binding = 0) buffer Displacements {{ vec4 e[]; }};
layout(std430, binding = 1) readonly buffer Inertial {{ vec4 xb[]; }};  // w: the node's mass
layout(std430, binding = 2) readonly buffer Forces {{ vec4 f0[]; }};
layout(std430, binding = 3) readonly buffer Ranges {{ ivec4 ranges[]; }};  // the node's springs, then its blocks
layout(std430, binding = 4) readonly buffer Springs {{ NodeSpring springs[]; }};
layout(std430, binding = 5) readonly buffer Blocks {{ Block blocks[]; }};
layout(std430, binding = 6) readonly buffer Order {{ int order[]; }};
uniform int first, count;
uniform float h;

// the spring's vector from node i (displaced by ei) to its other end
vec3 spring_vector(NodeSpring s, vec3 xbi, vec3 ei) {{
  int other = floatBitsToInt(s.other_stiffness.x);
  if (other < 0) return s.anchor_rest.xyz - (xbi + ei);
  return (xb[other].xyz - xbi) + (e[other].xyz - ei);
}}

void main() {{
  if (gl_GlobalInvocationID.x >= uint(count)) return;
  int i = order[first + int(gl_GlobalInvocationID.x)];
  vec3 xbi = xb[i].xyz, ei = e[i].xyz, f0i = f0[i].xyz;
  float m = xb[i].w, hh = h * h;
  ivec4 range = ranges[i];
  // (D0 (x - xb))_i and D0's block (i, i)
  vec3 d0e = vec3(0.0);
  mat3 d0ii = mat3(0.0);
  for (int k = range.z; k < range.w; ++k) {{
    Block b = blocks[k];
    int j = floatBitsToInt(b.c0.w);
    mat3 block = mat3(b.c0.xyz, b.c1.xyz, b.c2.xyz);
    d0e += block * (j == i ? ei : e[j].xyz);
    if (j == i) d0ii = block;
  }}
  // G's gradient and Hessian in x_i: the inertia, the damping, the other forces, the springs (their Hessians semidefinite)
  vec3 g = (m / hh) * ei - d0e / h - f0i;
  mat3 H = (m / hh) * mat3(1.0) - d0ii / h;
  for (int k = range.x; k < range.y; ++k) {{
    NodeSpring s = springs[k];
    float c = s.other_stiffness.y, rest = s.anchor_rest.w;
    vec3 r = spring_vector(s, xbi, ei);
    float len = length(r);
    vec3 u = r / len;
    mat3 uu = outerProduct(u, u);
    g -= c * (len - rest) * u;
    H += c * uu + c * max(0.0, 1.0 - rest / len) * (mat3(1.0) - uu);
  }}
  // the Newton step, -H^-1 g, by Cholesky (H is positive definite: its mass term is, the rest semidefinite)
  float l00 = H[0][0];
  if (!(l00 > 0.0)) return;
  l00 = sqrt(l00);
  float l10 = H[0][1] / l00, l20 = H[0][2] / l00;
  float p11 = H[1][1] - l10 * l10;
  if (!(p11 > 0.0)) return;
  float l11 = sqrt(p11), l21 = (H[1][2] - l20 * l10) / l11;
  float p22 = H[2][2] - l20 * l20 - l21 * l21;
  if (!(p22 > 0.0)) return;
  float l22 = sqrt(p22);
  vec3 z = vec3(-g.x / l00, 0.0, 0.0);
  z.y = (-g.y - l10 * z.x) / l11;
  z.z = (-g.z - l20 * z.x - l21 * z.y) / l22;
  vec3 step = vec3(0.0);
  step.z = z.z / l22;
  step.y = (z.y - l21 * step.z) / l11;
  step.x = (z.x - l10 * step.y - l20 * step.z) / l00;
  float slope = dot(g, step);
  if (!(slope < 0.0)) return;
  // halved until the node's change of G meets Armijo's fraction of the predicted decrease (else the node stays)
  for (int halving = 0; halving <= {max_halvings}; ++halving) {{
    float alpha = ldexp(1.0, -halving);
    vec3 d = alpha * step;
    float change = (m / hh) * (dot(ei, d) + 0.5 * dot(d, d)) - (dot(d, d0e) + 0.5 * dot(d, d0ii * d)) / h - dot(f0i, d);
    for (int k = range.x; k < range.y; ++k) {{
      NodeSpring s = springs[k];
      float c = s.other_stiffness.y, rest = s.anchor_rest.w;
      vec3 r = spring_vector(s, xbi, ei);
      float len = length(r), moved = length(r - d);
      // c / 2 ((L' - l)^2 - (L - l)^2), with L' - L = (|r - d|^2 - |r|^2) / (L' + L)
      float lengthening = (dot(d, d) - 2.0 * dot(r, d)) / (moved + len);
      change += 0.5 * c * lengthening * (moved + len - 2.0 * rest);
    }}
    if (change <= {armijo} * alpha * slope) {{
      e[i] = vec4(ei + d, 0.0);
      return;
    }}
  }}
}}
)";

std::string sweep_program() {
  return "#version 450\n" + fmt::format(fmt::runtime(sweep_source), fmt::arg("group", group), fmt::arg("max_halvings", vbd_max_halvings),
                                         fmt::arg("armijo", fmt::format("{:e}", vbd_armijo)));
}

// the network's springs seen from each node (two vec4s a spring end), and each node's range of them
std::vector<float> node_springs(const MassSpringView& view, std::vector<int>& first) {
  std::vector<std::vector<float>> at(static_cast<size_t>(view.nodes));
  for (const Spring& s : view.springs)
    for (const auto& [node, other] : {std::pair{s.b, s.a}, std::pair{s.a, s.b}}) {
      if (node < 0) continue;
      const Eigen::Vector3d anchor = other < 0 ? s.anchor : Eigen::Vector3d::Zero();
      const int bits = other;
      float other_bits = 0;
      std::memcpy(&other_bits, &bits, sizeof other_bits);
      const float entry[8] = {float(anchor.x()), float(anchor.y()), float(anchor.z()), float(s.rest), other_bits, float(s.stiffness), 0, 0};
      at[static_cast<size_t>(node)].insert(at[static_cast<size_t>(node)].end(), entry, entry + 8);
    }
  std::vector<float> all;
  first.assign(1, 0);
  for (const auto& node : at) {
    all.insert(all.end(), node.begin(), node.end());
    first.push_back(static_cast<int>(all.size() / 8));
  }
  return all;
}

// a node's three coordinates as float32, padded to a vec4 (w given)
void put_node(std::vector<float>& out, int i, const Eigen::VectorXd& x, int dimension, float w) {
  for (int c = 0; c < 3; ++c) out[4 * static_cast<size_t>(i) + c] = c < dimension ? static_cast<float>(x[Eigen::Index{dimension} * i + c]) : 0.0f;
  out[4 * static_cast<size_t>(i) + 3] = w;
}

}  // namespace

GpuVbd::GpuVbd(const Context& context, const MassSpringView& network, const std::vector<std::vector<int>>& colours, const Eigen::SparseMatrix<double>& damping)
    : context_(context), gl_(context.gl()), nodes_(network.nodes), dimension_(network.dimension), colours_(colours) {
  context.make_current();
  if (std::string problem = gl::compute_problem(gl_); !problem.empty()) throw GlError(problem);
  std::vector<int> spring_first;
  const std::vector<float> by_node = node_springs(network, spring_first);
  std::vector<int> node_order;
  for (const auto& colour : colours_) {
    colour_first_.push_back(static_cast<int>(node_order.size()));
    node_order.insert(node_order.end(), colour.begin(), colour.end());
  }
  const auto n = static_cast<size_t>(nodes_);
  xb_.assign(4 * n, 0.0f);
  f0_.assign(4 * n, 0.0f);
  e_.assign(4 * n, 0.0f);
  // each node's neighbours in D0's pattern (the blocks of its first column), fixed from step to step
  block_first_.assign(1, 0);
  for (int i = 0; i < nodes_; ++i) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(damping, Eigen::Index{dimension_} * i); it; ++it)
      if (const auto j = static_cast<int>(it.row() / dimension_); block_node_.size() == static_cast<size_t>(block_first_.back()) || block_node_.back() != j)
        block_node_.push_back(j);
    block_first_.push_back(static_cast<int>(block_node_.size()));
  }
  // each block's column node in its c0.w, once; its values each step (fill_damping_blocks)
  blocks_.assign(12 * block_node_.size(), 0.0f);
  for (size_t slot = 0; slot < block_node_.size(); ++slot) std::memcpy(&blocks_[12 * slot + 3], &block_node_[slot], sizeof(float));
  std::vector<int> range(4 * n);
  for (size_t i = 0; i < n; ++i) range[4 * i] = spring_first[i], range[4 * i + 1] = spring_first[i + 1], range[4 * i + 2] = block_first_[i], range[4 * i + 3] = block_first_[i + 1];

  GLint64 largest = 0;
  gl_.GetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &largest);
  const size_t bytes[bindings] = {16 * n, 16 * n, 16 * n, 16 * n, std::max<size_t>(by_node.size(), 8) * 4, std::max<size_t>(blocks_.size(), 12) * 4,
                                  std::max<size_t>(node_order.size(), 1) * 4};
  for (const size_t b : bytes)
    if (static_cast<double>(b) > static_cast<double>(largest))
      throw GlError(fmt::format("a buffer of {:.3g} MB for {} nodes passes this GL's largest storage buffer, GL_MAX_SHADER_STORAGE_BLOCK_SIZE = {} bytes",
                                static_cast<double>(b) / 1e6, nodes_, largest));
  gl_.CreateBuffers(bindings, buffers_);
  for (int b = 0; b < bindings; ++b) gl_.NamedBufferStorage(buffers_[b], static_cast<GLsizeiptr>(bytes[b]), nullptr, GL_DYNAMIC_STORAGE_BIT);
  gl_.NamedBufferSubData(buffers_[ranges], 0, static_cast<GLsizeiptr>(range.size() * sizeof(int)), range.data());
  if (!by_node.empty()) gl_.NamedBufferSubData(buffers_[springs], 0, static_cast<GLsizeiptr>(by_node.size() * sizeof(float)), by_node.data());
  gl_.NamedBufferSubData(buffers_[order], 0, static_cast<GLsizeiptr>(node_order.size() * sizeof(int)), node_order.data());
  program_ = gl::link_compute_program(gl_, sweep_program().c_str(), "vbd sweep");
  first_at_ = gl_.GetUniformLocation(program_, "first");
  count_at_ = gl_.GetUniformLocation(program_, "count");
  h_at_ = gl_.GetUniformLocation(program_, "h");
  check_gl(gl_, "the vbd sweep's buffers and program");
}

GpuVbd::~GpuVbd() {
  if (!context_.try_make_current()) return;
  gl_.DeleteProgram(program_);
  gl_.DeleteBuffers(bindings, buffers_);
}

void GpuVbd::fill_damping_blocks(const Eigen::SparseMatrix<double>& d0) {
  // D0's pattern is fixed, so each step writes the same entries (in the plane, the z row and column stay zero)
  for (int i = 0; i < nodes_; ++i) {
    const auto from = block_node_.begin() + block_first_[static_cast<size_t>(i)], to = block_node_.begin() + block_first_[static_cast<size_t>(i) + 1];
    for (int c = 0; c < dimension_; ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(d0, Eigen::Index{dimension_} * i + c); it; ++it) {
        // D0 is symmetric: column (i, c) row (j, r) is the block (i, j)'s entry (c, r), column r of the block as GLSL holds it
        const auto j = static_cast<int>(it.row() / dimension_), r = static_cast<int>(it.row() % dimension_);
        const auto slot = static_cast<size_t>(std::find(from, to, j) - block_node_.begin());
        if (slot == static_cast<size_t>(to - block_node_.begin())) throw GlError(fmt::format("D0's pattern changed: node {} now couples node {}", i, j));
        blocks_[12 * slot + 4 * static_cast<size_t>(r) + static_cast<size_t>(c)] = static_cast<float>(it.value());
      }
  }
}

void GpuVbd::start(const IncrementalPotential& potential, const Eigen::VectorXd& x) {
  const Eigen::VectorXd& xb = potential.inertial();
  const Eigen::VectorXd e = x - xb;
  for (int i = 0; i < nodes_; ++i) {
    put_node(xb_, i, xb, dimension_, static_cast<float>(potential.mass()[Eigen::Index{dimension_} * i]));
    put_node(f0_, i, potential.other_forces(), dimension_, 0.0f);
    put_node(e_, i, e, dimension_, 0.0f);
  }
  fill_damping_blocks(potential.damping());
  context_.make_current();
  const auto upload = [&](Binding b, const std::vector<float>& data) {
    gl_.NamedBufferSubData(buffers_[b], 0, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data());
  };
  upload(inertial, xb_);
  upload(forces, f0_);
  upload(displacements, e_);
  if (!blocks_.empty()) upload(blocks, blocks_);
  gl_.UseProgram(program_);
  gl_.Uniform1f(h_at_, static_cast<float>(potential.h()));
  check_gl(gl_, "the vbd sweep's step (glNamedBufferSubData)");
}

void GpuVbd::sweep(int count) {
  context_.make_current();
  gl_.UseProgram(program_);
  for (int b = 0; b < bindings; ++b) gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(b), buffers_[b]);
  for (int s = 0; s < count; ++s)
    for (size_t c = 0; c < colours_.size(); ++c) {
      const auto nodes = static_cast<GLint>(colours_[c].size());
      gl_.Uniform1i(first_at_, colour_first_[c]);
      gl_.Uniform1i(count_at_, nodes);
      gl_.DispatchCompute(static_cast<GLuint>((nodes + group - 1) / group), 1, 1);
      // the next colour reads what this one moved
      gl_.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
  check_gl(gl_, "a vbd sweep (glDispatchCompute)");
}

void GpuVbd::download(const IncrementalPotential& potential, Eigen::VectorXd& x) const {
  context_.make_current();
  std::vector<float> e(4 * static_cast<size_t>(nodes_));
  gl_.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  gl_.GetNamedBufferSubData(buffers_[displacements], 0, static_cast<GLsizeiptr>(e.size() * sizeof(float)), e.data());
  check_gl(gl_, "glGetNamedBufferSubData (the vbd sweep's displacements)");
  x = potential.inertial();
  for (int i = 0; i < nodes_; ++i)
    for (int c = 0; c < dimension_; ++c) x[Eigen::Index{dimension_} * i + c] += e[4 * static_cast<size_t>(i) + static_cast<size_t>(c)];
}

void GpuVbd::finish() const {
  context_.make_current();
  gl_.Finish();
}

std::string vbd_device_problem(const OdeSystem& system) {
  const auto* view = system.as<MassSpringView>();
  if (!view || !system.as<SpringNetworkView>()) return "no network of springs for gpu-vbd-compute to sweep";
  try {
    const auto context = make_device_context();
    context->make_current();
    return gl::compute_problem(context->gl());
  } catch (const GlError& e) {
    return e.what();
  }
}

namespace {

// vbd's step with its sweeps on the device: the state uploaded at each step's start, read back at its end
class GpuVbdStepper final : public VbdStepper {
 public:
  GpuVbdStepper(const CountedSystem& s, const VbdSettings& settings) : VbdStepper(s, settings, "gpu-vbd-compute") {}

 protected:
  bool iterate(const VbdNodes& nodes, Eigen::VectorXd& x, double& decrease, std::string& failure) override {
    const IncrementalPotential& potential = nodes.potential();
    start_ = x;
    try {
      if (!context_) context_ = make_device_context();
      if (!gpu_) gpu_ = std::make_unique<GpuVbd>(*context_, view(), nodes.colours(), potential.damping());
      gpu_->start(potential, x);
      gpu_->sweep(sweeps().sweeps);
      gpu_->download(potential, x);
    } catch (const GlError& e) {
      failure = fmt::format("gpu-vbd-compute: {}", e.what());
      return false;
    }
    decrease -= potential.change(start_, x - start_);
    return true;
  }

 private:
  std::unique_ptr<Context> context_;
  std::unique_ptr<GpuVbd> gpu_;
  Eigen::VectorXd start_;
};

}  // namespace

void register_vbd_compute_method(MethodTable& table) {
  table.add({
      .name = "gpu-vbd-compute",
      .family = Family::gpu,
      .source = Source::opengl_shader,
      .description = "vbd's coloured sweeps on a network of springs as an OpenGL 4.3 compute pass in float32, a dispatch a colour and an "
                     "invocation a node (the step's potential and start on the host, in float64)",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .needs = needs_spring_network,
      .options = vbd_options(false, false),
      .make = [](const Method& method, const StepControl& control) {
        return std::make_unique<FixedStepIntegrator>(method, control, [settings = vbd_settings(method, control)](const CountedSystem& system) {
          return std::make_unique<GpuVbdStepper>(system, settings);
        });
      },
      .device_problem = vbd_device_problem,
      .twin = "vbd",
  });
}

}  // namespace stepwise::gpu
