// The seeds' GPU simulation (issue 9) on llvmpipe through OSMesa, no GPU needed: the wave scheme's
// fragment pass against the float32 CPU loop step for step, against float64 to show what precision costs,
// and against the exactly evolved DST modes.
#include "models/height_field.hpp"
#include "solvers/gpu/gpu_wave.hpp"
#include "solvers/integrator.hpp"
#include "verification/tolerances.hpp"
#include "verification/wave_modes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

namespace stepwise {
namespace {

render::Context& context() {
  static const std::unique_ptr<render::Context> c = render::make_osmesa_context();
  return *c;
}

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
  Shader(int points, double fraction, unsigned seed)
      : grid{points, 0.02, 1.0, 0.0},
        dt(fraction * wave_stable_dt(grid)),
        k(to_float(wave_coefficients(grid, dt))),
        z0(random_wave_field(points, 1.0, seed).cast<float>()),
        z1(random_wave_field(points, 1.0, seed + 1).cast<float>()),
        gpu(context(), points, k) {
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
  Shader shader(64, 0.9, 3);
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
    std::cout << steps << " steps: |shader - cpu float32| = " << shader_cpu << ", |cpu float32 - float64| = " << cpu_wide
              << ", bound " << bound << " (|z| = " << wide.norm() << ")\n";
    EXPECT_LE(shader_cpu, bound) << steps << " steps";
    EXPECT_LE((gpu_prev - cpu_prev).cast<double>().norm(), bound) << steps << " steps, the previous level";
    EXPECT_LE(cpu_wide, bound) << steps << " steps: float32's own round-off";
  }
}

TEST(GpuShader, ShaderStateMatchesTheExactlyEvolvedDstModes) {
  // the water issue's FFT check on the shader's state: every mode of a random state evolved by its exact
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
  gpu::GpuSymplecticWave gpu(context(), grid.points, static_cast<float>(c2), 0.0f, static_cast<float>(dt));
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
    std::cout << steps << " steps: |shader z - cpu float32 z| = " << difference << ", bound " << bound << " (|z| = " << z.norm() << ")\n";
    EXPECT_LE(difference, bound) << steps << " steps";
  }
}

TEST(GpuShader, GpuWaveMethodFollowsWaveFdToFloat32RoundOff) {
  // the method as `run` takes it (wave_fd.hpp's start in double, then passes on the device, each level
  // read back): against wave-fd on the standing wave, 400 steps at 0.9 of the limit; the state enters the
  // texture rounded to float (one more rounding, once) and the coefficients too (one more per step)
  gpu::register_gpu_methods();
  const auto model = make_model("standing-wave", {{"size", 33}, {"spacing", 1.0 / 32}, {"mode_m", 2}, {"mode_n", 3}, {"amplitude", 1.0}, {"mu", 0.0}});
  const WaveGridView grid = *model->wave_grid();
  const double dt = 0.9 * wave_stable_dt(grid);
  const long steps = 400;
  const std::vector<double> t_out{steps * dt};
  const auto run = [&](const char* method) { return make_integrator(method, StepControl::fixed(dt))->integrate(*model, 0, model->initial_state(), t_out); };
  const RunResult gpu = run("gpu-wave"), cpu = run("wave-fd");
  ASSERT_EQ(gpu.status, Status::ok) << gpu.message;
  const Eigen::Index cells = static_cast<Eigen::Index>(grid.points) * grid.points;
  const double difference = (gpu.y_stop.head(cells) - cpu.y_stop.head(cells)).norm();
  const auto k = to_float(wave_coefficients(grid, dt));
  const double bound = tolerance::float32_wave_bound(steps, sin_theta_min(grid, dt), coefficient_sum(k), model->initial_state().head(cells).cwiseAbs().maxCoeff(),
                                                     static_cast<double>(cells)) *
                       (tolerance::float32_wave_roundings + 2) / tolerance::float32_wave_roundings;
  std::cout << "gpu-wave against wave-fd after " << steps << " steps: " << difference << " (|z| = " << cpu.y_stop.head(cells).norm() << "), bound " << bound << '\n';
  EXPECT_LE(difference, bound);
}

TEST(GpuShader, AGridPastTheLargestTextureIsRefusedNamingTheLimit) {
  // the check the run makes before a GPU method starts (exit 2): no texture is made for it
  EXPECT_EQ(gpu::grid_problem(64), "");
  const std::string problem = gpu::grid_problem(1 << 20);
  std::cout << problem << '\n';
  EXPECT_NE(problem.find("GL_MAX_TEXTURE_SIZE = "), std::string::npos) << problem;
}

}  // namespace
}  // namespace stepwise
