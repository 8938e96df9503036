// The equations model (a user's system in a scene file, models/equations.hpp) against what it must equal: the
// built-in pendulum on every method, hand-written right-hand sides, central-difference Jacobians, its own
// interpreter (bitwise), and the methods' documented orders on a scene with an exact solution.
#include "models/equations.hpp"
#include "models/native_code.hpp"
#include "run/scene.hpp"
#include "solvers/fd_jacobian.hpp"
#include "verification/convergence.hpp"
#include "verification/stability.hpp"
#include "verification/tolerances.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <chrono>
#include <fstream>
#include <random>
#include <thread>

#include <sys/stat.h>
#include <unistd.h>

namespace stepwise {
namespace {

std::string scene_path(const std::string& name) { return std::string(STEPWISE_SOURCE_DIR) + "/scenes/" + name + ".toml"; }

EquationsSpec spec_of(const std::string& name) { return *load_scene(scene_path(name)).equations; }

const char* shipped[] = {"pendulum-equations", "van-der-pol", "van-der-pol-stiff", "lorenz", "double-pendulum", "duffing", "damped-oscillator"};

// a compile cache of the test's own, removed after it
struct TemporaryCache {
  std::filesystem::path dir = std::filesystem::temp_directory_path() / ("stepwise-test-cache-" + std::to_string(::getpid()));
  TemporaryCache() { ::setenv("STEPWISE_CACHE", dir.c_str(), 1); }
  ~TemporaryCache() { std::filesystem::remove_all(dir); }
};

// each test compiles into a cache of its own
class Equations : public ::testing::Test {
 protected:
  TemporaryCache cache_;
};

Eigen::VectorXd random_state(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-2, 2);
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) y[i] = u(rng);
  return y;
}

TEST_F(Equations, ThePendulumWrittenAsEquationsRunsAsTheBuiltInOneOnEveryMethod) {
  const auto written = make_equations(spec_of("pendulum-equations"), {});
  const auto builtin = make_model("pendulum", {{"theta0", 1.0}});
  ASSERT_TRUE(equations_evaluation(*written)->compiled) << equations_evaluation(*written)->detail;
  int compared = 0, applying = 0;
  for (const auto& method : methods()) {
    applying += method_applies(method, *builtin) && method.family != Family::gpu;
    const bool written_applies = method_applies(method, *written), builtin_applies = method_applies(method, *builtin);
    // every method that takes the built-in pendulum takes the written one (x' = v is found: symplectic-euler and friends)
    if (method.family == Family::gpu) continue;  // float32 passes on a device, the same to float32 (test_gpu_shader)
    EXPECT_EQ(written_applies, builtin_applies) << method.name;
    if (!written_applies || !builtin_applies) continue;
    const StepControl control = method.fixed_step() ? StepControl::fixed(1e-3) : StepControl::adaptive(1e-8, 1e-11);
    const Measured a = run_and_measure(*written, method.name, control, 1.0, 1.0);
    const Measured b = run_and_measure(*builtin, method.name, control, 1.0, 1.0);
    ASSERT_EQ(a.result.status, Status::ok) << method.name << ": " << a.result.message;
    ASSERT_EQ(b.result.status, Status::ok) << method.name << ": " << b.result.message;
    EXPECT_LE((a.result.y_stop - b.result.y_stop).cwiseAbs().maxCoeff(), tolerance::equations_run_roundoff * std::max(1.0, b.result.y_stop.cwiseAbs().maxCoeff()))
        << method.name;
    EXPECT_EQ(a.result.stats.steps, b.result.stats.steps) << method.name;
    ++compared;
  }
  EXPECT_EQ(compared, applying);
  EXPECT_GT(compared, 30);
}

// the compiled f of a background compile, once it is in use (a hang bound only: a compile of these takes well under
// a second)
void wait_compiled(const Model& model) {
  for (int k = 0; k < 1200 && !equations_evaluation(model)->compiled && equations_evaluation(model)->compile_seconds == 0; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

// one function, one unit (the default for small systems); parts of one or two values each (the values that a later
// part reads kept in the workspace) in units of one or two parts, compiled in parallel and linked; the same
// compiled in the background while the interpreter runs
const std::pair<const char*, EquationsOptions> layouts[] = {
    {"one unit", EquationsOptions{}},
    {"parts in units", EquationsOptions{.function_bytes = 32, .unit_bytes = 256}},
    {"in the background", EquationsOptions{.function_bytes = 40, .unit_bytes = 300, .background_above = 0}},  // other units: not in the cache yet
};

TEST_F(Equations, CompiledAndInterpretedAgreeToTheBitAndTheJacobianIsTheDerivative) {
  std::mt19937 rng(7);
  for (const auto& [layout, options] : layouts)
  for (const char* name : shipped) {
    SCOPED_TRACE(layout);
    const auto spec = spec_of(name);
    const auto compiled = make_equations(spec, {}, options);
    const auto interpreted = make_equations(spec, {}, false);
    wait_compiled(*compiled);
    EXPECT_EQ(equations_evaluation(*compiled)->background, options.background_above == 0) << name;
    if (options.function_bytes < 1000) {
      EXPECT_GT(equations_evaluation(*compiled)->units, 1) << name;
    }
    ASSERT_TRUE(equations_evaluation(*compiled)->compiled) << name << ": " << equations_evaluation(*compiled)->detail;
    ASSERT_FALSE(equations_evaluation(*interpreted)->compiled) << name;
    const int n = compiled->size();
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::VectorXd y = random_state(n, rng);
      const double t = 0.37 * trial;
      Eigen::VectorXd f1(n), f2(n);
      compiled->rhs(t, y, f1);
      interpreted->rhs(t, y, f2);
      for (int i = 0; i < n; ++i) EXPECT_EQ(f1[i], f2[i]) << name << " f[" << i << "]";  // the same operations in the same order
      Eigen::MatrixXd j1(n, n), j2(n, n), fd(n, n);
      compiled->as<DenseJacobian>()->jacobian(t, y, j1);
      interpreted->as<DenseJacobian>()->jacobian(t, y, j2);
      EXPECT_EQ(j1, j2) << name;
      fd_jacobian(*compiled, t, y, fd);
      EXPECT_LE((j1 - fd).cwiseAbs().maxCoeff(), tolerance::jacobian_fd * (1 + j1.cwiseAbs().maxCoeff())) << name << "\n" << j1 << "\n" << fd;
      // the sparse Jacobian is the dense one on its pattern
      Eigen::SparseMatrix<double> sparse;
      compiled->as<SparseJacobian>()->sparse_jacobian(t, y, sparse);
      EXPECT_EQ(Eigen::MatrixXd(sparse), j1) << name;
    }
  }
}

TEST_F(Equations, RightHandSidesEqualHandWrittenOnes) {
  // the formulas of the shipped scenes typed again by hand, in C++: each f agrees to a few ulps of its terms
  struct HandWritten {
    const char* scene;
    std::function<Eigen::VectorXd(double t, const Eigen::VectorXd& y)> f;
  };
  const HandWritten hand[] = {
      {"van-der-pol", [](double, const Eigen::VectorXd& y) { return Eigen::Vector2d(y[1], 1.0 * ((1 - y[0] * y[0]) * y[1] - y[0])).eval(); }},
      {"van-der-pol-stiff", [](double, const Eigen::VectorXd& y) { return Eigen::Vector2d(y[1], 1000.0 * ((1 - y[0] * y[0]) * y[1] - y[0])).eval(); }},
      {"lorenz", [](double, const Eigen::VectorXd& y) {
         return Eigen::Vector3d(10 * (y[1] - y[0]), y[0] * (28 - y[2]) - y[1], y[0] * y[1] - 8.0 / 3.0 * y[2]).eval();
       }},
      {"duffing", [](double t, const Eigen::VectorXd& y) {
         return Eigen::Vector2d(y[1], -0.3 * y[1] + y[0] - y[0] * y[0] * y[0] + 0.5 * std::cos(1.2 * t)).eval();
       }},
      {"double-pendulum", [](double, const Eigen::VectorXd& y) {
         const double g = 9.81, d = y[0] - y[1], den = 3 - std::cos(2 * d);
         const double a1 = (-g * 3 * std::sin(y[0]) - g * std::sin(y[0] - 2 * y[1]) - 2 * std::sin(d) * (y[3] * y[3] + y[2] * y[2] * std::cos(d))) / den;
         const double a2 = 2 * std::sin(d) * (y[2] * y[2] * 2 + g * 2 * std::cos(y[0]) + y[3] * y[3] * std::cos(d)) / den;
         return Eigen::Vector4d(y[2], y[3], a1, a2).eval();
       }},
  };
  std::mt19937 rng(11);
  for (const auto& h : hand) {
    const auto model = make_equations(spec_of(h.scene), {});
    for (int trial = 0; trial < 50; ++trial) {
      const Eigen::VectorXd y = random_state(model->size(), rng);
      const double t = 0.1 * trial;
      Eigen::VectorXd f(model->size());
      model->rhs(t, y, f);
      const Eigen::VectorXd expected = h.f(t, y);
      // a few ulps of the largest term: the terms are O(|y|^3 mu) at most
      const double scale = 1000 * (1 + y.cwiseAbs().maxCoeff()) * (1 + y.cwiseAbs().maxCoeff()) * (1 + y.cwiseAbs().maxCoeff());
      EXPECT_LE((f - expected).cwiseAbs().maxCoeff(), 16 * tolerance::formula_roundoff * scale) << h.scene << " at trial " << trial;
    }
  }
}

TEST_F(Equations, WhatTheModelKnowsOfItself) {
  const auto duffing = make_equations(spec_of("duffing"), {});
  EXPECT_FALSE(duffing->autonomous());  // cos(omega t)
  EXPECT_EQ(equations_evaluation(*duffing)->second_order, 1);
  const auto lorenz = make_equations(spec_of("lorenz"), {});
  EXPECT_TRUE(lorenz->autonomous());
  EXPECT_EQ(equations_evaluation(*lorenz)->second_order, 0);
  // Lorenz's Jacobian: x' = sigma (y - x) does not depend on z, z' = x y - beta z: 2 zeros off the diagonal
  Eigen::SparseMatrix<double> j;
  lorenz->as<SparseJacobian>()->sparse_jacobian(0, lorenz->initial_state(), j);
  EXPECT_EQ(j.nonZeros(), 8);
  const auto dp = make_equations(spec_of("double-pendulum"), {});
  EXPECT_EQ(equations_evaluation(*dp)->second_order, 2);
  // --set on an initial value and a parameter
  const auto vdp = make_equations(spec_of("van-der-pol"), {{"x", 0.5}, {"mu", 3.0}});
  EXPECT_EQ(vdp->initial_state()[0], 0.5);
  Eigen::VectorXd f(2);
  vdp->rhs(0, Eigen::Vector2d(1.0, 1.0), f);
  EXPECT_EQ(f[1], 3.0 * ((1 - 1.0) * 1.0 - 1.0));
  EXPECT_THROW(make_equations(spec_of("van-der-pol"), {{"nu", 1.0}}), BadParameter);
  // [exact] used where it solves the initial state, not when --set moved the start off it
  const auto exact = make_equations(spec_of("damped-oscillator"), {});
  EXPECT_TRUE(exact->has_exact());
  const auto moved = make_equations(spec_of("damped-oscillator"), {{"x", 2.0}});
  EXPECT_FALSE(moved->has_exact());
  EXPECT_FALSE(equations_evaluation(*moved)->exact_note.empty());
  // the energy of the double pendulum is conserved by a tight run
  const Measured m = run_and_measure(*dp, "verner98", StepControl::adaptive(1e-12, 1e-14), 5.0, 5.0);
  ASSERT_EQ(m.result.status, Status::ok);
  EXPECT_NEAR(*dp->energy(m.result.y_stop), *dp->energy(dp->initial_state()), 1e-8 * std::abs(*dp->energy(dp->initial_state())));
}

TEST_F(Equations, FixedStepMethodsKeepTheirOrderOnAnEquationsScene) {
  // the damped oscillator against its [exact]: velocity-dependent acceleration, so a method that treats a(x) as
  // v-independent would lose order here. Same windows and band as test_order, which gives the 5(4) pairs built
  // for a small principal error coefficient (Dormand-Prince, Tsitouras: slopes 5.33 here, their sixth-order term
  // competing) and the orders above 5 longer runs of their own
  const auto long_run = [](std::string_view name) {
    return name == "arkode-erk-dormand-prince54" || name == "odeint-dopri5" || name == "tsitouras54";
  };
  const auto model = make_equations(spec_of("damped-oscillator"), {});
  ASSERT_TRUE(model->has_exact());
  int checked = 0;
  for (const auto& method : methods()) {
    if (!method.fixed_step() || !method_applies(method, *model) || method.order.min != method.order.max || method.order.max > 5 || method.family == Family::gpu ||
        long_run(method.name))
      continue;
    const ConvergenceSweep sweep = convergence_sweep(*model, method, 5.0, 6, coarse_dt(method, 0.25));
    if (sweep.fit_dt.size() < 5u) {
      ADD_FAILURE() << method.name << ": fewer than four halvings in the asymptotic range";
      continue;
    }
    std::cout << method.name << ": observed order " << sweep.observed_order << " (documented " << method.order.text << ")\n";
    EXPECT_NEAR(sweep.observed_order, method.order.max, tolerance::order_band) << method.name;
    ++checked;
  }
  EXPECT_GT(checked, 20);
}

TEST_F(Equations, StiffVanDerPolRunsOnCvodeBdfWithTheExactSparseJacobian) {
  const auto model = make_equations(spec_of("van-der-pol-stiff"), {});
  const Measured m = run_and_measure(*model, "cvode-bdf", StepControl::adaptive(1e-6, 1e-9), 2.0, 2.0);
  ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
  EXPECT_GT(m.result.stats.jac_evals, 0);
  // an explicit method at the step cvode-bdf averages diverges: the fast eigenvalue -mu (x^2 - 1) ~ -3000
  const double mean_step = 2.0 / static_cast<double>(m.result.stats.steps);
  const Measured explicit_run = run_and_measure(*model, "rk4", StepControl::fixed(mean_step), 2.0, 2.0);
  EXPECT_NE(explicit_run.result.status, Status::ok) << "rk4 at dt " << mean_step;
}

TEST_F(Equations, TheCacheLoadsOnlyWhatItWrote) {
  const auto spec = spec_of("lorenz");
  std::string so;
  {
    const auto first = make_equations(spec, {});
    ASSERT_TRUE(equations_evaluation(*first)->compiled);
    so = equations_evaluation(*first)->detail;
  }
  ASSERT_TRUE(std::filesystem::exists(so));
  // overwritten by a foreign file of the same size: its sum no longer matches, so it is compiled again
  const auto size = std::filesystem::file_size(so);
  { std::ofstream(so, std::ios::binary | std::ios::trunc) << std::string(size, 'x'); }
  const auto second = make_equations(spec, {});
  ASSERT_TRUE(equations_evaluation(*second)->compiled) << equations_evaluation(*second)->detail;
  Eigen::VectorXd f(3);
  second->rhs(0, Eigen::Vector3d(1, 2, 3), f);
  EXPECT_EQ(f[0], 10.0 * (2 - 1));
  // no compiler: the interpreter, and the reason
  ::setenv("STEPWISE_CC", "/nonexistent/cc", 1);
  const auto spec2 = spec_of("duffing");
  const auto third = make_equations(spec2, {});
  ::unsetenv("STEPWISE_CC");
  EXPECT_FALSE(equations_evaluation(*third)->compiled);
  EXPECT_NE(equations_evaluation(*third)->detail.find("no C compiler"), std::string::npos) << equations_evaluation(*third)->detail;
}

// a cache entry tampered with is compiled anew, never loaded: the .so with a byte flipped (in its .comment, so it
// would still load), its .sum changed, the .so made group- or world-writable, replaced by a link to a good copy,
// truncated. A cache directory others can write to is not used at all (the interpreter, saying why)
TEST_F(Equations, ATamperedCacheEntryIsCompiledAnewNeverLoaded) {
  namespace fs = std::filesystem;
  const auto spec = spec_of("lorenz");
  const auto evaluation_of_new_model = [&] { return *equations_evaluation(*make_equations(spec, {})); };
  const auto first = evaluation_of_new_model();
  ASSERT_TRUE(first.compiled && !first.from_cache) << first.detail;
  const fs::path so = first.detail, sum = fs::path(first.detail).replace_extension(".sum");
  ASSERT_TRUE(evaluation_of_new_model().from_cache) << "an untouched entry is loaded";
  const fs::path good = cache_.dir / "good-copy.so";
  fs::copy_file(so, good);
  const auto read = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const auto write = [](const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes; };
  const std::pair<const char*, std::function<void()>> tamperings[] = {
      {"a byte of the .so flipped", [&] {
         std::string bytes = read(so);
         const auto at = bytes.find("GCC: (");
         ASSERT_NE(at, std::string::npos);
         bytes[at + 6] ^= 0x20;
         write(so, bytes);
       }},
      {"the .sum changed", [&] {
         std::string line = read(sum);
         line[line.size() - 2] = line[line.size() - 2] == '0' ? '1' : '0';
         write(sum, line);
       }},
      {"the .so group-writable", [&] { ::chmod(so.c_str(), 0620); }},
      {"the .so world-writable", [&] { ::chmod(so.c_str(), 0602); }},
      {"the .so a symbolic link", [&] {
         fs::remove(so);
         fs::create_symlink(good, so);
       }},
      {"the .so truncated", [&] { fs::resize_file(so, fs::file_size(so) / 2); }},
  };
  for (const auto& [what, tamper] : tamperings) {
    tamper();
    const auto e = evaluation_of_new_model();
    EXPECT_TRUE(e.compiled && !e.from_cache) << what << ": " << e.detail;
    EXPECT_FALSE(fs::is_symlink(so)) << what;
    EXPECT_EQ(fs::status(so).permissions() & (fs::perms::group_write | fs::perms::others_write), fs::perms::none) << what;
  }
  // the directory writable by others: neither loaded from nor compiled into
  ::chmod(cache_.dir.c_str(), 0777);
  const auto open_dir = evaluation_of_new_model();
  ::chmod(cache_.dir.c_str(), 0700);
  EXPECT_FALSE(open_dir.compiled);
  EXPECT_NE(open_dir.detail.find("writable by others"), std::string::npos) << open_dir.detail;
}

// a shared object that compiles and does not load: dlopen's message, read once, is the reason given
TEST_F(Equations, AnObjectThatDoesNotLoadSaysWhy) {
  std::string why;
  const auto code = load_native("extern void stepwise_no_such_function(void);\nvoid stepwise_rhs(void) { stepwise_no_such_function(); }\n", why);
  EXPECT_EQ(code, nullptr);
  EXPECT_NE(why.find("did not load"), std::string::npos) << why;
  EXPECT_NE(why.find("stepwise_no_such_function"), std::string::npos) << why;
}

// a compiler that hangs is stopped at its time limit, and the interpreter runs, saying so; a compile cancelled
// (the model gone) likewise; no compiler process outlives either
TEST_F(Equations, AHangingCompilerIsStoppedAndTheInterpreterRuns) {
  const std::string hanging = (cache_.dir / "hanging-cc").string();
  std::filesystem::create_directories(cache_.dir);
  // its child sleeps for a time no other process on the machine is likely to (300 s and this process's id in
  // microseconds), so that the look for it below finds it alone
  const std::string sleep_for = fmt::format("300.{:06d}", ::getpid() % 1000000);
  std::ofstream(hanging) << "#!/bin/sh\nsleep " << sleep_for << " &\nwait\n";
  ::chmod(hanging.c_str(), 0700);
  ::setenv("STEPWISE_CC", hanging.c_str(), 1);
  EquationsOptions options;
  options.compile_seconds = 0.5;
  const auto model = make_equations(spec_of("duffing"), {}, options);
  ::unsetenv("STEPWISE_CC");
  const auto e = *equations_evaluation(*model);
  EXPECT_FALSE(e.compiled);
  EXPECT_NE(e.detail.find("longer than its 0.5 s limit"), std::string::npos) << e.detail;
  // the script's sleep was in the compiler's process group: gone with it (a zombie has no command line). SIGKILL
  // is delivered asynchronously: on a loaded machine (the suite in parallel) the process can still be listed for
  // a moment after the group was killed, so it is looked for until it is gone, within a hang bound of 10 s
  const std::string command = "sleep" + std::string(1, '\0') + sleep_for + std::string(1, '\0');
  const auto sleeping = [&command] {
    for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
      std::ifstream in(entry.path() / "cmdline", std::ios::binary);
      const std::string line((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      if (line == command) return true;
    }
    return false;
  };
  bool still = sleeping();
  for (int k = 0; k < 200 && still; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    still = sleeping();
  }
  EXPECT_FALSE(still) << "the hanging compiler's child still runs 10 s after its group was killed";
}

}  // namespace
}  // namespace stepwise

namespace stepwise {
namespace {

// the Rosenbrock methods' stability functions: from the tableau in closed form, as measured by one step on
// y' = z y, of their order, A-stable and L-stable
TEST(Rosenbrock, StabilityFunctionsAreOfTheirOrderAndLStable) {
  for (const char* name : {"rodas4", "rodas5"}) {
    const Method& method = *find_method(name);
    ASSERT_TRUE(method.stability.R) << name;
    const auto measured = measured_stability_function(method);
    ASSERT_TRUE(measured.has_value()) << name;
    for (const std::complex<double> z : {std::complex<double>(-0.5, 0.3), {-20, 5}, {-3, 0}, {0.2, 1.5}}) {
      const std::complex<double> r = method.stability.R(z), m = (*measured)(z);
      // the step solves W k = r by LU: round-off of a few eps x the stages' size (|k| up to ~30 |y| for these tableaus)
      EXPECT_NEAR(std::abs(r - m), 0.0, 1e-12 * (1 + std::abs(r))) << name << " at z = " << z;
    }
    // order p: R(z) - e^z = C z^(p+1) + ..., so halving z divides the difference by 2^(p+1); within the band
    const int p = method.order.max;
    const std::complex<double> z(-0.08, 0.04);  // R - e^z ~ 1e-11 here, far above the round-off of R (1e-15)
    const double slope = std::log2(std::abs(method.stability.R(z) - std::exp(z)) / std::abs(method.stability.R(z / 2.0) - std::exp(z / 2.0)));
    EXPECT_NEAR(slope, p + 1, tolerance::order_band) << name;
    // A-stable: |R| <= 1 on the imaginary axis (the left half-plane's boundary; R is analytic there), L-stable:
    // R -> 0 at infinity (stiffly accurate: R(infinity) = 0 exactly)
    for (double y = 0.01; y < 1e6; y *= 1.5) EXPECT_LE(std::abs(method.stability.R({0, y})), 1 + 1e-12) << name << " at iy, y = " << y;
    EXPECT_LT(std::abs(method.stability.R({-1e8, 0})), 1e-6) << name;
  }
}

}  // namespace
}  // namespace stepwise

namespace stepwise {
namespace {

// rodas4's and rodas5's dense output: 1000 output times over the damped oscillator, between steps, each within
// the bound against the exact solution
TEST(Rosenbrock, DenseOutputFollowsTheSolutionBetweenSteps) {
  const TemporaryCache cache;
  const auto model = make_equations(*load_scene(std::string(STEPWISE_SOURCE_DIR) + "/scenes/damped-oscillator.toml").equations, {});
  const double rtol = 1e-7;
  for (const char* name : {"rodas4", "rodas5"}) {
    const Measured m = run_and_measure(*model, name, StepControl::adaptive(rtol, 1e-3 * rtol), 5.0, 5.0 / 1000);
    ASSERT_EQ(m.result.status, Status::ok) << name;
    EXPECT_LT(m.result.stats.steps, 1000) << name << ": the steps pass over the output times";
    double worst = 0;
    for (size_t k = 0; k < m.result.trajectory.t.size(); ++k)
      worst = std::max(worst, (m.result.trajectory.y[k] - model->exact(m.result.trajectory.t[k])).cwiseAbs().maxCoeff());
    EXPECT_LE(worst, tolerance::dense_output_rtols * rtol * 3) << name;  // |y| <= 3: the velocity's amplitude
  }
}

}  // namespace
}  // namespace stepwise

#include "report/advise.hpp"
#include "report/user_scene.hpp"

namespace stepwise {
namespace {

// the advice's pick on a shipped scene against a full sweep at every third of a decade of the advised method: the
// advice's search ran the coarsest setting on that grid meeting the error, and its pick meets the error (settings,
// not timings: the pick is the cheapest point measured, and where two settings cost within the CPU clock's noise
// of each other, as verner98's rtol 4.64e-4 and 1e-4 do on the damped oscillator at 16 and 18 steps, either may be it)
TEST(Advice, FindsTheAdvisedMethodsCoarsestSettingMeetingTheError) {
  const TemporaryCache cache;
  for (const char* scene_name : {"van-der-pol", "damped-oscillator"}) {
    RunOptions options;
    options.scene_file = std::string(STEPWISE_SOURCE_DIR) + "/scenes/" + scene_name + ".toml";
    const StudyScene scene = user_study_scene(options);
    const double target = 1e-6;
    const Advice advice = advise(scene, target, 8, 2);
    ASSERT_FALSE(advice.candidates.empty());
    ASSERT_TRUE(advice.candidates[0].cheapest.has_value()) << scene_name;
    const AdvisePoint& advised = *advice.candidates[0].cheapest;
    const auto model = scene_model(scene);
    std::optional<Eigen::VectorXd> reference;
    if (!model->has_exact()) reference = converged_reference(*model, scene.t_end).y;
    const auto full = full_sweep(scene, *find_method(advised.method), target, reference ? &*reference : nullptr, 20);
    ASSERT_FALSE(full.empty());
    const AdvisePoint& first = full.back();  // the sweep stops at the first setting meeting the target
    ASSERT_TRUE(first.error && *first.error <= target) << scene_name;
    EXPECT_TRUE(advised.error && *advised.error <= target) << scene_name;
    const bool searched = std::any_of(advice.points.begin(), advice.points.end(),
                                      [&](const AdvisePoint& p) { return p.method == advised.method && p.setting() == first.setting(); });
    EXPECT_TRUE(searched) << scene_name << ": " << advised.method << "'s search never ran " << first.setting() << " (advised: " << advised.setting() << ")";
    EXPECT_FALSE(advice.stiff) << scene_name;
  }
}

}  // namespace
}  // namespace stepwise
