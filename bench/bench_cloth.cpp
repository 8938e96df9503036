// The seeds' flag (the cloth model's defaults: four corners pinned, gusting wind) at N x N nodes, N = 32,
// 64, 128, one implicit Euler step of dt = 0.01 from the state 0.1 s into the run. In one run:
//  - the linear solve of Baraff & Witkin's step, M - h D - h^2 K, refactorised by CHOLMOD (analysis kept)
//    against Eigen's SimplicialLDLT refactorised (pattern analysed once) and Eigen's conjugate gradients
//    with a diagonal preconditioner, each to a relative residual of 1e-8;
//  - CHOLMOD's symbolic analysis with AMD and with METIS (flops of the factor each predicts);
//  - the best a kept factor can do: CG on the next step's matrix preconditioned by this step's factor, on
//    the flag and on the hanging sheet, against refactorising;
//  - whole steps: implicit-euler as the project runs it (a kept CHOLMOD factor preconditioning CG, refreshed
//    when the iterations climb), against the same step refactorising every step, and against Liu et al.'s
//    prefactored fast-mass-spring;
//  - the continuum flag (`continuum = 1`: StVK membrane and bending elements on the same grid, 32 and 64) against
//    the spring flag: assembly (force Jacobians, each element's Hessian projected, and the matrix), CHOLMOD's
//    refactorisation and solve, and a whole implicit-euler step, the symbolic analysis kept across steps; and
//    the continuum's assembly with the exact K against the projected one (what the projection costs);
//  - one 1/60 s frame (one step from the same state) of backward Euler by Newton on the incremental potential
//    (implicit-euler-newton) against the linearised step (implicit-euler, refactorising), springs and continuum, with
//    the Newton iterations a frame, and its parts: the potential's gradient and its Hessian's assembly (the
//    factorisation and the solve are the refactor and solve rows above);
//  - a run's 1/60 s frames (the flag's first second from rest, the steppers' factors kept from frame to frame, as
//    the report runs them): the continuum's and the springs' converged frame (implicit-euler-newton) against the
//    springs' linearised one (implicit-euler), the ratio the aim is stated in.
// One core: CHOLMOD's BLAS is kept on the calling thread (sparse_cholesky.cpp). The BLAS is Debian's
// alternative (OpenBLAS when installed); LD_LIBRARY_PATH=/usr/lib/x86_64-linux-gnu/blas runs the reference
// BLAS instead. The program prints the library its dgemm_ comes from.
#include "run/scene.hpp"
#include "models/model.hpp"
#include "solvers/method_table.hpp"
#include "solvers/incremental_potential.hpp"
#include "solvers/mass_spring_implicit.hpp"
#include "solvers/run_support.hpp"
#include "solvers/sparse_cholesky.hpp"

#include "ratio_reporter.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <dlfcn.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <thread>
#include <tuple>

namespace {

using stepwise::Params;
constexpr double dt = 0.01;
constexpr double residual = 1e-8;

struct Flag {
  std::unique_ptr<stepwise::Model> model;
  Eigen::VectorXd y;
  stepwise::Stats stats;
  std::unique_ptr<stepwise::CountedSystem> counted;
  std::unique_ptr<stepwise::BaraffWitkinSystem> bw;
};

// the flag (the model's defaults), or a scene file's cloth, at n x n nodes; springs, or the continuum
Flag& flag(int n, const std::string& scene = {}, bool continuum = false) {
  static std::map<std::tuple<int, std::string, bool>, Flag> flags;
  auto [it, fresh] = flags.try_emplace({n, scene, continuum});
  Flag& f = it->second;
  if (fresh) {
    Params params = scene.empty() ? Params{} : stepwise::load_scene(stepwise::scenes_directory() + "/" + scene + ".toml").parameters;
    params["rows"] = params["columns"] = n;
    params["continuum"] = continuum ? 1 : 0;
    f.model = stepwise::make_model("cloth", params);
    const std::vector<double> t_out{0.1};
    f.y = stepwise::make_integrator("implicit-euler", stepwise::StepControl::fixed(dt))->integrate(*f.model, 0, f.model->initial_state(), t_out).y_stop;
    f.counted = std::make_unique<stepwise::CountedSystem>(*f.model, f.stats);
    f.bw = std::make_unique<stepwise::BaraffWitkinSystem>(*f.counted, true);
    f.bw->assemble_matrix(0.1, f.y, dt);
    f.bw->assemble_rhs(f.y, dt);
  }
  return f;
}

// a numeric factorisation and a solve, the analysis kept
void refactor_and_solve(benchmark::State& state, const std::string& scene, bool continuum = false) {
  Flag& f = flag(static_cast<int>(state.range(0)), scene, continuum);
  stepwise::SparseCholesky cholesky;
  cholesky.analyze(f.bw->matrix(), stepwise::Ordering::cheaper);
  Eigen::MatrixXd x;
  for (auto _ : state) {
    cholesky.factorize(f.bw->matrix());
    cholesky.solve(f.bw->rhs(), x);
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["unknowns"] = static_cast<double>(f.bw->rhs().size());
  state.SetLabel(cholesky.analysis().ordering + " (the cheaper)");
  state.counters["residual"] = (f.bw->rhs() - f.bw->matrix() * x.col(0)).norm() / f.bw->rhs().norm();
}
void BM_cholmod_refactor(benchmark::State& state) { refactor_and_solve(state, {}); }
void BM_hanging_cholmod_refactor(benchmark::State& state) { refactor_and_solve(state, "hanging-cloth"); }
void BM_continuum_cholmod_refactor(benchmark::State& state) { refactor_and_solve(state, {}, true); }

// one pair of triangular solves with a factor
void BM_cholmod_solve(benchmark::State& state) {
  Flag& f = flag(static_cast<int>(state.range(0)));
  stepwise::SparseCholesky cholesky;
  cholesky.analyze(f.bw->matrix(), stepwise::Ordering::cheaper);
  cholesky.factorize(f.bw->matrix());
  Eigen::MatrixXd x;
  for (auto _ : state) {
    cholesky.solve(f.bw->rhs(), x);
    benchmark::DoNotOptimize(x.data());
  }
}

// the step's matrix and right-hand side: force Jacobians, M - h D - h^2 K, f, b
void assemble(benchmark::State& state, bool continuum) {
  Flag& f = flag(static_cast<int>(state.range(0)), {}, continuum);
  for (auto _ : state) {
    f.bw->assemble_matrix(0.1, f.y, dt);
    f.bw->assemble_rhs(f.y, dt);
    benchmark::DoNotOptimize(f.bw->rhs().data());
  }
}
void BM_assemble(benchmark::State& state) { assemble(state, false); }
void BM_continuum_assemble(benchmark::State& state) { assemble(state, true); }
// the same with the exact K: what the per-element projection costs
void BM_continuum_assemble_exact(benchmark::State& state) {
  Flag& f = flag(static_cast<int>(state.range(0)), {}, true);
  stepwise::BaraffWitkinSystem exact(*f.counted, false);
  for (auto _ : state) {
    exact.assemble_matrix(0.1, f.y, dt);
    exact.assemble_rhs(f.y, dt);
    benchmark::DoNotOptimize(exact.rhs().data());
  }
}

void BM_eigen_ldlt_refactor(benchmark::State& state) {
  Flag& f = flag(static_cast<int>(state.range(0)));
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  ldlt.analyzePattern(f.bw->matrix());
  Eigen::VectorXd x;
  for (auto _ : state) {
    ldlt.factorize(f.bw->matrix());
    x = ldlt.solve(f.bw->rhs());
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["residual"] = (f.bw->rhs() - f.bw->matrix() * x).norm() / f.bw->rhs().norm();
}

void BM_diagonal_pcg(benchmark::State& state) {
  Flag& f = flag(static_cast<int>(state.range(0)));
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg;
  cg.setTolerance(residual);
  cg.setMaxIterations(100000);
  Eigen::VectorXd x;
  for (auto _ : state) {
    cg.compute(f.bw->matrix());
    x = cg.solve(f.bw->rhs());
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["iterations"] = static_cast<double>(cg.iterations());
  state.counters["residual"] = (f.bw->rhs() - f.bw->matrix() * x).norm() / f.bw->rhs().norm();
}

void analyse(benchmark::State& state, stepwise::Ordering ordering) {
  Flag& f = flag(static_cast<int>(state.range(0)));
  stepwise::SparseCholesky cholesky;
  for (auto _ : state) cholesky.analyze(f.bw->matrix(), ordering);
  state.counters["factor_Mflop"] = cholesky.analysis().flops / 1e6;
  state.counters["factor_nnz"] = cholesky.analysis().factor_nonzeros;
}
void BM_cholmod_analyze_amd(benchmark::State& state) { analyse(state, stepwise::Ordering::amd); }
void BM_cholmod_analyze_metis(benchmark::State& state) { analyse(state, stepwise::Ordering::metis); }

// the best any kept factor can do: CG to the residual on the matrix one step on, preconditioned by the
// factor of this step's matrix and started from this step's dv (a factor older than one step, or a worse
// guess, only needs more iterations); against a refactorisation and solve, the most a kept factor can save
void previous_factor_cg(benchmark::State& state, const std::string& scene) {
  Flag& f = flag(static_cast<int>(state.range(0)), scene);
  stepwise::SparseCholesky cholesky;
  cholesky.analyze(f.bw->matrix(), stepwise::Ordering::cheaper);
  cholesky.factorize(f.bw->matrix());
  Eigen::MatrixXd dv;
  cholesky.solve(f.bw->rhs(), dv);
  Eigen::VectorXd next;
  std::string failure;
  stepwise::MassSpringImplicitOptions options;
  options.solve = stepwise::LinearSolve::refactor;
  if (!stepwise::make_mass_spring_implicit(*f.counted, options)->step(0.1, dt, f.y, next, failure)) state.SkipWithError(failure.c_str());
  stepwise::BaraffWitkinSystem later(*f.counted, true);
  later.assemble_matrix(0.1 + dt, next, dt);
  later.assemble_rhs(next, dt);
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper, stepwise::FactorPreconditioner> cg;
  cg.setTolerance(residual);
  cg.setMaxIterations(10000);
  cg.preconditioner().use(&cholesky);
  cg.compute(later.matrix());
  Eigen::VectorXd x;
  for (auto _ : state) {
    x = cg.solveWithGuess(later.rhs(), dv.col(0));
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["solves"] = static_cast<double>(cg.iterations() + 1);  // Eigen counts the iterations after the first
  state.counters["residual"] = (later.rhs() - later.matrix() * x).norm() / later.rhs().norm();
}
void BM_previous_factor_cg(benchmark::State& state) { previous_factor_cg(state, {}); }
void BM_hanging_previous_factor_cg(benchmark::State& state) { previous_factor_cg(state, "hanging-cloth"); }

// steps of dt from the fixture's state, one stepper for the whole benchmark (its symbolic analysis, done at
// the first step, is set apart first), 10 steps per iteration; time per step
void steps(benchmark::State& state, const stepwise::FixedStepperFactory& make, const std::string& scene = {}, bool continuum = false) {
  Flag& f = flag(static_cast<int>(state.range(0)), scene, continuum);
  stepwise::Stats stats;
  stepwise::CountedSystem counted(*f.model, stats);
  auto stepper = make(counted);
  Eigen::VectorXd y = f.y, next;
  std::string failure;
  double t = 0.1;
  const auto take = [&]() {
    if (!stepper->step(t, dt, y, next, failure)) state.SkipWithError(failure.c_str());
    y.swap(next);
    t += dt;
  };
  take();
  stats = {};
  long taken = 0;
  for (auto _ : state) {
    for (int k = 0; k < 10; ++k) take();
    taken += 10;
  }
  state.SetItemsProcessed(taken);
  state.counters["ms/step"] = benchmark::Counter(static_cast<double>(taken) / 1e3, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["solves/step"] = static_cast<double>(stats.linear_solves) / static_cast<double>(taken);
  state.counters["factors/step"] = static_cast<double>(stats.factorizations) / static_cast<double>(taken);
}
std::unique_ptr<stepwise::FixedStepper> refactoring(const stepwise::CountedSystem& s) {
  stepwise::MassSpringImplicitOptions options;
  options.solve = stepwise::LinearSolve::refactor;
  return stepwise::make_mass_spring_implicit(s, options);
}
void BM_step_kept_factor(benchmark::State& state) { steps(state, stepwise::make_implicit_euler); }
void BM_step_refactor(benchmark::State& state) { steps(state, refactoring); }
// the sheet hanging from two corners (scenes/hanging-cloth.toml): no wind, its matrix changes slowly
void BM_hanging_step_kept_factor(benchmark::State& state) { steps(state, stepwise::make_implicit_euler, "hanging-cloth"); }
void BM_hanging_step_refactor(benchmark::State& state) { steps(state, refactoring, "hanging-cloth"); }
void BM_step_fast_mass_spring(benchmark::State& state) { steps(state, stepwise::make_fast_mass_spring); }
void BM_continuum_step_kept_factor(benchmark::State& state) { steps(state, stepwise::make_implicit_euler, {}, true); }

// one 1/60 s frame from the flag's state at 0.1 s, by the step `newton` says, refactorising every solve
constexpr double frame = 1.0 / 60;
void one_frame(benchmark::State& state, bool newton, bool continuum) {
  Flag& f = flag(static_cast<int>(state.range(0)), {}, continuum);
  stepwise::MassSpringImplicitOptions options;
  options.newton = newton;
  options.solve = stepwise::LinearSolve::refactor;
  const auto stepper = stepwise::make_mass_spring_implicit(*f.counted, options);
  Eigen::VectorXd y_next;
  std::string failure;
  const long iterations = f.stats.newton_iterations;
  long frames = 0;
  for (auto _ : state) {
    if (!stepper->step(0.1, frame, f.y, y_next, failure)) state.SkipWithError(failure.c_str());
    benchmark::DoNotOptimize(y_next.data());
    ++frames;
  }
  state.counters["newton_iterations"] = static_cast<double>(f.stats.newton_iterations - iterations) / static_cast<double>(std::max(1L, frames));
}
// a run's frames: the flag's first seconds from rest (range(1) of them: the first, its fall from flat rest, costs the
// converged step the most; the whole 5 s the flag scene runs) in 1/60 s steps, each stepper as the method table makes it
// (implicit-euler: the kept factor preconditioning CG; implicit-euler-newton: that step, then Newton from it) and kept
// from frame to frame as a run keeps it: the mean frame, what a frame costs a user's run (the frame above is one step
// from a state the linearised step left, far from backward Euler's own motion: 75 Newton iterations on the continuum
// at 32^2 where a run averages 4 to 5)
void run_frames(benchmark::State& state, const stepwise::FixedStepperFactory& make, bool continuum) {
  Flag& f = flag(static_cast<int>(state.range(0)), {}, continuum);
  const int frames = 60 * static_cast<int>(state.range(1));
  stepwise::Stats stats;
  stepwise::CountedSystem counted(*f.model, stats);
  Eigen::VectorXd y, next;
  std::string failure;
  long runs = 0;
  for (auto _ : state) {
    const auto stepper = make(counted);
    y = f.model->initial_state();
    for (int k = 0; k < frames; ++k) {
      if (!stepper->step(k * frame, frame, y, next, failure)) state.SkipWithError(failure.c_str());
      y.swap(next);
    }
    ++runs;
  }
  const double taken = static_cast<double>(runs * frames);
  state.counters["ms/frame"] = benchmark::Counter(taken / 1e3, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["newton/frame"] = static_cast<double>(stats.newton_iterations) / taken;
  state.counters["factors/frame"] = static_cast<double>(stats.factorizations) / taken;
  state.counters["solves/frame"] = static_cast<double>(stats.linear_solves) / taken;
}
std::unique_ptr<stepwise::FixedStepper> converged(const stepwise::CountedSystem& s) {
  stepwise::MassSpringImplicitOptions options;
  options.newton = true;
  return stepwise::make_mass_spring_implicit(s, options);
}
void BM_run_frame_linearised(benchmark::State& state) { run_frames(state, stepwise::make_implicit_euler, false); }
void BM_run_frame_newton(benchmark::State& state) { run_frames(state, converged, false); }
void BM_continuum_run_frame_newton(benchmark::State& state) { run_frames(state, converged, true); }
// Newton with every direction from a fresh factor: the inexact Newton's gain, in the same run
std::unique_ptr<stepwise::FixedStepper> exactly_converged(const stepwise::CountedSystem& s) {
  stepwise::MassSpringImplicitOptions options;
  options.newton = options.exact_newton = true;
  return stepwise::make_mass_spring_implicit(s, options);
}
void BM_continuum_run_frame_exact_newton(benchmark::State& state) { run_frames(state, exactly_converged, true); }
void BM_frame_linearised(benchmark::State& state) { one_frame(state, false, false); }
void BM_frame_newton(benchmark::State& state) { one_frame(state, true, false); }
void BM_continuum_frame_linearised(benchmark::State& state) { one_frame(state, false, true); }
void BM_continuum_frame_newton(benchmark::State& state) { one_frame(state, true, true); }

// one 1/60 s frame from the flag's state at 0.1 s by a fixed-step method of the table: vbd or vbd-chebyshev (10
// sweeps, on `threads`) or xpbd (20 substeps of one sweep); wall-clock time (vbd's threads share the frame)
void frame_by(benchmark::State& state, const char* method, int threads, bool continuum) {
  Flag& f = flag(static_cast<int>(state.range(0)), {}, continuum);
  stepwise::StepControl control = stepwise::StepControl::fixed(frame);
  const bool vbd = std::string(method).starts_with("vbd");
  if (vbd) control.settings["threads"] = threads;
  control.settings["iterations"] = vbd ? 10 : 1;
  control.settings["substeps"] = vbd ? 1 : 20;
  const auto integrator = stepwise::make_integrator(method, control);
  const std::vector<double> t_out{0.1 + frame};
  for (auto _ : state) {
    const stepwise::RunResult r = integrator->solve(*f.model, 0.1, f.y, t_out);
    if (r.status != stepwise::Status::ok) state.SkipWithError(r.message.c_str());
    benchmark::DoNotOptimize(r.y_stop.data());
  }
}
void BM_frame_vbd(benchmark::State& state) { frame_by(state, "vbd", 1, false); }
void BM_frame_vbd_2_threads(benchmark::State& state) { frame_by(state, "vbd", 2, false); }
// on 4, 8, ... threads, up to the machine's cores (none on two; a lent device's 16): range(1) the threads
void BM_frame_vbd_on(benchmark::State& state) { frame_by(state, "vbd", static_cast<int>(state.range(1)), false); }
int cores() { return static_cast<int>(std::thread::hardware_concurrency()); }
void BM_frame_vbd_chebyshev(benchmark::State& state) { frame_by(state, "vbd-chebyshev", 1, false); }
void BM_frame_xpbd(benchmark::State& state) { frame_by(state, "xpbd", 1, false); }
void BM_continuum_frame_vbd(benchmark::State& state) { frame_by(state, "vbd", 1, true); }
void BM_continuum_frame_vbd_2_threads(benchmark::State& state) { frame_by(state, "vbd", 2, true); }
void BM_continuum_frame_vbd_chebyshev(benchmark::State& state) { frame_by(state, "vbd-chebyshev", 1, true); }

// the incremental potential's parts at the frame's start: its gradient, and its Hessian assembled (M - h D0 - h^2 K)
void potential_part(benchmark::State& state, bool continuum, bool hessian) {
  Flag& f = flag(static_cast<int>(state.range(0)), {}, continuum);
  stepwise::IncrementalPotential potential(*f.counted, *f.counted->as<stepwise::MassSpringView>());
  potential.start(0.1, f.y, frame);
  const Eigen::VectorXd x = potential.inertial();
  Eigen::VectorXd g;
  Eigen::SparseMatrix<double> a;
  for (auto _ : state) {
    if (hessian) potential.scaled_hessian(x, false, a);
    else potential.gradient(x, g);
    benchmark::DoNotOptimize(hessian ? a.valuePtr() : g.data());
  }
}
void BM_potential_gradient(benchmark::State& state) { potential_part(state, false, false); }
void BM_potential_hessian(benchmark::State& state) { potential_part(state, false, true); }
void BM_continuum_potential_gradient(benchmark::State& state) { potential_part(state, true, false); }
void BM_continuum_potential_hessian(benchmark::State& state) { potential_part(state, true, true); }

#define FLAG_SIZES ->Arg(32)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond)
BENCHMARK(BM_cholmod_analyze_amd) FLAG_SIZES;
BENCHMARK(BM_cholmod_analyze_metis) FLAG_SIZES;
BENCHMARK(BM_assemble) FLAG_SIZES;
BENCHMARK(BM_cholmod_refactor) FLAG_SIZES;
BENCHMARK(BM_cholmod_solve) FLAG_SIZES;
BENCHMARK(BM_eigen_ldlt_refactor) FLAG_SIZES;
BENCHMARK(BM_diagonal_pcg) FLAG_SIZES;
BENCHMARK(BM_previous_factor_cg) FLAG_SIZES;
BENCHMARK(BM_hanging_cholmod_refactor) FLAG_SIZES;
BENCHMARK(BM_hanging_previous_factor_cg) FLAG_SIZES;
BENCHMARK(BM_step_refactor) FLAG_SIZES;
BENCHMARK(BM_step_kept_factor) FLAG_SIZES;
BENCHMARK(BM_step_fast_mass_spring) FLAG_SIZES;
BENCHMARK(BM_hanging_step_refactor) FLAG_SIZES;
BENCHMARK(BM_hanging_step_kept_factor) FLAG_SIZES;
#define CONTINUUM_SIZES ->Arg(32)->Arg(64)->Unit(benchmark::kMillisecond)
BENCHMARK(BM_continuum_assemble) CONTINUUM_SIZES;
BENCHMARK(BM_continuum_assemble_exact) CONTINUUM_SIZES;
BENCHMARK(BM_continuum_cholmod_refactor) CONTINUUM_SIZES;
BENCHMARK(BM_continuum_step_kept_factor) CONTINUUM_SIZES;
BENCHMARK(BM_frame_linearised) CONTINUUM_SIZES;
BENCHMARK(BM_frame_newton) CONTINUUM_SIZES;
BENCHMARK(BM_continuum_frame_linearised) CONTINUUM_SIZES;
BENCHMARK(BM_continuum_frame_newton) CONTINUUM_SIZES;
// a run's first second and its whole 5 s, at 32^2 only (at 64^2 the continuum's second takes 45 s)
#define RUN_SECONDS ->Args({32, 1})->Args({32, 5})->Unit(benchmark::kMillisecond)
BENCHMARK(BM_run_frame_linearised) RUN_SECONDS;
BENCHMARK(BM_run_frame_newton) RUN_SECONDS;
BENCHMARK(BM_continuum_run_frame_newton) RUN_SECONDS;
BENCHMARK(BM_continuum_run_frame_exact_newton)->Args({32, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_frame_vbd) CONTINUUM_SIZES->UseRealTime();
BENCHMARK(BM_frame_vbd_2_threads) CONTINUUM_SIZES->UseRealTime();
BENCHMARK(BM_frame_vbd_chebyshev) CONTINUUM_SIZES->UseRealTime();
BENCHMARK(BM_frame_xpbd) CONTINUUM_SIZES;
BENCHMARK(BM_continuum_frame_vbd) CONTINUUM_SIZES->UseRealTime();
BENCHMARK(BM_continuum_frame_vbd_2_threads) CONTINUUM_SIZES->UseRealTime();
BENCHMARK(BM_continuum_frame_vbd_chebyshev) CONTINUUM_SIZES->UseRealTime();
BENCHMARK(BM_potential_gradient) CONTINUUM_SIZES;
BENCHMARK(BM_potential_hessian) CONTINUUM_SIZES;
BENCHMARK(BM_continuum_potential_gradient) CONTINUUM_SIZES;
BENCHMARK(BM_continuum_potential_hessian) CONTINUUM_SIZES;

}  // namespace

int main(int argc, char** argv) {
  // the library whose dgemm_ CHOLMOD calls (OpenBLAS may be loaded beside the reference BLAS, through LAPACK)
  Dl_info blas{};
  if (void* dgemm = dlsym(RTLD_DEFAULT, "dgemm_"); dgemm && dladdr(dgemm, &blas))
    std::printf("BLAS (dgemm_ from): %s\n", std::filesystem::weakly_canonical(blas.dli_fname).c_str());
  if (cores() >= 4)
    benchmark::RegisterBenchmark("BM_frame_vbd_on", BM_frame_vbd_on)
        ->Apply([](benchmark::internal::Benchmark* b) {
          for (const int n : {32, 64})
            for (int threads = 4; threads <= cores(); threads *= 2) b->Args({n, threads});
        })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const char* n : {"32", "64", "128"}) {
    const std::string arg = std::string("/") + n;
    pairs.emplace_back("BM_eigen_ldlt_refactor" + arg, "BM_cholmod_refactor" + arg);
    pairs.emplace_back("BM_diagonal_pcg" + arg, "BM_cholmod_refactor" + arg);
    pairs.emplace_back("BM_cholmod_analyze_metis" + arg, "BM_cholmod_analyze_amd" + arg);
    pairs.emplace_back("BM_cholmod_refactor" + arg, "BM_previous_factor_cg" + arg);
    pairs.emplace_back("BM_hanging_cholmod_refactor" + arg, "BM_hanging_previous_factor_cg" + arg);
    pairs.emplace_back("BM_step_refactor" + arg, "BM_step_kept_factor" + arg);
    pairs.emplace_back("BM_step_kept_factor" + arg, "BM_step_fast_mass_spring" + arg);
    pairs.emplace_back("BM_hanging_step_refactor" + arg, "BM_hanging_step_kept_factor" + arg);
  }
  // the aim: the continuum's converged frame within 3x the springs' linearised one, over a run's frames
  for (const char* seconds : {"/32/1", "/32/5"}) {
    pairs.emplace_back(std::string("BM_continuum_run_frame_newton") + seconds, std::string("BM_run_frame_linearised") + seconds);
    pairs.emplace_back(std::string("BM_run_frame_newton") + seconds, std::string("BM_run_frame_linearised") + seconds);
  }
  pairs.emplace_back("BM_continuum_run_frame_exact_newton/32/1", "BM_continuum_run_frame_newton/32/1");
  for (const char* n : {"32", "64"}) {
    const std::string arg = std::string("/") + n;
    pairs.emplace_back("BM_continuum_assemble" + arg, "BM_assemble" + arg);
    pairs.emplace_back("BM_continuum_assemble" + arg, "BM_continuum_assemble_exact" + arg);
    pairs.emplace_back("BM_continuum_cholmod_refactor" + arg, "BM_cholmod_refactor" + arg);
    pairs.emplace_back("BM_continuum_step_kept_factor" + arg, "BM_step_kept_factor" + arg);
    pairs.emplace_back("BM_continuum_frame_newton" + arg, "BM_frame_linearised" + arg);
    pairs.emplace_back("BM_frame_newton" + arg, "BM_frame_linearised" + arg);
    pairs.emplace_back("BM_continuum_frame_newton" + arg, "BM_continuum_frame_linearised" + arg);
    // vbd (10 sweeps) against xpbd (20 substeps) and Newton; its colour sweeps on two threads against one
    // (vbd timed in wall-clock time, "/real_time" in its name: its threads share the frame)
    const std::string real = arg + "/real_time";
    pairs.emplace_back("BM_frame_vbd" + real, "BM_frame_xpbd" + arg);
    pairs.emplace_back("BM_frame_vbd" + real, "BM_frame_newton" + arg);
    pairs.emplace_back("BM_continuum_frame_vbd" + real, "BM_continuum_frame_newton" + arg);
    pairs.emplace_back("BM_frame_vbd" + real, "BM_frame_vbd_2_threads" + real);
    for (int threads = 4; threads <= cores(); threads *= 2) pairs.emplace_back("BM_frame_vbd" + real, "BM_frame_vbd_on" + arg + "/" + std::to_string(threads) + "/real_time");
    pairs.emplace_back("BM_continuum_frame_vbd" + real, "BM_continuum_frame_vbd_2_threads" + real);
  }
  return stepwise::bench::run_with_ratios(argc, argv, pairs);
}
