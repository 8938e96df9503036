#include "vertex_block_descent.hpp"

#include "solvers/run_support.hpp"

#include "kernels/spring_end.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include <omp.h>

namespace stepwise {

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

VbdNodes::VbdNodes(const IncrementalPotential& potential, std::vector<std::vector<int>> colours, const MassSpringView* springs)
    : potential_(potential), colours_(std::move(colours)), springs_(springs) {
  for (const auto& colour : colours_) order_.insert(order_.end(), colour.begin(), colour.end());
  refresh();
}

void VbdNodes::refresh() {
  if (!springs_) return;
  const Eigen::SparseMatrix<double>& d0 = potential_.damping();
  const int dim = springs_->dimension;
  if (value_at_.size() != static_cast<size_t>(d0.nonZeros())) {
    // the layout, once: each node's springs seen from it, and its blocks of D0 (its own first), in sweep order
    const std::vector<std::vector<int>> by_node = springs_by_node(springs_->springs, springs_->nodes);
    spring_end_.clear();
    block_end_.clear();
    springs_at_.clear();
    block_node_.clear();
    value_at_.assign(static_cast<size_t>(d0.nonZeros()), -1);
    std::vector<int> slot_of_node(static_cast<size_t>(springs_->nodes));
    for (size_t k = 0; k < order_.size(); ++k) slot_of_node[static_cast<size_t>(order_[k])] = static_cast<int>(k);
    for (const int i : order_) {
      for (const int k : by_node[static_cast<size_t>(i)]) {
        const Spring& s = springs_->springs[static_cast<size_t>(k)];
        const int other = s.b == i ? s.a : s.b;
        springs_at_.push_back({other, s.rest, s.stiffness, {s.anchor.x(), s.anchor.y(), s.anchor.z()}});
      }
      spring_end_.push_back(static_cast<int>(springs_at_.size()));
      block_node_.push_back(i);
      for (Eigen::SparseMatrix<double>::InnerIterator it(d0, Eigen::Index{dim} * i); it; ++it)
        if (const auto j = static_cast<int>(it.row() / dim); j != i && std::find(block_node_.begin() + (block_end_.empty() ? 0 : block_end_.back()), block_node_.end(), j) == block_node_.end())
          block_node_.push_back(j);
      block_end_.push_back(static_cast<int>(block_node_.size()));
    }
    // where each stored value of D0 goes: column (i, c), row (j, r) is block (i, j)'s entry (c, r) (D0 is symmetric)
    for (Eigen::Index column = 0; column < d0.outerSize(); ++column) {
      const auto i = static_cast<int>(column / dim), c = static_cast<int>(column % dim);
      const size_t k = static_cast<size_t>(slot_of_node[static_cast<size_t>(i)]);
      const auto first = block_node_.begin() + (k == 0 ? 0 : block_end_[k - 1]), last = block_node_.begin() + block_end_[k];
      for (Eigen::Index at = d0.outerIndexPtr()[column]; at < d0.outerIndexPtr()[column + 1]; ++at) {
        const int j = d0.innerIndexPtr()[at] / dim, r = d0.innerIndexPtr()[at] % dim;
        const auto block = std::find(first, last, j) - block_node_.begin();
        value_at_[static_cast<size_t>(at)] = (block * dim + c) * dim + r;
      }
    }
    blocks_.assign(block_node_.size() * static_cast<size_t>(dim * dim), 0.0);
  }
  const double* values = d0.valuePtr();
  for (size_t at = 0; at < value_at_.size(); ++at) blocks_[static_cast<size_t>(value_at_[at])] = values[at];
}

double VbdNodes::move(size_t k, Eigen::VectorXd& x) const {
  if (!springs_) return move_through_vertex(order_[k], x);
  return springs_->dimension == 3 ? move_in_network<3>(k, x.data()) : move_in_network<2>(k, x.data());
}

// node i's Newton step on G, halved until G falls; G's decrease (0 where it stays)
double VbdNodes::move_through_vertex(int i, Eigen::VectorXd& x) const {
  const IncrementalPotential::Vertex here = potential_.vertex(i, x, true, true);
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(here.hessian);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) return 0;
  const Eigen::Vector3d step = -ldlt.solve(here.gradient);  // in the plane, its z zero (the gradient's is)
  const double slope = here.gradient.dot(step);
  if (!(slope < 0)) return 0;
  const int dim = potential_.dimension();
  auto node = x.segment(Eigen::Index{dim} * i, dim);
  Eigen::Vector3d from = Eigen::Vector3d::Zero();
  from.head(dim) = node;
  for (int halving = 0; halving <= vbd_max_halvings; ++halving) {
    const double alpha = std::ldexp(1.0, -halving);
    node = (from + alpha * step).head(dim);
    const double change = potential_.vertex_change(i, x, here, alpha * step);
    if (change <= vbd_armijo * alpha * slope) return -change;
  }
  node = from.head(dim);
  return 0;
}

// the same move on the network's layout: G's gradient and Hessian in x_i from the node's blocks of D0 and its springs
// (each spring's Hessian made semidefinite), the step by Cholesky, its halvings' changes from the springs' lengths
template <int D>
double VbdNodes::move_in_network(size_t k, double* x) const {
  using Vector = SpringVector<D>;
  using Block = SpringBlock<D>;
  const int i = order_[k];
  const double* xb = potential_.inertial().data();
  const double h = potential_.h(), m = potential_.mass()[D * Eigen::Index{i}], mh = m / (h * h);
  Eigen::Map<Vector> xi(x + D * i);
  const Vector e = xi - Eigen::Map<const Vector>(xb + D * i), f0 = Eigen::Map<const Vector>(potential_.other_forces().data() + D * i);
  // (D0 (x - xb))_i and D0's block (i, i)
  const int first_block = k == 0 ? 0 : block_end_[k - 1], last_block = block_end_[k];
  Vector d0e = Vector::Zero();
  for (int b = first_block; b < last_block; ++b) {
    const int j = block_node_[static_cast<size_t>(b)];
    d0e += Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>>(blocks_.data() + D * D * b) *
           (Eigen::Map<const Vector>(x + D * j) - Eigen::Map<const Vector>(xb + D * j));
  }
  const Block d0ii = Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>>(blocks_.data() + D * D * first_block);
  // the springs seen from node i: the vector to each's other end and its length, kept for the halvings (a cloth's
  // node has a dozen springs; past `kept`, computed again)
  const auto first_spring = static_cast<size_t>(k == 0 ? 0 : spring_end_[k - 1]), last_spring = static_cast<size_t>(spring_end_[k]);
  constexpr size_t kept = 16;
  std::array<Vector, kept> r;
  std::array<double, kept> length;
  const auto to_other = [&](const NodeSpring& spring) -> Vector {
    return spring.other < 0 ? Vector(Eigen::Map<const Vector>(spring.anchor.data()) - xi) : Vector(Eigen::Map<const Vector>(x + D * spring.other) - xi);
  };
  Vector force = Vector::Zero();
  LowerSum<D> stiffness;
  for (size_t s = first_spring; s < last_spring; ++s) {
    const NodeSpring& spring = springs_at_[s];
    const Vector to = to_other(spring);
    const double l = to.norm();
    if (s - first_spring < kept) r[s - first_spring] = to, length[s - first_spring] = l;
    add_spring_end<D>(to, l, spring.rest, spring.stiffness, true, force, stiffness);
  }
  const Vector g = mh * e - d0e / h - f0 - force;
  // H's inverse by cofactors (Eigen's fixed-size inverse, inlined: its LLT called an unblocked routine, 9% of a sweep);
  // positive definite by Sylvester's criterion, its leading minors positive
  const Block H = mh * Block::Identity() - d0ii / h + stiffness.full();
  Block inverse;
  double determinant = 0;
  bool invertible = false;
  H.computeInverseAndDetWithCheck(inverse, determinant, invertible);
  if (!invertible || !(H(0, 0) > 0) || !(H.template topLeftCorner<2, 2>().determinant() > 0) || !(determinant > 0)) return 0;
  const Vector step = -(inverse * g);
  const double slope = g.dot(step);
  if (!(slope < 0)) return 0;
  // halved until the node's change of G meets Armijo's fraction of the predicted decrease (else the node stays)
  for (int halving = 0; halving <= vbd_max_halvings; ++halving) {
    const double alpha = std::ldexp(1.0, -halving);
    const Vector d = alpha * step;
    double change = mh * (e.dot(d) + d.squaredNorm() / 2) - (d.dot(d0e) + d.dot(d0ii * d) / 2) / h - f0.dot(d);
    for (size_t s = first_spring; s < last_spring; ++s) {
      const NodeSpring& spring = springs_at_[s];
      if (const size_t at = s - first_spring; at < kept) {
        change += spring_end_change<D>(r[at], length[at], d, spring.rest, spring.stiffness);
      } else {
        const Vector to = to_other(spring);
        change += spring_end_change<D>(to, to.norm(), d, spring.rest, spring.stiffness);
      }
    }
    if (change <= vbd_armijo * alpha * slope) {
      xi += d;
      return -change;
    }
  }
  return 0;
}

double vbd_sweep(const VbdNodes& nodes, Eigen::VectorXd& x, int threads, Eigen::VectorXd& decrease) {
  decrease.setZero(x.size() / nodes.potential().dimension());
  std::atomic<double>* const workers = worker_cpu_seconds();  // the run's, its cpu_seconds counting every thread
  // one team for the whole sweep, the colours in turn (the barrier closing each colour's loop keeps them apart):
  // a team a colour started and joined a team for some 100 nodes, 1.38x one thread's CPU on the 32^2 flag
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const WorkerCpuTime timed(workers, omp_get_thread_num() != 0);
    size_t first = 0;
    for (const std::vector<int>& colour : nodes.colours()) {
      const auto count = static_cast<std::ptrdiff_t>(colour.size());
#pragma omp for schedule(static)
      for (std::ptrdiff_t k = 0; k < count; ++k) decrease[colour[static_cast<size_t>(k)]] += nodes.move(first + static_cast<size_t>(k), x);
      first += colour.size();
    }
  }
  return decrease.sum();
}

double vbd_iterate(const VbdNodes& nodes, Eigen::VectorXd& x, const VbdSweeps& how, Eigen::VectorXd& decrease) {
  const IncrementalPotential& potential = nodes.potential();
  const double rho2 = how.rho * how.rho;
  double total = 0, omega = 0;     // omega 0: the sequence starts again
  Eigen::VectorXd older, old, dx;  // x_{k-2} and x_{k-1}
  if (rho2 > 0) old = x;
  for (int k = 1; k <= how.sweeps; ++k) {
    total += vbd_sweep(nodes, x, how.threads, decrease);
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

bool VbdStepper::iterate(const VbdNodes& nodes, Eigen::VectorXd& x, double& decrease, std::string& /*failure*/) {
  decrease += vbd_iterate(nodes, x, sweeps_, decrease_);
  return true;
}

bool VbdStepper::substep(double t, double h, Eigen::VectorXd& y, std::string& failure) {
  potential_.start(t, y, h);
  if (nodes_) {
    nodes_->refresh();
  } else {
    // the colours from the force Jacobians' pattern (D0's, the view's one pattern), at the first step
    const auto* network = system_.as<SpringNetworkView>();
    nodes_.emplace(potential_, colour_nodes(potential_.damping(), view_.dimension), network ? network->network : nullptr);
    system_.stats().colours = static_cast<long>(nodes_->colours().size());
  }
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
  if (!iterate(*nodes_, x_, system_.stats().potential_decrease, failure)) return false;
  previous_v_ = y.tail(n_);
  previous_h_ = h;
  y.tail(n_) = (x_ - y.head(n_)) / h;
  y.head(n_) = x_;
  return true;
}

}  // namespace stepwise
