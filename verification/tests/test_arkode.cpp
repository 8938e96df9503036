// ARKODE's IMEX methods on the models' stiff/non-stiff splits: the split itself, orders at a fixed step,
// error against tolerance, agreement with CVODE BDF on the flag, honest counts, and the refusals.
#include "models/model.hpp"
#include "run/measure.hpp"
#include "solvers/capabilities/imex_split.hpp"
#include "solvers/method_table.hpp"
#include "verification/convergence.hpp"
#include "verification/order_fit.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace stepwise {
namespace {

// a small standing wave (mode (2, 1) of a 12 x 12 grid, damped): its semi-discrete exact solution is in
// closed form, and both parts of the split act (the Laplacian implicit, the damping explicit)
std::unique_ptr<Model> small_wave() { return make_model("standing-wave", {{"size", 12}, {"mu", 0.5}}); }
// a small gusting flag with a picked node: every force of both parts of the cloth's split acts
std::unique_ptr<Model> small_flag() {
  return make_model("cloth", {{"rows", 5}, {"columns", 5}, {"pick_row", 2}, {"pick_column", 2}, {"pick_fz", 0.1}});
}

std::vector<const Method*> imex_methods() {
  std::vector<const Method*> found;
  for (const auto& m : methods())
    if (m.needs.type == needs_imex_split.type) found.push_back(&m);
  return found;
}

TEST(Imex, TheModelsSplitsAddUpToTheirRightHandSides) {
  // the smoke: viscosity and diffusion against advection, buoyancy and the source, each part projected
  for (const auto& model : {small_wave(), small_flag(), make_model("smoke", {{"size", 16}, {"viscosity", 0.01}})}) {
    const ImexSplit* split = model->as<ImexSplit>();
    ASSERT_NE(split, nullptr) << model->name();
    // a state away from rest: the initial state moved by a smooth field, velocities included
    Eigen::VectorXd y = model->initial_state();
    for (Eigen::Index i = 0; i < y.size(); ++i) y[i] += 0.01 * std::sin(0.7 * static_cast<double>(i));
    Eigen::VectorXd f(y.size()), fi(y.size()), fe(y.size());
    for (const double t : {0.0, 0.37}) {
      model->rhs(t, y, f);
      split->implicit_part(t, y, fi);
      split->explicit_part(t, y, fe);
      // each entry of f is a sum of the same terms as fi + fe, summed in another grouping: a few roundings
      // of the larger part's size
      const double scale = fi.cwiseAbs().maxCoeff() + fe.cwiseAbs().maxCoeff();
      EXPECT_LE((fi + fe - f).lpNorm<Eigen::Infinity>(), tolerance::split_roundoff * scale) << model->name() << " t " << t;
      EXPECT_GT(fi.lpNorm<Eigen::Infinity>(), 0) << model->name();
      EXPECT_GT(fe.lpNorm<Eigen::Infinity>(), 0) << model->name();
    }
  }
}

TEST(Imex, FixedStepOrdersOnTheFlag) {
  // the flag, nonlinear in both parts (springs, wind through the normals), against CVODE BDF at rtol 1e-12:
  // each method's error over four halvings of dt; the wave, being linear, is not used (a linear problem
  // meets order conditions a nonlinear one does not: ARK 5(4) showed slope 6.0 there, ARK 3(2) 2.7)
  const auto model = small_flag();
  const double t_end = 0.25;
  const std::vector<double> t_out{t_end};
  const RunResult reference =
      make_integrator("cvode-bdf", StepControl::adaptive(1e-12, 1e-15))->integrate(*model, 0, model->initial_state(), t_out);
  ASSERT_EQ(reference.status, Status::ok) << reference.message;
  for (const Method* method : imex_methods()) {
    std::vector<double> dts, errors;
    // from a step where each method's error is already asymptotic (measured), over five halvings
    const int coarsest = method->order.max <= 4 ? 80 : 40;
    for (int k = 0; k <= 5; ++k) {
      const double dt = t_end / (coarsest * (1 << k));
      const RunResult r = make_integrator(method->name, StepControl::fixed(dt))->integrate(*model, 0, model->initial_state(), t_out);
      ASSERT_EQ(r.status, Status::ok) << method->name << ": " << r.message;
      const double error = (r.y_stop - reference.y_stop).lpNorm<Eigen::Infinity>();
      if (error > tolerance::reference_floor && error < tolerance::asymptotic_ceiling) {
        dts.push_back(dt);
        errors.push_back(error);
      }
    }
    ASSERT_GE(dts.size(), 4u) << method->name;
    const double order = loglog_slope(dts, errors);
    std::cout << method->name << " on the flag: observed order " << order << ", error " << errors.front() << " -> " << errors.back() << '\n';
    EXPECT_NEAR(order, method->order.max, tolerance::order_band) << method->name;
  }
}

TEST(Imex, ErrorFallsAsToleranceTightensOnTheStandingWave) {
  const auto model = small_wave();
  for (const Method* method : imex_methods()) {
    std::vector<double> rtols, errors;
    for (int e = 3; e <= 10; ++e) {
      const double rtol = std::pow(10.0, -e);
      const Measured m = run_and_measure(*model, method->name, StepControl::adaptive(rtol, 1e-3 * rtol), 1.0, 1.0);
      ASSERT_EQ(m.result.status, Status::ok) << method->name << ": " << m.result.message;
      rtols.push_back(rtol);
      errors.push_back(std::max(*m.error, 1e-16));
    }
    const double slope = loglog_slope(rtols, errors);
    std::cout << method->name << ": error " << errors.front() << " at rtol 1e-3 -> " << errors.back() << " at 1e-10, slope " << slope << '\n';
    EXPECT_GT(slope, tolerance::min_tolerance_slope(method->order.min)) << method->name;
  }
}

TEST(Imex, TheFlagAgreesWithCvodeBdfAtTightTolerance) {
  const auto model = small_flag();
  const double rtol = 1e-9, t_end = 0.5;
  const std::vector<double> t_out{t_end};
  const auto control = StepControl::adaptive(rtol, 1e-3 * rtol);
  const RunResult reference = make_integrator("cvode-bdf", control)->integrate(*model, 0, model->initial_state(), t_out);
  ASSERT_EQ(reference.status, Status::ok) << reference.message;
  const double size = reference.y_stop.lpNorm<Eigen::Infinity>();
  for (const Method* method : imex_methods()) {
    const RunResult r = make_integrator(method->name, control)->integrate(*model, 0, model->initial_state(), t_out);
    ASSERT_EQ(r.status, Status::ok) << method->name << ": " << r.message;
    const double difference = (r.y_stop - reference.y_stop).lpNorm<Eigen::Infinity>();
    std::cout << method->name << " against cvode-bdf at rtol 1e-9: " << difference << " (state size " << size << ")\n";
    EXPECT_LE(difference, tolerance::adaptive_agreement_factor * rtol * size) << method->name;
  }
}

// the flag, its split's two parts counting their own calls
class CountingSplit final : public OdeSystem {
 public:
  explicit CountingSplit(const Model& m) : model_(m), inner_(*m.as<ImexSplit>()) {
    split_ = inner_;
    split_.implicit_part = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
      ++calls;
      inner_.implicit_part(t, y, f);
    };
    split_.explicit_part = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
      ++calls;
      inner_.explicit_part(t, y, f);
    };
  }
  int size() const override { return model_.size(); }
  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) const override {
    ++calls;
    model_.rhs(t, y, f);
  }
  const void* capability(const std::type_info& type) const override { return type == typeid(ImexSplit) ? &split_ : model_.capability(type); }
  mutable long calls = 0;

 private:
  const Model& model_;
  const ImexSplit& inner_;
  ImexSplit split_;
};

TEST(Imex, EveryCallOfEitherPartIsCounted) {
  const auto model = small_flag();
  for (const Method* method : imex_methods()) {
    CountingSplit system(*model);
    for (const auto& control : {StepControl::adaptive(1e-6, 1e-9), StepControl::fixed(1e-3)}) {
      system.calls = 0;
      const RunResult r = make_integrator(method->name, control)->integrate(system, 0, model->initial_state(), std::vector{0.1});
      ASSERT_EQ(r.status, Status::ok) << method->name << ": " << r.message;
      EXPECT_EQ(r.stats.rhs_evals, system.calls) << method->name;
      EXPECT_GT(r.stats.jac_evals, 0) << method->name;
    }
  }
}

TEST(Imex, AMethodNeedingASplitRefusesAModelWithout) {
  const auto pendulum = make_model("pendulum", {});
  for (const Method* method : imex_methods()) {
    EXPECT_FALSE(method_applies(*method, *pendulum)) << method->name;
    const auto integrator = make_integrator(method->name, StepControl::adaptive(1e-6, 1e-9));
    EXPECT_THROW((void)integrator->integrate(*pendulum, 0, pendulum->initial_state(), std::vector{1.0}), BadMethod) << method->name;
  }
}

TEST(Odeint, TheFlagThroughOdeintAgreesWithTheSameMethodsElsewhere) {
  // the same Runge-Kutta methods in two codes on the gusting flag: odeint's rk4 and stepwise's at a fixed
  // step differ by round-off only (a few ulps a step); odeint's dopri5 and rkf78 and ARKODE's Dormand-Prince
  // and Fehlberg 8(7) at rtol 1e-9 agree as two tolerance-controlled codes do
  const auto model = small_flag();
  const std::vector<double> t_out{0.25};
  const auto run = [&](const char* method, const StepControl& control) {
    const RunResult r = make_integrator(method, control)->integrate(*model, 0, model->initial_state(), t_out);
    EXPECT_EQ(r.status, Status::ok) << method << ": " << r.message;
    return r;
  };
  const RunResult ours = run("rk4", StepControl::fixed(1e-3)), theirs = run("odeint-rk4", StepControl::fixed(1e-3));
  const double size = ours.y_stop.lpNorm<Eigen::Infinity>();
  EXPECT_LE((ours.y_stop - theirs.y_stop).lpNorm<Eigen::Infinity>(),
            tolerance::roundoff_per_step * 2.220446049250313e-16 * size * static_cast<double>(ours.stats.steps));
  const double rtol = 1e-9;
  const auto control = StepControl::adaptive(rtol, 1e-3 * rtol);
  for (const auto& [a, b] : {std::pair{"odeint-dopri5", "arkode-erk-dormand-prince54"}, {"odeint-rkf78", "arkode-erk-fehlberg87"}}) {
    const RunResult x = run(a, control), y = run(b, control);
    const double difference = (x.y_stop - y.y_stop).lpNorm<Eigen::Infinity>();
    std::cout << a << " against " << b << " at rtol 1e-9: " << difference << '\n';
    EXPECT_LE(difference, tolerance::adaptive_agreement_factor * rtol * size) << a << " against " << b;
  }
}

TEST(Arkode, AFailureNamesTheCallAndItsCode) {
  const auto model = make_model("pendulum", {{"theta0", 1.0}});
  StepControl control = StepControl::adaptive(1e-10, 1e-12);
  control.max_steps = 5;
  for (const char* method : {"arkode-erk-dormand-prince54", "arkode-dirk-kvaerno43"}) {
    const RunResult r = make_integrator(method, control)->integrate(*model, 0, model->initial_state(), std::vector{10.0});
    EXPECT_EQ(r.status, Status::failed) << method;
    EXPECT_NE(r.message.find("ARKStepEvolve returned -1 (ARK_TOO_MUCH_WORK)"), std::string::npos) << r.message;
  }
}

}  // namespace
}  // namespace stepwise
