// The seeds' GPU simulation on llvmpipe through OSMesa, no GPU needed (on a GPU through EGL with
// STEPWISE_GPU_BACKEND=egl, where the bitwise claims that hold for llvmpipe alone are not made): the wave schemes'
// fragment passes against the float32 CPU loops step for step, against float64 to show what precision
// costs, and against the exactly evolved DST modes; the cloth's pass against its float32 CPU step, that step
// in float64 against the model's own symplectic Euler, and gpu-cloth as `run` takes it. Every pass twice: the
// seeds' fragment pass and its compute twin (OpenGL 4.3 storage buffers; the wave's with a shared-memory tile),
// which on llvmpipe give the float32 CPU loops' bits. And vbd's sweeps as a compute pass (gpu-vbd-compute): with enough
// sweeps its step is backward Euler's to float32's round-off, on the spring flag, the hanging chain and the compliant
// pendulum in the plane, and as `run` takes it.
#include "models/height_field.hpp"
#include "models/model.hpp"
#include "run/measure.hpp"
#include "solvers/gpu/gpu_cloth.hpp"
#include "solvers/gpu/gpu_vbd.hpp"
#include "solvers/gpu/gpu_wave.hpp"
#include "solvers/incremental_potential.hpp"
#include "solvers/method_table.hpp"
#include "solvers/run_support.hpp"
#include "solvers/vertex_block_descent.hpp"
#include "verification/gpu_references.hpp"
#include "verification/stability.hpp"
#include "verification/tolerances.hpp"
#include "verification/vbd_roundoff.hpp"
#include "verification/wave_modes.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

namespace stepwise {
namespace {

// the GPU methods' backend: OSMesa (llvmpipe) unless STEPWISE_GPU_BACKEND=egl (a GPU's driver, where one is)
gl::Context& context() {
  static const std::unique_ptr<gl::Context> c = gl::make_context(gpu::backend());
  return *c;
}

// llvmpipe: IEEE float32 with the operations kept in order, the CPU's bits
bool on_llvmpipe() { return context().description().find("llvmpipe") != std::string::npos; }

constexpr gpu::Pass passes[] = {gpu::Pass::fragment, gpu::Pass::compute};
const char* pass_name(gpu::Pass pass) { return pass == gpu::Pass::fragment ? "fragment pass" : "compute pass"; }

// sin theta of the scheme's slowest mode (1, 1) at mu = 0: 2 cos theta = 2 - c^2 dt^2 lambda_11
double sin_theta_min(const WaveGridView& grid, double dt) {
  const double lambda = laplacian_eigenvalue(grid.points - 1, grid.spacing, 1, 1);
  const double cosine = 1 - grid.c * grid.c * dt * dt * lambda / 2;
  return std::sqrt(1 - cosine * cosine);
}

double coefficient_sum(const BasicWaveCoefficients<float>& k) { return std::abs(k.self) + std::abs(k.previous) + 4 * std::abs(k.neighbours); }

// an undamped grid of `points` (d = 0.02, c = 1) at `fraction` of its step limit, two random levels in
// float, uploaded to the shader
struct Shader {
  Shader(int points, double fraction, unsigned seed, gpu::Pass pass = gpu::Pass::fragment)
      : grid{points, 0.02, 1.0, 0.0},
        dt(fraction * wave_stable_dt(grid)),
        k(to_float(wave_coefficients(grid, dt))),
        z0(random_wave_field(points, 1.0, seed).cast<float>()),
        z1(random_wave_field(points, 1.0, seed + 1).cast<float>()),
        gpu(context(), points, k, pass) {
    gpu.upload(z0, z1);
  }
  // the round-off bound after `steps` (extra roundings per cell and step beyond the scheme's own)
  double bound(long steps, double extra = 0) const {
    return tolerance::float32_wave_bound(steps, sin_theta_min(grid, dt), coefficient_sum(k), z1.cwiseAbs().maxCoeff(), static_cast<double>(z0.size())) *
           (tolerance::float32_wave_roundings + extra) / tolerance::float32_wave_roundings;
  }
  WaveGridView grid;
  double dt;
  BasicWaveCoefficients<float> k;
  Eigen::VectorXf z0, z1;
  gpu::GpuWave gpu;
};

TEST(GpuShader, WavePassMatchesTheFloat32CpuLoopStepForStep) {
  for (const gpu::Pass pass : passes) {
    Shader shader(64, 0.9, 3, pass);
    Eigen::VectorXf cpu_prev = shader.z0, cpu = shader.z1, gpu_prev, gpu_z;
    Eigen::VectorXd wide_prev = shader.z0.cast<double>(), wide = shader.z1.cast<double>();
    long done = 0;
    for (const long steps : {1L, 10L, 100L, 1000L}) {
      shader.gpu.step(steps - done);
      run_wave_scheme_float32(shader.grid, shader.dt, steps - done, cpu_prev, cpu);
      run_wave_scheme(shader.grid, shader.dt, steps - done, wide_prev, wide);
      done = steps;
      shader.gpu.download(gpu_prev, gpu_z);
      const double bound = shader.bound(steps);
      const double shader_cpu = (gpu_z - cpu).cast<double>().norm(), cpu_wide = (cpu.cast<double>() - wide).norm();
      std::cout << pass_name(pass) << ", " << steps << " steps: |shader - cpu float32| = " << shader_cpu << ", |cpu float32 - float64| = " << cpu_wide
                << ", bound " << bound << " (|z| = " << wide.norm() << ")\n";
      EXPECT_LE(shader_cpu, bound) << pass_name(pass) << ", " << steps << " steps";
      EXPECT_LE((gpu_prev - cpu_prev).cast<double>().norm(), bound) << pass_name(pass) << ", " << steps << " steps, the previous level";
      EXPECT_LE(cpu_wide, bound) << steps << " steps: float32's own round-off";
      if (on_llvmpipe()) {
        EXPECT_EQ(shader_cpu, 0) << pass_name(pass) << ", " << steps << " steps: llvmpipe gives the float32 CPU loop's bits";
      }
    }
  }
}

TEST(GpuShader, TheWaveComputePassesGiveTheSameBitsWhateverTheirTiling) {
  // a tile is a copy of z in shared memory, and four steps a dispatch recompute its halo from copies: the same
  // values into the same operations, so the same cells. 70 points: work groups that overhang the grid, and
  // tiles clamped at its edges; 301 steps: a last dispatch of one step
  const WaveGridView grid{70, 0.02, 1.0, 0.0};
  const double dt = 0.9 * wave_stable_dt(grid), c2 = grid.c * grid.c / (grid.spacing * grid.spacing);
  const auto k = to_float(wave_coefficients(grid, dt));
  const Eigen::VectorXf z0 = random_wave_field(grid.points, 1.0, 11).cast<float>(), z1 = random_wave_field(grid.points, 1.0, 12).cast<float>();
  const auto three_level = [&](gpu::Tiling tiling) {
    gpu::GpuWave gpu(context(), grid.points, k, gpu::Pass::compute, tiling);
    gpu.upload(z0, z1);
    gpu.step(301);
    Eigen::VectorXf prev, z;
    gpu.download(prev, z);
    return std::pair{prev, z};
  };
  const auto symplectic = [&](gpu::Tiling tiling) {
    gpu::GpuSymplecticWave gpu(context(), grid.points, static_cast<float>(c2), 0.5f, static_cast<float>(0.9 * symplectic_euler_wave_dt(grid)),
                               gpu::Pass::compute, tiling);
    gpu.upload(z0, z1);
    gpu.step(301);
    Eigen::VectorXf z, v;
    gpu.download(z, v);
    return std::pair{z, v};
  };
  const auto same = [](const std::pair<Eigen::VectorXf, Eigen::VectorXf>& a, const std::pair<Eigen::VectorXf, Eigen::VectorXf>& b) {
    return (a.first - b.first).cwiseAbs().maxCoeff() == 0 && (a.second - b.second).cwiseAbs().maxCoeff() == 0;
  };
  const auto wave_tile = three_level(gpu::Tiling::tile), symplectic_tile = symplectic(gpu::Tiling::tile);
  EXPECT_GT(wave_tile.second.cwiseAbs().maxCoeff(), 0);
  for (const auto tiling : {gpu::Tiling::none, gpu::Tiling::four_steps}) {
    EXPECT_TRUE(same(three_level(tiling), wave_tile)) << "the three-level scheme, tiling " << static_cast<int>(tiling);
    EXPECT_TRUE(same(symplectic(tiling), symplectic_tile)) << "symplectic Euler, tiling " << static_cast<int>(tiling);
  }
}

TEST(GpuShader, ShaderStateMatchesTheExactlyEvolvedDstModes) {
  // the water's FFT check on the shader's state: every mode of a random state evolved by its exact
  // discrete recurrence (FFTW's DST-I), against 2000 passes
  Shader shader(49, 0.8, 5);
  const long steps = 2000;
  shader.gpu.step(steps);
  Eigen::VectorXf z_prev, z;
  shader.gpu.download(z_prev, z);
  const Eigen::VectorXd exact = evolve_modes(shader.grid, shader.dt, shader.z0.cast<double>(), shader.z1.cast<double>(), steps + 1);
  const double error = (z.cast<double>() - exact).norm();
  // the exact modes use the double coefficients; the shader's, rounded to float, differ by at most u of
  // each, which puts at most u S M more into a cell each step: one more rounding in the bound's count
  const double bound = shader.bound(steps, 1);
  std::cout << steps << " passes: |shader - exact modes| = " << error << " (relative " << error / exact.norm() << "), bound " << bound << '\n';
  EXPECT_LE(error, bound);
}

TEST(GpuShader, SymplecticPassMatchesTheFloat32CpuLoopStepForStep) {
  // the second seed's scheme: z and v random (v on the scale of the fastest mode's rate), undamped, at 0.9
  // of its limit; the bound's Z and V are the largest |z| and |v| the reference run reaches
  const WaveGridView grid{64, 0.02, 1.0, 0.0};
  const double dt = 0.9 * symplectic_euler_wave_dt(grid), c2 = grid.c * grid.c / (grid.spacing * grid.spacing);
  const Eigen::VectorXf z0 = random_wave_field(grid.points, 1.0, 7).cast<float>();
  const Eigen::VectorXf v0 = random_wave_field(grid.points, 2 / dt, 8).cast<float>();
  for (const gpu::Pass pass : passes) {
    gpu::GpuSymplecticWave gpu(context(), grid.points, static_cast<float>(c2), 0.0f, static_cast<float>(dt), pass);
    gpu.upload(z0, v0);
    Eigen::VectorXf z = z0, v = v0, gpu_z, gpu_v;
    double max_z = z0.cwiseAbs().maxCoeff(), max_v = v0.cwiseAbs().maxCoeff();
    long done = 0;
    for (const long steps : {1L, 10L, 100L, 1000L}) {
      gpu.step(steps - done);
      for (; done < steps; ++done) {
        run_symplectic_wave_float32(grid, dt, 1, z, v);
        max_z = std::max(max_z, static_cast<double>(z.cwiseAbs().maxCoeff()));
        max_v = std::max(max_v, static_cast<double>(v.cwiseAbs().maxCoeff()));
      }
      gpu.download(gpu_z, gpu_v);
      const double bound = tolerance::float32_symplectic_wave_bound(steps, sin_theta_min(grid, dt), dt, c2, max_z, max_v, static_cast<double>(z0.size()));
      const double difference = (gpu_z - z).cast<double>().norm();
      std::cout << pass_name(pass) << ", " << steps << " steps: |shader z - cpu float32 z| = " << difference << ", bound " << bound << " (|z| = " << z.norm() << ")\n";
      EXPECT_LE(difference, bound) << pass_name(pass) << ", " << steps << " steps";
      if (on_llvmpipe()) {
        EXPECT_EQ(difference, 0) << pass_name(pass) << ", " << steps << " steps: llvmpipe gives the float32 CPU loop's bits";
        EXPECT_EQ((gpu_v - v).cwiseAbs().maxCoeff(), 0) << pass_name(pass) << ", " << steps << " steps, v";
      }
    }
  }
}

TEST(GpuShader, GpuWaveMethodFollowsWaveFdToFloat32RoundOff) {
  // the method as `run` takes it (wave_fd.hpp's start in double, then passes on the device, each level
  // read back): against wave-fd on the standing wave, 400 steps at 0.9 of the limit; the state enters the
  // texture rounded to float (one more rounding, once) and the coefficients too (one more per step)
  const auto model = make_model("standing-wave", {{"size", 33}, {"spacing", 1.0 / 32}, {"mode_m", 2}, {"mode_n", 3}, {"amplitude", 1.0}, {"mu", 0.0}});
  const WaveGridView grid = *model->as<WaveGridView>();
  const double dt = 0.9 * wave_stable_dt(grid);
  const long steps = 400;
  const std::vector<double> t_out{steps * dt};
  const auto run = [&](const char* method) { return make_integrator(method, StepControl::fixed(dt))->integrate(*model, 0, model->initial_state(), t_out); };
  const RunResult cpu = run("wave-fd"), fragment = run("gpu-wave");
  const Eigen::Index cells = static_cast<Eigen::Index>(grid.points) * grid.points;
  const auto k = to_float(wave_coefficients(grid, dt));
  const double bound = tolerance::float32_wave_bound(steps, sin_theta_min(grid, dt), coefficient_sum(k), model->initial_state().head(cells).cwiseAbs().maxCoeff(),
                                                     static_cast<double>(cells)) *
                       (tolerance::float32_wave_roundings + 2) / tolerance::float32_wave_roundings;
  for (const char* method : {"gpu-wave", "gpu-wave-compute"}) {
    const RunResult gpu = run(method);
    ASSERT_EQ(gpu.status, Status::ok) << gpu.message;
    const double difference = (gpu.y_stop.head(cells) - cpu.y_stop.head(cells)).norm();
    std::cout << method << " against wave-fd after " << steps << " steps: " << difference << " (|z| = " << cpu.y_stop.head(cells).norm() << "), bound " << bound << '\n';
    EXPECT_LE(difference, bound) << method;
    // the twins: the same state, the same bits
    if (on_llvmpipe()) {
      EXPECT_EQ((gpu.y_stop - fragment.y_stop).cwiseAbs().maxCoeff(), 0) << method;
    }
  }
}

TEST(GpuShader, ComputePassesAreRefusedWithoutOpenGl43AndPastTheLargestStorageBufferNamingWhy) {
  // the check a run makes before a compute method starts (exit 2): the version found, or the limit
  EXPECT_EQ(gl::compute_problem(4, 3, "4.3"), "");
  EXPECT_EQ(gl::compute_problem(4, 5, "4.5 (Core Profile) Mesa"), "");
  const std::string old = gl::compute_problem(4, 2, "4.2 (Core Profile) Mesa 22.3.6");
  EXPECT_NE(old.find("OpenGL 4.3"), std::string::npos) << old;
  EXPECT_NE(old.find("4.2 (Core Profile) Mesa 22.3.6"), std::string::npos) << old;
  EXPECT_NE(gl::compute_problem(3, 3, "3.3").find("this GL is 3.3"), std::string::npos);
  EXPECT_EQ(gpu::compute_grid_problem(context(), 64, 64), "");
  const std::string huge = gpu::compute_grid_problem(context(), 1 << 16, 1 << 16);
  std::cout << huge << '\n';
  EXPECT_NE(huge.find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE = "), std::string::npos) << huge;
}

TEST(GpuShader, AGridPastTheLargestTextureIsRefusedNamingTheLimit) {
  // the check the run makes before a GPU method starts (exit 2): no texture is made for it
  EXPECT_EQ(gpu::texture_problem(context(), 64, 64), "");
  const std::string problem = gpu::texture_problem(context(), 64, 1 << 20);
  std::cout << problem << '\n';
  EXPECT_NE(problem.find("GL_MAX_TEXTURE_SIZE = "), std::string::npos) << problem;
}

// ---- the cloth

// a 12 x 16 flag (rows != columns, so a swapped texel axis shows) with every force the pass has: its four
// corners pinned, the gusting wind through its normals, a pick force; and a 12 x 12 sheet dropped onto a
// sphere, whose nodes meet it within the run. Each at half its symplectic Euler limit (the stiffest mode's)
Params flag_params() {
  return {{"rows", 12}, {"columns", 16}, {"width", 1.2}, {"height", 0.8}, {"wind_x", 1}, {"wind_z", 4}, {"pick_row", 5}, {"pick_column", 7},
          {"pick_fx", 0.3}, {"pick_fz", -0.5}};
}
Params draping_params() {
  return {{"rows", 12}, {"columns", 12}, {"width", 0.6}, {"height", 0.6}, {"horizontal", 1}, {"elevation", 0.52}, {"pin_corners", 0},
          {"wind_coefficient", 0}, {"sphere_radius", 0.5}, {"ground", 1}, {"ground_y", -0.5}, {"friction", 0.4}};
}
double half_limit(const Model& model) {
  return 0.5 * *mass_spring_stable_dt("symplectic-euler", stiffest_mode(model, 0, model.initial_state()));
}

TEST(GpuShader, ClothPassMatchesTheFloat32CpuStepStepForStep) {
  // step for step: each of 400 steps from the same float32 state on both sides (the CPU's, uploaded), one
  // pass against one CPU step, held to one step's round-off bound; and the device left to run on its own
  // state, which on llvmpipe (IEEE float32 with the operations kept in order) is the CPU's to the bit
  const bool llvmpipe = on_llvmpipe();
  for (const gpu::Pass pass : passes)
  for (const auto& [sheet, params] : {std::pair{"flag", flag_params()}, std::pair{"draping sheet", draping_params()}}) {
    const std::string name = fmt::format("{}, {}", sheet, pass_name(pass));
    const auto model = make_model("cloth", params);
    const ClothGridView& view = *model->as<ClothGridView>();
    const double h = half_limit(*model), nodes = static_cast<double>(view.start.size());
    gpu::GpuCloth stepped(context(), view, pass), running(context(), view, pass);
    cloth_grid::State<float> cpu = cloth_grid::spread<float>(view, model->initial_state()), next, shader;
    running.upload(cpu);
    tolerance::ClothRoundoffScale scale;
    widen_roundoff_scale(view, cpu, scale);
    double worst = 0, worst_bound = 0, precision = 0;  // precision: one float32 step against float64 from the same state
    const long steps = 400;
    for (long done = 0; done < steps; ++done) {
      const auto k = cloth_grid::constants<float>(view, static_cast<double>(done) * h, h);
      stepped.upload(cpu);
      stepped.set_constants(k);
      stepped.step(1);
      running.set_constants(k);
      running.step(1);
      cloth_grid::State<double> wide{std::vector<Vec3<double>>(cpu.x.size()), std::vector<Vec3<double>>(cpu.v.size())}, wide_next;
      for (size_t n = 0; n < cpu.x.size(); ++n) {
        wide.x[n] = {cpu.x[n].x, cpu.x[n].y, cpu.x[n].z};
        wide.v[n] = {cpu.v[n].x, cpu.v[n].y, cpu.v[n].z};
      }
      cloth_grid::step(cloth_grid::constants<double>(view, static_cast<double>(done) * h, h), view.free_index, wide, wide_next);
      cloth_grid::step(k, view.free_index, cpu, next);
      std::swap(cpu, next);
      widen_roundoff_scale(view, cpu, scale);
      precision = std::max(precision, position_difference(cpu, wide_next) / tolerance::cloth_step_roundoff(tolerance::float32_unit_roundoff, h, nodes, scale));
      stepped.download(shader);
      const double difference = position_difference(shader, cpu), bound = tolerance::cloth_step_roundoff(tolerance::float32_unit_roundoff, h, nodes, scale);
      EXPECT_LE(difference, bound) << name << ", step " << done + 1;
      if (difference >= worst) worst = difference, worst_bound = bound;
    }
    running.download(shader);
    const double chained = position_difference(shader, cpu);
    std::cout << name << ", " << steps << " steps of " << h << " s: largest one-step |shader x - cpu float32 x| = " << worst << " (bound "
              << worst_bound << "); after " << steps << " steps on the device's own state: " << chained << " (bound "
              << tolerance::cloth_steps_bound(tolerance::float32_unit_roundoff, steps, h, nodes, scale) << "); one float32 step from float64's "
              << "at most " << precision << " of the one-step bound\n";
    EXPECT_LE(precision, 1) << name << ": float32's own one-step round-off";
    EXPECT_LE(chained, tolerance::cloth_steps_bound(tolerance::float32_unit_roundoff, steps, h, nodes, scale)) << name;
    if (llvmpipe) {
      EXPECT_EQ(chained, 0) << name << ": llvmpipe computes the CPU's float32 operations in the CPU's order";
    }
    if (sheet == std::string("draping sheet")) {
      // the sheet met the sphere: some node lies on it (to float rounding), none inside
      double closest = 1e9;
      for (const auto& x : shader.x) closest = std::min(closest, double(norm(x)));
      std::cout << "  closest node to the sphere's centre: " << closest << " m (radius 0.5)\n";
      EXPECT_NEAR(closest, 0.5, 1e-6);
    }
  }
}

TEST(GpuShader, ClothGridStepInFloat64IsTheModelsSymplecticEuler) {
  // the node-by-node step (gathering each node's forces) against the model's spring list and triangle loop
  // under symplectic-euler, both float64: equal to round-off, so the grid form (and the shader's) is the
  // model's physics; the float32 step's distance from it is what precision costs, inside float32's bound
  const auto model = make_model("cloth", flag_params());
  const ClothGridView& view = *model->as<ClothGridView>();
  const double h = half_limit(*model);
  const long steps = 400;
  tolerance::ClothRoundoffScale scale;
  const auto wide = run_cloth_grid<double>(view, model->initial_state(), 0, h, steps, scale);
  const auto narrow = run_cloth_grid<float>(view, model->initial_state(), 0, h, steps, scale);
  const RunResult run = make_integrator("symplectic-euler", StepControl::fixed(h))->integrate(*model, 0, model->initial_state(), std::vector<double>{steps * h});
  ASSERT_EQ(run.status, Status::ok) << run.message;
  const auto model_state = cloth_grid::spread<double>(view, run.y_stop);
  const double nodes = static_cast<double>(view.start.size());
  const double to_model = position_difference(wide, model_state), precision = position_difference(narrow, wide);
  const double bound64 = tolerance::cloth_steps_bound(tolerance::float64_unit_roundoff, steps, h, nodes, scale);
  const double bound32 = tolerance::cloth_steps_bound(tolerance::float32_unit_roundoff, steps, h, nodes, scale);
  std::cout << steps << " steps: |grid float64 - model| = " << to_model << " (bound " << bound64 << "), |grid float32 - float64| = " << precision
            << " (bound " << bound32 << ")\n";
  // each side is within its bound of the exact step's result: their difference within the sum
  EXPECT_LE(to_model, 2 * bound64);
  EXPECT_LE(precision, bound32 + bound64);
}

TEST(GpuShader, GpuClothMethodFollowsSymplecticEulerToFloat32RoundOff) {
  // gpu-cloth as `run` takes it (the state uploaded once rounded to float, the constants each step, each
  // new state read back) against symplectic-euler on the model; the sheet that meets the sphere runs too
  for (const auto& params : {flag_params(), draping_params()}) {
    const auto model = make_model("cloth", params);
    const double h = half_limit(*model);
    const long steps = 200;
    const std::vector<double> t_out{steps * h};
    const auto run = [&](const char* method) { return make_integrator(method, StepControl::fixed(h))->integrate(*model, 0, model->initial_state(), t_out); };
    const RunResult cpu = run("symplectic-euler"), fragment = run("gpu-cloth");
    const ClothGridView& view = *model->as<ClothGridView>();
    tolerance::ClothRoundoffScale scale;
    run_cloth_grid<double>(view, model->initial_state(), 0, h, steps, scale);
    const double bound = tolerance::cloth_steps_bound(tolerance::float32_unit_roundoff, steps, h, static_cast<double>(view.start.size()), scale);
    for (const char* method : {"gpu-cloth", "gpu-cloth-compute"}) {
      const RunResult gpu = run(method);
      ASSERT_EQ(gpu.status, Status::ok) << gpu.message;
      const double difference = position_difference(cloth_grid::spread<double>(view, gpu.y_stop), cloth_grid::spread<double>(view, cpu.y_stop));
      std::cout << method << " against symplectic-euler after " << steps << " steps: " << difference << ", bound " << bound << '\n';
      EXPECT_LE(difference, bound) << method;
      if (on_llvmpipe()) {
        EXPECT_EQ((gpu.y_stop - fragment.y_stop).cwiseAbs().maxCoeff(), 0) << method << ": the twins' bits";
      }
    }
  }
  // and only on a cloth
  const auto water = make_model("standing-wave", {});
  EXPECT_FALSE(method_applies(*find_method("gpu-cloth"), *water));
  EXPECT_FALSE(method_applies(*find_method("gpu-cloth-compute"), *water));
  EXPECT_NE(method_requirement(*find_method("gpu-cloth"), *water).find("cloth"), std::string::npos);
}

// a mass-spring scene in motion for one backward Euler step: the flag of springs (8 x 8, six frames from its flat
// start), the hanging chain from its start, the pendulum on a stiff rod (1e-4 m/N, omega h = 1.7) at 0.5 rad, 2 rad/s.
// (A stiffer rod tells the pass from vbd less: the float32 bound grows with the stiffness, c eps_f |x| h^2 / m)
struct SpringScene {
  const char* name;
  std::unique_ptr<Model> model;
  Eigen::VectorXd y;
};
std::vector<SpringScene> spring_scenes() {
  std::vector<SpringScene> scenes;
  scenes.push_back({"flag", make_model("cloth", {{"rows", 8}, {"columns", 8}}), {}});
  scenes.push_back({"hanging chain", make_model("hanging-chain", {}), {}});
  scenes.push_back({"compliant pendulum", make_model("pendulum-cartesian", {{"compliance", 1e-4}, {"theta0", 0.5}, {"omega0", 2.0}}), {}});
  for (auto& scene : scenes) scene.y = scene.model->initial_state();
  const Measured m = run_and_measure(*scenes[0].model, "implicit-euler-newton", StepControl::fixed(1.0 / 60), 0.1, 0.1);
  EXPECT_EQ(m.result.status, Status::ok) << m.result.message;
  scenes[0].y = m.result.y_stop;
  return scenes;
}

// one 1/60 s backward Euler step of a scene: its potential G, vbd's colours, and the float32 bound at x
struct SpringStep {
  static constexpr double h = 1.0 / 60;
  Stats stats;
  CountedSystem system;
  const MassSpringView& view;
  IncrementalPotential G;
  std::vector<std::vector<int>> colours;
  explicit SpringStep(const SpringScene& scene) : system(*scene.model, stats), view(*system.as<MassSpringView>()), G(system, view) {
    G.start(0, scene.y, h);
    Eigen::SparseMatrix<double> k, d;
    force_jacobians(system, view, 0, scene.y, true, k, d);
    colours = colour_nodes(k, view.dimension);
  }
  double bound(const Eigen::VectorXd& x) const {
    return tolerance::vbd_float32_step(h, *std::min_element(view.mass.begin(), view.mass.end()), gradient_scale(G, view, x));
  }
};

TEST(GpuVbd, WithEnoughSweepsItsStepIsBackwardEulersToFloat32RoundOff) {
  // one 1/60 s step: the pass's sweeps from the inertial point, 64 at a time until they leave the nodes where they
  // were (or 4096), against Newton on the same G to 1e-9 m/s: within the float32 bound, and closer than the start was
  for (const SpringScene& scene : spring_scenes()) {
    SpringStep step(scene);
    const IncrementalPotential& G = step.G;
    Eigen::VectorXd newton_x = G.inertial();
    const NewtonOnPotential converged{.velocity_tolerance = 1e-9};
    PotentialNewton newton(converged);
    ASSERT_EQ(newton.minimise(G, newton_x, step.stats), "") << scene.name;
    gpu::GpuVbd gpu(context(), step.view, step.colours, G.damping());
    Eigen::VectorXd x = G.inertial(), last;
    gpu.start(G, x);
    int sweeps = 0;
    do {
      last = x;
      gpu.sweep(64);
      sweeps += 64;
      gpu.download(G, x);
    } while (x != last && sweeps < 4096);
    const double bound = step.bound(newton_x) + converged.velocity_tolerance * SpringStep::h * std::sqrt(double(x.size()));
    const double gap = (x - newton_x).norm(), start = (G.inertial() - newton_x).norm();
    std::cout << scene.name << ": " << sweeps << " sweeps, |x - x*| = " << gap << " m (bound " << bound << ", from the inertial point " << start << ")\n";
    EXPECT_LE(gap, bound) << scene.name;
    EXPECT_LT(gap, start) << scene.name;
  }
}

TEST(GpuVbd, EachSweepIsVbdsToFloat32RoundOff) {
  // 1, 2 and 5 sweeps from the inertial point, the pass's against vbd's in float64: each sweep moves each node as
  // vbd's does, its float32 round-off within vbd_float32_step of the node's (a Gauss-Seidel sweep of G does not
  // amplify a perturbation in G's Hessian norm), so after k sweeps within k times it
  for (const SpringScene& scene : spring_scenes()) {
    const SpringStep step(scene);
    const IncrementalPotential& G = step.G;
    gpu::GpuVbd gpu(context(), step.view, step.colours, G.damping());
    for (const int sweeps : {1, 2, 5}) {
      Eigen::VectorXd cpu = G.inertial(), gpu_x = G.inertial(), decrease;
      vbd_iterate(VbdNodes(G, step.colours, &step.view), cpu, {.sweeps = sweeps}, decrease);
      gpu.start(G, gpu_x);
      gpu.sweep(sweeps);
      gpu.download(G, gpu_x);
      const double bound = sweeps * std::max(step.bound(G.inertial()), step.bound(cpu));
      const double gap = (gpu_x - cpu).norm();
      std::cout << scene.name << ", " << sweeps << " sweeps: |pass - vbd| = " << gap << " m (bound " << bound << ", the sweeps moved the nodes "
                << (cpu - G.inertial()).norm() << ")\n";
      EXPECT_LE(gap, bound) << scene.name << ", " << sweeps << " sweeps";
    }
  }
}

TEST(GpuVbd, TheMethodsConvergedStepIsImplicitEulerNewtonsToFloat32RoundOff) {
  // gpu-vbd-compute as `run` takes it (its default start, the sweeps, the velocity from the positions), 1000 sweeps a
  // step, one 1/60 s step, against implicit-euler-newton's; and what it counts (the colours, G's decrease)
  for (const SpringScene& scene : spring_scenes()) {
    const double h = 1.0 / 60;
    StepControl sweeps = StepControl::fixed(h);
    sweeps.settings["iterations"] = 1000;
    const auto step = [&](const char* method) {
      return make_integrator(method, find_method(method)->option("iterations") ? sweeps : StepControl::fixed(h))->integrate(*scene.model, 0, scene.y, std::vector<double>{h});
    };
    const RunResult gpu = step("gpu-vbd-compute"), newton = step("implicit-euler-newton"), cpu = step("vbd");
    ASSERT_EQ(gpu.status, Status::ok) << scene.name << ": " << gpu.message;
    ASSERT_EQ(newton.status, Status::ok) << newton.message;
    const SpringStep at(scene);
    const Eigen::Index n = scene.y.size() / 2;
    // Newton's own tolerance (1e-5 m/s) on each side of the comparison
    const double bound = at.bound(newton.y_stop.head(n)) + 2 * NewtonOnPotential{}.velocity_tolerance * h * std::sqrt(double(n));
    const double gap = (gpu.y_stop.head(n) - newton.y_stop.head(n)).norm();
    std::cout << scene.name << ": gpu-vbd-compute " << gap << " m from implicit-euler-newton's step (bound " << bound << "), G's decrease "
              << gpu.stats.potential_decrease << " J (vbd's " << cpu.stats.potential_decrease << ")\n";
    EXPECT_LE(gap, bound) << scene.name;
    EXPECT_LE((gpu.y_stop.tail(n) - newton.y_stop.tail(n)).norm(), bound / h) << scene.name << ": the velocity, (x1 - x0) / h";
    EXPECT_EQ(gpu.stats.colours, cpu.stats.colours) << scene.name;
    EXPECT_GT(gpu.stats.potential_decrease, 0) << scene.name;
  }
  // and only on a network of springs: the continuum cloth's elements are not in the pass
  const auto continuum = make_model("cloth", {{"continuum", 1.0}, {"rows", 4}, {"columns", 4}});
  EXPECT_FALSE(method_applies(*find_method("gpu-vbd-compute"), *continuum));
  EXPECT_NE(method_requirement(*find_method("gpu-vbd-compute"), *continuum).find("springs alone"), std::string::npos);
}

}  // namespace
}  // namespace stepwise
