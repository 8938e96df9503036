#include "vertex_block_descent.hpp"

#include "solvers/run_support.hpp"

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include <omp.h>

namespace stepwise {

namespace {

// node i's Newton step on G, halved until G falls; G's decrease (0 where it stays)
double move(const IncrementalPotential& potential, int i, Eigen::VectorXd& x) {
  const IncrementalPotential::Vertex here = potential.vertex(i, x, true, true);
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(here.hessian);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) return 0;
  const Eigen::Vector3d step = -ldlt.solve(here.gradient);  // in the plane, its z zero (the gradient's is)
  const double slope = here.gradient.dot(step);
  if (!(slope < 0)) return 0;
  const int dim = potential.dimension();
  auto node = x.segment(Eigen::Index{dim} * i, dim);
  Eigen::Vector3d from = Eigen::Vector3d::Zero();
  from.head(dim) = node;
  for (int halving = 0; halving <= vbd_max_halvings; ++halving) {
    const double alpha = std::ldexp(1.0, -halving);
    node = (from + alpha * step).head(dim);
    const double change = potential.vertex(i, x, true, false).value - here.value;
    if (change <= vbd_armijo * alpha * slope) return -change;
  }
  node = from.head(dim);
  return 0;
}

}  // namespace

std::vector<std::vector<int>> colour_nodes(const Eigen::SparseMatrix<double>& pattern, int dimension) {
  const Eigen::Index nodes = pattern.cols() / dimension;
  std::vector<int> colour(static_cast<size_t>(nodes), -1);
  std::vector<char> taken;
  std::vector<std::vector<int>> by_colour;
  for (Eigen::Index i = 0; i < nodes; ++i) {
    taken.assign(by_colour.size() + 1, 0);
    for (Eigen::SparseMatrix<double>::InnerIterator it(pattern, dimension * i); it; ++it)
      if (const int c = colour[static_cast<size_t>(it.row() / dimension)]; c >= 0) taken[static_cast<size_t>(c)] = 1;
    const auto c = static_cast<int>(std::find(taken.begin(), taken.end(), 0) - taken.begin());
    colour[static_cast<size_t>(i)] = c;
    if (static_cast<size_t>(c) == by_colour.size()) by_colour.emplace_back();
    by_colour[static_cast<size_t>(c)].push_back(static_cast<int>(i));
  }
  return by_colour;
}

double vbd_sweep(const IncrementalPotential& potential, const std::vector<std::vector<int>>& colours, Eigen::VectorXd& x, int threads,
                 Eigen::VectorXd& decrease) {
  decrease.setZero(x.size() / potential.dimension());
  std::atomic<double>* const workers = worker_cpu_seconds();  // the run's, its cpu_seconds counting every thread
  // one team for the whole sweep, the colours in turn (the barrier closing each colour's loop keeps them apart):
  // a team a colour started and joined a team for some 100 nodes, 1.38x one thread's CPU on the 32^2 flag
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const WorkerCpuTime timed(workers, omp_get_thread_num() != 0);
    for (const std::vector<int>& colour : colours) {
      const auto count = static_cast<std::ptrdiff_t>(colour.size());
#pragma omp for schedule(static)
      for (std::ptrdiff_t k = 0; k < count; ++k) {
        const int i = colour[static_cast<size_t>(k)];
        decrease[i] += move(potential, i, x);
      }
    }
  }
  return decrease.sum();
}

double vbd_iterate(const IncrementalPotential& potential, const std::vector<std::vector<int>>& colours, Eigen::VectorXd& x, const VbdSweeps& how,
                   Eigen::VectorXd& decrease) {
  const double rho2 = how.rho * how.rho;
  double total = 0, omega = 0;     // omega 0: the sequence starts again
  Eigen::VectorXd older, old, dx;  // x_{k-2} and x_{k-1}
  if (rho2 > 0) old = x;
  for (int k = 1; k <= how.sweeps; ++k) {
    total += vbd_sweep(potential, colours, x, how.threads, decrease);
    if (!(rho2 > 0)) continue;
    if (k >= 2) {
      omega = omega == 0 ? 2 / (2 - rho2) : 4 / (4 - rho2 * omega);
      dx = (omega - 1) * (x - older);
      if (const double change = potential.change(x, dx); change < 0) {
        x += dx;
        total -= change;
      } else {
        omega = 0;
      }
    }
    older = std::move(old);
    old = x;
  }
  return total;
}

namespace {
using Coordinates = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;  // a node's, on the stack
}  // namespace

VbdStepper::VbdStepper(const CountedSystem& s, const VbdSettings& settings, std::string_view name)
    : system_(s), view_(*s.as<MassSpringView>()), potential_(s, view_), substeps_(settings.substeps),
      sweeps_{settings.sweeps.sweeps, std::max(settings.sweeps.threads, 1), settings.sweeps.rho}, start_(settings.start), name_(name), n_(s.size() / 2) {}

bool VbdStepper::step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) {
  if (colours_.empty()) {
    Eigen::SparseMatrix<double> k, d;
    force_jacobians(system_, view_, t, y, true, k, d);
    colours_ = colour_nodes(k, view_.dimension);
    system_.stats().colours = static_cast<long>(colours_.size());
  }
  const double hs = h / substeps_;
  y_next = y;
  for (int s = 0; s < substeps_; ++s) {
    if (!substep(t + s * hs, hs, y_next, failure)) return false;
    if (!y_next.allFinite()) {
      failure = fmt::format("{}: the state is not finite after substep {} of the step at t = {:.9g} (h = {:.3g})", name_, s, t, h);
      return false;
    }
  }
  return true;
}

bool VbdStepper::iterate(const IncrementalPotential& potential, const std::vector<std::vector<int>>& colours, Eigen::VectorXd& x, double& decrease,
                         std::string& /*failure*/) {
  decrease += vbd_iterate(potential, colours, x, sweeps_, decrease_);
  return true;
}

bool VbdStepper::substep(double t, double h, Eigen::VectorXd& y, std::string& failure) {
  potential_.start(t, y, h);
  const Eigen::VectorXd& m = potential_.mass();
  x_ = potential_.inertial();
  // the adaptive start: along each node's other forces' acceleration a (gravity, wind, ...), the last step's
  // acceleration's component, clamped to [0, |a|]
  const int dim = view_.dimension;
  for (int i = 0; start_ == VbdStart::adaptive && i < view_.nodes; ++i) {
    const Eigen::Index at = Eigen::Index{dim} * i;
    const Coordinates a = potential_.other_forces().segment(at, dim) / m[at];
    const double size = a.norm();
    if (!(size > 0)) continue;
    const Coordinates along = a / size;
    const double last = previous_v_.size() ? std::clamp((y.segment(n_ + at, dim) - previous_v_.segment(at, dim)).dot(along) / previous_h_, 0.0, size) : size;
    x_.segment(at, dim) += h * h * last * along;
  }
  if (!iterate(potential_, colours_, x_, system_.stats().potential_decrease, failure)) return false;
  previous_v_ = y.tail(n_);
  previous_h_ = h;
  y.tail(n_) = (x_ - y.head(n_)) / h;
  y.head(n_) = x_;
  return true;
}

}  // namespace stepwise
