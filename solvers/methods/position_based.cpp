// pbd and xpbd: position-based dynamics, the way game and film engines step cloth, ropes and joints. A frame step
// dt is taken in `substeps` substeps (its options); each predicts the positions from the external acceleration
// alone (v += h a, p = x + h v), then moves them onto the constraints by `iterations` Gauss-Seidel sweeps (each
// constraint in turn, on the positions the previous one left), and takes the velocity from the positions' change
// (v = (p - x) / h). Müller et al., "Position Based Dynamics" (2007); Macklin, Müller & Chentanez, "XPBD" (2016):
// a constraint C(p) with compliance alpha moves p by w grad C dlambda, where (alpha~ = alpha / h^2)
//   xpbd:  dlambda = (-C - alpha~ lambda) / (w + alpha~),  lambda += dlambda  (lambda from 0 each substep)
//   pbd:   dlambda = -C / (w + alpha~)                      (no multiplier: each sweep pulls the whole way again)
// so xpbd's constraint obeys Hooke's law with k = 1/alpha whatever the substeps and iterations, and pbd's
// stiffens with every sweep (its compliance is a per-iteration stiffness w / (w + alpha~)). With alpha = 0 the
// two are the same. "Small steps" (Macklin et al. 2019) is xpbd with many substeps of one iteration.
#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/method_table.hpp"
#include "solvers/run_support.hpp"

#include <algorithm>
#include <limits>

namespace stepwise {
namespace {

enum class Multiplier { kept, none };  // xpbd keeps lambda across the sweeps of a substep; pbd has none

class PositionBased final : public PlainStepping<PositionBased> {
 public:
  static constexpr int size = 0;  // PlainStepping: no advance(), the state of a run-time size

  PositionBased(const CountedSystem& s, int substeps, int iterations, Multiplier multiplier)
      : system_(s), c_(*s.as<DistanceConstraints>()), substeps_(substeps), iterations_(iterations),
        multiplier_(multiplier), n_(s.size() / 2), a_(n_), p_(n_), lambda_(c_.constraints.size()) {}

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    const double hs = h / substeps_;
    y_next = y;
    double* x = y_next.data();
    double* v = x + n_;
    for (int s = 0; s < substeps_; ++s) {
      predict(t + s * hs, hs, x, v);
      solve_constraints(hs);
      update_velocities(hs, x, v);
    }
    RunningNorm norm;
    for (Eigen::Index i = 0; i < y_next.size(); ++i) norm.add(y_next[i]);
    norm_ = norm.value();
    return true;
  }

 private:
  // the substep's three phases. Predict: the velocities from the external acceleration alone, the positions
  // from them (v += h a, p = x + h v)
  void predict(double t, double hs, const double* x, double* v) {
    c_.external(t, x, v, a_.data());
    ++system_.stats().rhs_evals;
    for (Eigen::Index i = 0; i < n_; ++i) {
      if (c_.inverse_mass[static_cast<size_t>(i / c_.dimension)] > 0) v[i] += hs * a_[i];
      p_[i] = x[i] + hs * v[i];
    }
  }
  // solve: `iterations` Gauss-Seidel sweeps over the constraints on the predicted positions (xpbd's multipliers
  // from 0)
  void solve_constraints(double hs) {
    std::fill(lambda_.begin(), lambda_.end(), 0.0);
    for (int k = 0; k < iterations_; ++k)
      for (size_t j = 0; j < c_.constraints.size(); ++j) project(j, hs);
    system_.stats().projections += iterations_;
  }
  // update: the velocities from the positions' change, and the positions
  void update_velocities(double hs, double* x, double* v) const {
    for (Eigen::Index i = 0; i < n_; ++i) {
      v[i] = (p_[i] - x[i]) / hs;
      x[i] = p_[i];
    }
  }

  // constraint j on the predicted positions, in place
  void project(size_t j, double hs) {
    const DistanceConstraint& c = c_.constraints[j];
    double n[3] = {0, 0, 0};  // the constraint direction (dimension entries set)
    const double C = c_.violation(c, p_.data(), n);
    const double wa = c_.inverse_mass[static_cast<size_t>(c.a)], wb = c.b < 0 ? 0.0 : c_.inverse_mass[static_cast<size_t>(c.b)];
    const double alpha = c.compliance / (hs * hs), w = wa + wb;
    if (w + alpha == 0) return;  // two pinned ends
    const double dlambda = multiplier_ == Multiplier::kept ? (-C - alpha * lambda_[j]) / (w + alpha) : -C / (w + alpha);
    lambda_[j] += dlambda;
    const int d = c_.dimension;
    for (int k = 0; k < d; ++k) {
      p_[c.a * d + k] += wa * dlambda * n[k];
      if (c.b >= 0) p_[c.b * d + k] -= wb * dlambda * n[k];
    }
  }

  const CountedSystem& system_;
  const DistanceConstraints& c_;
  int substeps_, iterations_;
  Multiplier multiplier_;
  Eigen::Index n_;       // coordinates
  Eigen::VectorXd a_, p_;  // the external acceleration; the predicted positions
  std::vector<double> lambda_;
};

MakeIntegrator position_based(Multiplier multiplier) {
  return [multiplier](const Method& method, const StepControl& control) {
    const int substeps = method.whole_setting(control, "substeps"), iterations = method.whole_setting(control, "iterations");
    return std::make_unique<FixedStepIntegrator>(method, control, [substeps, iterations, multiplier](const CountedSystem& system) {
      return std::make_unique<PositionBased>(system, substeps, iterations, multiplier);
    });
  };
}

// a frame step in substeps of iterations sweeps each; PhysX's default of 4 position iterations in one step. "Small
// steps" is many substeps of one iteration
std::vector<MethodOption> position_based_options() {
  return {{.name = "substeps", .max = max_substeps, .fallback = 1, .help = "substeps a step, each predicting and projecting"},
          {.name = "iterations", .max = max_substeps, .fallback = 4, .help = "constraint sweeps a substep"}};
}

}  // namespace

void register_position_based_methods(MethodTable& table) {
  table.add({
      .name = "pbd",
      .family = Family::position_based,
      .source = Source::hand_written,
      .description = "position-based dynamics (Müller 2007): constraints projected, stiffness per iteration",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .needs = needs_distance_constraints,
      .options = position_based_options(),
      .make = position_based(Multiplier::none),
  });
  table.add({
      .name = "xpbd",
      .family = Family::position_based,
      .source = Source::hand_written,
      .description = "extended position-based dynamics (Macklin 2016): compliant constraints, Hooke's law at any iteration count",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .needs = needs_distance_constraints,
      .options = position_based_options(),
      .make = position_based(Multiplier::kept),
  });
}

}  // namespace stepwise
