// Work against precision, stepwise's own methods (hand-written pairs, ARKODE) against the peers a user would
// pick instead (Boost.Odeint's dopri5 and rkf78 on a fixed-size state, raw GSL rk8pd, raw CVODE Adams), on
// the pendulum released at 170 degrees to t = 10 s, the flow field and the projectile with drag. Every
// candidate runs at rtol = atol = 10^(-k/2), k = 2..24 (from 0.1: a method whose error estimate is cautious
// reaches a loose target from a loose tolerance, as a user would set it; the grid began at 1e-3 until
// 2026-11-25, which had tsitouras54 at 1e-3 reach 1e-4 with a hundredfold to spare); its error (max over the
// state at t_end against the exact solution) is measured once, its CPU time by Google Benchmark. Every solve is
// timed whole, as a user's program makes it: stepwise's integrator constructed by name (make_integrator) for
// each solve, the peers' steppers, drivers and CVODE's memory likewise. Then, per error target from 1e-4 to 1e-10,
// each candidate's cost at that error read off its own work-precision curve (log-log interpolation between the
// two tolerances whose errors bracket it; the cheapest point reaching it where the curve is not monotone there),
// and each side's best (times: medians where run with --benchmark_repetitions, as docs/performance.md's are):
//   error 1e-06: stepwise <method> <us> us, peer <name> <us> us, ratio <r>
#include "models/model.hpp"
#include "solvers/method_table.hpp"

#include <benchmark/benchmark.h>
#include <boost/numeric/odeint.hpp>
#include <cvode/cvode.h>
#include <fmt/format.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <nvector/nvector_serial.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <set>

namespace {

namespace odeint = boost::numeric::odeint;

// one test problem: the model stepwise runs, and the same f for the raw peers on a fixed-size state
template <int N>
struct Problem {
  const char* label;
  const char* model;
  stepwise::Params params;
  double t_end;
  std::function<void(const double* y, double* f)> f;
};

constexpr double g = 9.81, drag = 0.5;

const Problem<2> pendulum{"pendulum-170", "pendulum", {{"theta0", 170 * std::numbers::pi / 180}, {"g", g}, {"length", 1.0}}, 10.0,
                          [](const double* y, double* f) {
                            f[0] = y[1];
                            f[1] = -g * std::sin(y[0]);
                          }};
const Problem<2> flow{"flow-particle", "flow-particle", {}, 1.0, [](const double* y, double* f) {
                        f[0] = y[0];
                        f[1] = std::sin(y[1]);
                      }};
const Problem<4> projectile{"projectile", "projectile", {{"drag", drag}, {"g", g}}, 2.0, [](const double* y, double* f) {
                              f[0] = y[2];
                              f[1] = y[3];
                              f[2] = -drag * y[2];
                              f[3] = -g - drag * y[3];
                            }};

// what one candidate at one tolerance reached, and the name Google Benchmark times it under
struct Point {
  std::string problem, side, name;  // side: "stepwise" or "peer"
  double tol = 0, error = NAN;
  std::string benchmark;
};
std::vector<Point> points;

template <int N>
using State = std::array<double, N>;

// each peer: run once to t_end from y0 at tolerance tol, returning y(t_end) (NaN on failure)
template <int N>
State<N> run_odeint_dopri5(const Problem<N>& p, State<N> y, double tol) {
  auto f = [&](const State<N>& x, State<N>& dxdt, double) { p.f(x.data(), dxdt.data()); };
  odeint::integrate_adaptive(odeint::make_controlled(tol, tol, odeint::runge_kutta_dopri5<State<N>>()), f, y, 0.0, p.t_end, 1e-3 * p.t_end);
  return y;
}
template <int N>
State<N> run_odeint_rkf78(const Problem<N>& p, State<N> y, double tol) {
  auto f = [&](const State<N>& x, State<N>& dxdt, double) { p.f(x.data(), dxdt.data()); };
  odeint::integrate_adaptive(odeint::make_controlled(tol, tol, odeint::runge_kutta_fehlberg78<State<N>>()), f, y, 0.0, p.t_end, 1e-3 * p.t_end);
  return y;
}
template <int N>
int gsl_f(double, const double y[], double f[], void* problem) {
  static_cast<const Problem<N>*>(problem)->f(y, f);
  return GSL_SUCCESS;
}
template <int N>
State<N> run_gsl_rk8pd(const Problem<N>& p, State<N> y, double tol) {
  gsl_odeiv2_system sys{gsl_f<N>, nullptr, N, const_cast<Problem<N>*>(&p)};
  gsl_odeiv2_driver* d = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-3 * p.t_end, tol, tol);
  double t = 0;
  if (gsl_odeiv2_driver_apply(d, &t, p.t_end, y.data()) != GSL_SUCCESS) y.fill(NAN);
  gsl_odeiv2_driver_free(d);
  return y;
}
template <int N>
int cvode_f(sunrealtype, N_Vector y, N_Vector f, void* problem) {
  static_cast<const Problem<N>*>(problem)->f(N_VGetArrayPointer(y), N_VGetArrayPointer(f));
  return 0;
}
template <int N>
State<N> run_cvode_adams(const Problem<N>& p, State<N> y0, double tol) {
  SUNContext ctx;
  SUNContext_Create(nullptr, &ctx);
  N_Vector y = N_VNew_Serial(N, ctx);
  std::copy(y0.begin(), y0.end(), N_VGetArrayPointer(y));
  void* mem = CVodeCreate(CV_ADAMS, ctx);
  CVodeInit(mem, cvode_f<N>, 0.0, y);
  CVodeSetUserData(mem, const_cast<Problem<N>*>(&p));
  CVodeSStolerances(mem, tol, tol);
  CVodeSetMaxNumSteps(mem, 1000000);
  SUNNonlinearSolver nls = SUNNonlinSol_FixedPoint(y, 0, ctx);
  CVodeSetNonlinearSolver(mem, nls);
  double t = 0;
  State<N> out;
  if (CVode(mem, p.t_end, y, &t, CV_NORMAL) < 0) out.fill(NAN);
  else std::copy_n(N_VGetArrayPointer(y), N, out.begin());
  CVodeFree(&mem);
  SUNNonlinSolFree(nls);
  N_VDestroy(y);
  SUNContext_Free(&ctx);
  return out;
}

// each point's timing: long enough for a stable minimum of 1-100 us runs (STEPWISE_MIN_TIME to profile one)
const double min_time = std::getenv("STEPWISE_MIN_TIME") ? std::atof(std::getenv("STEPWISE_MIN_TIME")) : 0.02;

const char* own_methods[] = {"tsitouras54", "verner98", "arkode-erk-dormand-prince54", "arkode-erk-verner65", "arkode-erk-fehlberg87"};

template <int N>
void register_problem(const Problem<N>& p) {
  const auto model = stepwise::make_model(p.model, p.params);
  const Eigen::VectorXd y0 = model->initial_state(), exact = model->exact(p.t_end);
  State<N> y0_array;
  std::copy_n(y0.data(), N, y0_array.begin());
  const auto error_of = [&](const double* y) {
    double e = 0;
    for (int i = 0; i < N; ++i) e = std::max(e, std::abs(y[i] - exact[i]));
    return std::isfinite(e) ? e : NAN;
  };
  for (int k = 2; k <= 24; ++k) {
    const double tol = std::pow(10.0, -k / 2.0);
    for (const char* method : own_methods) {
      const auto integrator = stepwise::make_integrator(method, stepwise::StepControl::adaptive(tol, tol));
      const auto r = integrator->integrate(*model, 0, y0, std::vector{p.t_end});
      Point point{p.label, "stepwise", method, tol, r.status == stepwise::Status::ok ? error_of(r.y_stop.data()) : NAN,
                  fmt::format("{}/{}/{:.1e}", p.label, method, tol)};
      benchmark::RegisterBenchmark(point.benchmark.c_str(), [&p, method, tol](benchmark::State& state) {
        const auto m = stepwise::make_model(p.model, p.params);
        const Eigen::VectorXd start = m->initial_state();
        const std::vector<double> t_out{p.t_end};
        // constructed by name for each solve, as a user's program does; solve(), the untimed call (integrate()
        // adds two reads of the thread CPU clock, ~1.1 us, for the stats' cpu_seconds)
        for (auto _ : state)
          benchmark::DoNotOptimize(stepwise::make_integrator(method, stepwise::StepControl::adaptive(tol, tol))->solve(*m, 0, start, t_out).y_stop[0]);
      })->MinTime(min_time);
      points.push_back(std::move(point));
    }
    using Run = State<N> (*)(const Problem<N>&, State<N>, double);
    for (const auto& [name, run] : {std::pair<const char*, Run>{"odeint-dopri5", run_odeint_dopri5<N>}, {"odeint-rkf78", run_odeint_rkf78<N>},
                                    {"gsl-rk8pd (raw)", run_gsl_rk8pd<N>}, {"cvode-adams (raw)", run_cvode_adams<N>}}) {
      const State<N> y = run(p, y0_array, tol);
      Point point{p.label, "peer", name, tol, error_of(y.data()), fmt::format("{}/{}/{:.1e}", p.label, name, tol)};
      benchmark::RegisterBenchmark(point.benchmark.c_str(), [&p, run, y0_array, tol](benchmark::State& state) {
        for (auto _ : state) benchmark::DoNotOptimize(run(p, y0_array, tol)[0]);
      })->MinTime(min_time);
      points.push_back(std::move(point));
    }
  }
}

// the per-solve cost at equal calls: the pendulum as a user's own OdeSystem (a virtual rhs on Eigen vectors, as
// examples/cpp writes one), 100 rk4 steps (400 calls) made by name for each solve, against odeint's rk4 over
// integrate_n_steps on a std::array with the same f
struct UserPendulum : stepwise::OdeSystem {
  int size() const override { return 2; }
  bool autonomous() const override { return true; }
  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) const override {
    f[0] = y[1];
    f[1] = -g * std::sin(y[0]);
  }
};

void register_per_solve() {
  const double theta0 = 170 * std::numbers::pi / 180, dt = pendulum.t_end / 100;
  for (const bool timed : {false, true})
    benchmark::RegisterBenchmark(timed ? "per-solve/stepwise rk4, integrate()" : "per-solve/stepwise rk4, solve()", [=](benchmark::State& state) {
      const UserPendulum system;
      const Eigen::Vector2d y0(theta0, 0);
      const std::vector<double> t_out{pendulum.t_end};
      for (auto _ : state) {
        const auto integrator = stepwise::make_integrator("rk4", stepwise::StepControl::fixed(dt));
        benchmark::DoNotOptimize((timed ? integrator->integrate(system, 0, y0, t_out) : integrator->solve(system, 0, y0, t_out)).y_stop[0]);
      }
    })->MinTime(min_time);
  benchmark::RegisterBenchmark("per-solve/odeint rk4", [=](benchmark::State& state) {
    const auto f = [](const State<2>& x, State<2>& dxdt, double) {  // the same f, written where odeint can inline it
      dxdt[0] = x[1];
      dxdt[1] = -g * std::sin(x[0]);
    };
    for (auto _ : state) {
      State<2> y{theta0, 0};
      odeint::integrate_n_steps(odeint::runge_kutta4<State<2>>(), f, y, 0.0, dt, 100);
      benchmark::DoNotOptimize(y[0]);
    }
  })->MinTime(min_time);
}

// the usual table, then per problem and error target the cheapest setting of each side and their ratio
class WorkPrecisionReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    // one run's time, or with --benchmark_repetitions the median of the repetitions (the runs are 1-100 us:
    // one timing scatters by 10-20% from run to run of the program, so a ratio's claim takes repetitions)
    for (const auto& run : runs) {
      const std::string& name = run.run_name.function_name;
      if (run.run_type == Run::RT_Aggregate && run.aggregate_name == "median") {
        cpu_[name] = run.GetAdjustedCPUTime() / 1e3;  // ns -> us
        medians_.insert(name);
      } else if (run.run_type == Run::RT_Iteration && !medians_.contains(name)) {
        cpu_[name] = run.GetAdjustedCPUTime() / 1e3;
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    if (cpu_.contains("per-solve/odeint rk4")) {
      const double peer = cpu_.at("per-solve/odeint rk4");
      std::printf("per solve, 400 calls (100 rk4 steps) on a user's own OdeSystem, made by name each solve: odeint rk4 %.2f us\n", peer);
      for (const char* name : {"per-solve/stepwise rk4, solve()", "per-solve/stepwise rk4, integrate()"})
        if (cpu_.contains(name)) std::printf("  %s %.2f us: %+.2f us\n", name + 10, cpu_.at(name), cpu_.at(name) - peer);
    }
    std::printf("each solve timed whole: stepwise's integrator constructed by name (make_integrator) for every solve and run by solve(); "
                "the peers' steppers, GSL's driver and CVODE's memory made for every solve too. A candidate's cost at an error: log-log "
                "interpolation on its own curve\n");
    for (const char* problem : {pendulum.label, flow.label, projectile.label}) {
      std::printf("%s\n", problem);
      for (int e = 4; e <= 10; ++e) {
        const double target = std::pow(10.0, -e);
        const auto [own, a] = best(problem, "stepwise", target);
        const auto [peer, b] = best(problem, "peer", target);
        if (own.empty() || peer.empty()) {
          std::printf("error 1e-%02d: %s\n", e, own.empty() ? "no stepwise setting reaches it" : "no peer setting reaches it");
          continue;
        }
        std::printf("error 1e-%02d: stepwise %s %.2f us, peer %s %.2f us, ratio %.3f\n", e, own.c_str(), a, peer.c_str(), b, a / b);
      }
    }
  }

 private:
  // a candidate's cost at error `target` on its own curve: its points in the order of decreasing tolerance,
  // interpolated in log-log between the first successive pair whose errors bracket the target; where no pair
  // does (a curve that jumps past it), its cheapest point reaching it. Infinite where none does
  double cost_at(const std::string& problem, const std::string& name, double target) const {
    std::vector<const Point*> mine;
    for (const auto& p : points)
      if (p.problem == problem && p.name == name && std::isfinite(p.error) && p.error > 0 && cpu_.contains(p.benchmark)) mine.push_back(&p);
    std::sort(mine.begin(), mine.end(), [](const Point* a, const Point* b) { return a->tol > b->tol; });
    std::vector<std::pair<double, double>> curve;  // (error, us), loosest tolerance first
    for (const Point* p : mine) curve.emplace_back(p->error, cpu_.at(p->benchmark));
    for (size_t k = 0; k + 1 < curve.size(); ++k) {
      const auto [e1, c1] = curve[k];
      const auto [e2, c2] = curve[k + 1];
      if (e1 >= target && target >= e2 && e1 > e2) {
        const double w = std::log(e1 / target) / std::log(e1 / e2);
        return std::exp(std::log(c1) + w * std::log(c2 / c1));
      }
    }
    double cheapest = INFINITY;
    for (const auto& [e, c] : curve)
      if (e <= target) cheapest = std::min(cheapest, c);
    return cheapest;
  }
  std::pair<std::string, double> best(const std::string& problem, const std::string& side, double target) const {
    std::pair<std::string, double> found{"", INFINITY};
    std::set<std::string> names;
    for (const auto& p : points)
      if (p.problem == problem && p.side == side) names.insert(p.name);
    for (const auto& name : names)
      if (const double c = cost_at(problem, name, target); c < found.second) found = {name, c};
    return found;
  }
  std::map<std::string, double> cpu_;
  std::set<std::string> medians_;
};

}  // namespace

int main(int argc, char** argv) {
  gsl_set_error_handler_off();
  benchmark::Initialize(&argc, argv);
  points.reserve(3 * 23 * 9);
  register_per_solve();
  register_problem(pendulum);
  register_problem(flow);
  register_problem(projectile);
  WorkPrecisionReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
