// vbd: Vertex Block Descent (solvers/vertex_block_descent.hpp) as a fixed-step method on a mass-spring system: each
// (sub)step backward Euler's incremental potential, `iterations` coloured sweeps from the paper's adaptive start (the
// inertial position plus the part of the last step's acceleration along the other forces', clamped between none and
// all of it; all of it at the first step). With enough sweeps the step is backward Euler's; with few, less.
#include "solvers/fixed_step.hpp"
#include "solvers/incremental_potential.hpp"
#include "solvers/method_table.hpp"
#include "solvers/run_support.hpp"
#include "solvers/vertex_block_descent.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace stepwise {
namespace {

using Coordinates = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;  // a node's, on the stack

class VertexBlockDescent final : public FixedStepper {
 public:
  VertexBlockDescent(const CountedSystem& s, const StepControl& control, bool chebyshev)
      : system_(s), view_(*s.as<MassSpringView>()), potential_(s, view_), substeps_(control.substeps),
        sweeps_{control.iterations, std::max(control.threads, 1), chebyshev ? control.chebyshev_rho : 0.0}, n_(s.size() / 2) {}

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    if (colours_.empty()) {
      Eigen::SparseMatrix<double> k, d;
      force_jacobians(system_, view_, t, y, true, k, d);
      colours_ = colour_nodes(k, view_.dimension);
      system_.stats().colours = static_cast<long>(colours_.size());
    }
    const double hs = h / substeps_;
    y_next = y;
    for (int s = 0; s < substeps_; ++s) {
      substep(t + s * hs, hs, y_next);
      if (!y_next.allFinite()) {
        failure = fmt::format("vbd: the state is not finite after substep {} of the step at t = {:.9g} (h = {:.3g})", s, t, h);
        return false;
      }
    }
    return true;
  }

 private:
  // one backward Euler step of length h from y (x, v), in place
  void substep(double t, double h, Eigen::VectorXd& y) {
    potential_.start(t, y, h);
    const Eigen::VectorXd& m = potential_.mass();
    x_ = potential_.inertial();
    // the adaptive start: along each node's other forces' acceleration a (gravity, wind, ...), the last step's
    // acceleration's component, clamped to [0, |a|]
    const int dim = view_.dimension;
    for (int i = 0; i < view_.nodes; ++i) {
      const Eigen::Index at = Eigen::Index{dim} * i;
      const Coordinates a = potential_.other_forces().segment(at, dim) / m[at];
      const double size = a.norm();
      if (!(size > 0)) continue;
      const Coordinates along = a / size;
      const double last = previous_v_.size() ? std::clamp((y.segment(n_ + at, dim) - previous_v_.segment(at, dim)).dot(along) / previous_h_, 0.0, size) : size;
      x_.segment(at, dim) += h * h * last * along;
    }
    system_.stats().potential_decrease += vbd_iterate(potential_, colours_, x_, sweeps_, decrease_);
    previous_v_ = y.tail(n_);
    previous_h_ = h;
    y.tail(n_) = (x_ - y.head(n_)) / h;
    y.head(n_) = x_;
  }

  const CountedSystem& system_;
  const MassSpringView& view_;
  IncrementalPotential potential_;
  int substeps_;
  VbdSweeps sweeps_;
  Eigen::Index n_;
  std::vector<std::vector<int>> colours_;
  Eigen::VectorXd x_, decrease_, previous_v_;
  double previous_h_ = 0;
};

}  // namespace

void register_vbd_methods(MethodTable& table) {
  for (const bool chebyshev : {false, true})
    table.add({
        .name = chebyshev ? "vbd-chebyshev" : "vbd",
        .family = Family::vertex_block_descent,
        .source = Source::hand_written,
        .description = chebyshev ? "vbd with Chebyshev's semi-iterative acceleration of its sweeps (Wang 2015) at the rate --rho (0.99), an "
                                   "extrapolation that would raise the potential not taken"
                                 : "Vertex Block Descent (Chen et al. 2024): backward Euler's incremental potential by coloured Gauss-Seidel over "
                                   "the nodes, a 3 x 3 Newton step each",
        .order = {1, 1, "1"},
        .stepping = Stepping::fixed,
        .needs = needs_mass_spring,
        .substepped = true,
        .make =
            [chebyshev](const Method& method, const StepControl& control) {
              return std::make_unique<FixedStepIntegrator>(method, control, [control, chebyshev](const CountedSystem& system) {
                return std::make_unique<VertexBlockDescent>(system, control, chebyshev);
              });
            },
    });
}

}  // namespace stepwise
