#include "springs.hpp"

#include "kernels/spring_end.hpp"
#include "kernels/spring_force.hpp"

#include <algorithm>
#include <stdexcept>

namespace stepwise {

namespace {

// x_b - x_a (the anchor for a pinned spring), x holding `dimension` coordinates a node (the rest of r zero)
Eigen::Vector3d span_of(const Spring& s, const double* x, int dimension) {
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  for (int c = 0; c < dimension; ++c) r[c] = x[dimension * s.b + c] - (s.a < 0 ? s.anchor[c] : x[dimension * s.a + c]);
  return r;
}

// v_b - v_a (an anchor does not move)
Eigen::Vector3d closing_of(const Spring& s, const double* v, int dimension) {
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  for (int c = 0; c < dimension; ++c) w[c] = v[dimension * s.b + c] - (s.a < 0 ? 0.0 : v[dimension * s.a + c]);
  return w;
}

// f[dimension i ..) += g's first `dimension` entries
void add_at(double* f, int i, int dimension, const Eigen::Vector3d& g) {
  for (int c = 0; c < dimension; ++c) f[dimension * i + c] += g[c];
}

}  // namespace

void add_springs_at_node(std::span<const Spring> springs, std::span<const int> which, int node, const double* x, bool definite, bool derivatives,
                         VertexElastic& out, int dimension) {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  LowerSum<3> block;
  for (const int k : which) {
    const Spring& s = springs[static_cast<size_t>(k)];
    const Eigen::Vector3d r = span_of(s, x, dimension);  // from a to b: from b, the other end is -r away
    out.energy += spring_end_energy<3>(r, s.rest, s.stiffness);
    if (derivatives) add_spring_end<3>(node == s.b ? Eigen::Vector3d(-r) : r, r.norm(), s.rest, s.stiffness, definite, force, block);
  }
  out.force += force;
  out.jacobian -= block.full();  // the force's derivative by the node's place: -dF/dr
}

void add_spring_forces(std::span<const Spring> springs, const double* x, const double* v, double* f, int dimension) {
  for (const Spring& s : springs) {
    const Eigen::Vector3d force = spring_force(span_of(s, x, dimension), closing_of(s, v, dimension), s.rest, s.stiffness, s.damping);
    add_at(f, s.b, dimension, -force);
    if (s.a >= 0) add_at(f, s.a, dimension, force);
  }
}

double spring_energy(std::span<const Spring> springs, const double* x, int dimension) {
  double e = 0;
  for (const Spring& s : springs) {
    const double stretch = span_of(s, x, dimension).norm() - s.rest;
    e += s.stiffness * stretch * stretch / 2;
  }
  return e;
}

BlockPattern::BlockPattern(int nodes, std::span<const std::pair<int, int>> pairs, int dimension) : nodes_(nodes), dimension_(dimension) {
  std::vector<std::vector<int>> columns(nodes);
  for (int j = 0; j < nodes; ++j) columns[j].push_back(j);
  for (const auto& [i, j] : pairs) {
    if (i < 0 || j < 0 || i >= nodes || j >= nodes) throw std::out_of_range("BlockPattern: node pair outside the network");
    columns[j].push_back(i);
    columns[i].push_back(j);
  }
  column_start_.push_back(0);
  for (auto& column : columns) {
    std::sort(column.begin(), column.end());
    column.erase(std::unique(column.begin(), column.end()), column.end());
    rows_.insert(rows_.end(), column.begin(), column.end());
    column_start_.push_back(static_cast<int>(rows_.size()));
  }
}

void BlockPattern::zero(Eigen::SparseMatrix<double>& m) const {
  const int d = dimension_;
  const Eigen::Index n = d * Eigen::Index{nodes_}, entries = d * d * static_cast<Eigen::Index>(rows_.size());
  if (m.rows() == n && m.cols() == n && m.isCompressed() && m.nonZeros() == entries) {
    std::fill(m.valuePtr(), m.valuePtr() + entries, 0.0);
    return;
  }
  m = Eigen::SparseMatrix<double>(n, n);
  m.resizeNonZeros(entries);
  Eigen::Index k = 0;
  for (int j = 0; j < nodes_; ++j)
    for (int c = 0; c < d; ++c) {
      m.outerIndexPtr()[d * j + c] = static_cast<int>(k);
      for (int b = column_start_[j]; b < column_start_[j + 1]; ++b)
        for (int r = 0; r < d; ++r, ++k) {
          m.innerIndexPtr()[k] = d * rows_[b] + r;
          m.valuePtr()[k] = 0;
        }
    }
  m.outerIndexPtr()[n] = static_cast<int>(k);
}

BlockPattern::Slot BlockPattern::slot(int i, int j) const {
  const auto first = rows_.begin() + column_start_[j], last = rows_.begin() + column_start_[j + 1];
  const auto found = std::lower_bound(first, last, i);
  if (found == last || *found != i) throw std::out_of_range("BlockPattern::slot: block outside the pattern");
  const Eigen::Index blocks = last - first, rank = found - first;
  const int d = dimension_;
  return {d * d * Eigen::Index{column_start_[j]} + d * rank, d * blocks, d};
}

std::vector<std::pair<int, int>> spring_pairs(std::span<const Spring> springs) {
  std::vector<std::pair<int, int>> pairs;
  for (const Spring& s : springs)
    if (s.a >= 0) pairs.emplace_back(s.a, s.b);
  return pairs;
}

std::vector<std::array<BlockPattern::Slot, 4>> spring_slots(std::span<const Spring> springs, const BlockPattern& pattern) {
  std::vector<std::array<BlockPattern::Slot, 4>> slots;
  for (const Spring& s : springs) {
    if (s.a < 0)
      slots.push_back({pattern.slot(s.b, s.b)});
    else
      slots.push_back({pattern.slot(s.b, s.b), pattern.slot(s.a, s.a), pattern.slot(s.a, s.b), pattern.slot(s.b, s.a)});
  }
  return slots;
}

void add_spring_force_jacobians(std::span<const Spring> springs, std::span<const std::array<BlockPattern::Slot, 4>> slots, const double* x,
                                const double* v, bool definite, Eigen::SparseMatrix<double>& dfdx, Eigen::SparseMatrix<double>* dfdv, int dimension) {
  for (size_t k = 0; k < springs.size(); ++k) {
    const Spring& s = springs[k];
    const Eigen::Vector3d r = span_of(s, x, dimension);
    const double length = r.norm();
    const Eigen::Vector3d u = r / length;
    const Eigen::Matrix3d uu = u * u.transpose(), across = Eigen::Matrix3d::Identity() - uu;
    Eigen::Matrix3d dr;
    if (definite) {
      dr = spring_stiffness<3>(u, length, s.rest, s.stiffness, true);
    } else {
      const Eigen::Vector3d w = dfdv ? closing_of(s, v, dimension) : Eigen::Vector3d::Zero();
      const double tension = s.stiffness * (length - s.rest) + s.damping * u.dot(w);
      dr = s.stiffness * uu + tension / length * across + s.damping / length * u * (across * w).transpose();
    }
    const Eigen::Matrix3d dw = s.damping * uu;
    // F acts on a (+) and b (-); it depends on r and w through x_b, v_b (+) and x_a, v_a (-)
    const auto& slot = slots[k];
    const auto add = [&](int block, double sign) {
      BlockPattern::add(dfdx, slot[block], sign * dr);
      if (dfdv) BlockPattern::add(*dfdv, slot[block], sign * dw);
    };
    add(0, -1);
    if (s.a < 0) continue;
    add(1, -1);
    add(2, 1);
    add(3, 1);
  }
}

void mass_spring_jacobian(const Eigen::SparseMatrix<double>& dfdx, const Eigen::SparseMatrix<double>& dfdv, std::span<const double> mass,
                          Eigen::SparseMatrix<double>& dfdy) {
  const Eigen::Index m = dfdx.rows(), dimension = m / static_cast<Eigen::Index>(mass.size());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<size_t>(m + dfdx.nonZeros() + dfdv.nonZeros()));
  for (Eigen::Index j = 0; j < m; ++j) entries.emplace_back(j, m + j, 1.0);
  for (int part = 0; part < 2; ++part) {
    const Eigen::SparseMatrix<double>& block = part == 0 ? dfdx : dfdv;
    for (Eigen::Index j = 0; j < m; ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(block, j); it; ++it)
        entries.emplace_back(m + it.row(), part * m + j, it.value() / mass[static_cast<size_t>(it.row() / dimension)]);
  }
  dfdy.resize(2 * m, 2 * m);
  dfdy.setFromTriplets(entries.begin(), entries.end());
}

SpringNetwork::SpringNetwork(std::vector<double> mass, std::vector<Spring> springs, int dimension, double drag)
    : view_{static_cast<int>(mass.size()), dimension, std::move(mass), std::move(springs)},
      drag_(drag),
      pattern_(view_.nodes, spring_pairs(view_.springs), dimension),
      slots_(spring_slots(view_.springs, pattern_)),
      by_node_(springs_by_node(view_.springs, view_.nodes)) {
  const Eigen::Index n = Eigen::Index{dimension} * view_.nodes;
  view_.force_jacobians = [this, n](double, const Eigen::Ref<const Eigen::VectorXd>& y, bool definite, Eigen::SparseMatrix<double>& dfdx,
                                    Eigen::SparseMatrix<double>& dfdv) { force_jacobians(y.data(), y.data() + n, definite, dfdx, dfdv); };
  view_.potential = [this](const Eigen::Ref<const Eigen::VectorXd>& x) { return spring_energy(view_.springs, x.data(), view_.dimension); };
  // the elastic part: the springs at rest relative to each other (their Voigt damping zero)
  view_.elastic_force = [this, n](const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) {
    const Eigen::VectorXd at_rest = Eigen::VectorXd::Zero(n);
    add_spring_forces(view_.springs, x.data(), at_rest.data(), f.data(), view_.dimension);
  };
  view_.elastic_jacobian = [this](const Eigen::Ref<const Eigen::VectorXd>& x, bool definite, Eigen::SparseMatrix<double>& dfdx) {
    pattern_.zero(dfdx);
    add_spring_force_jacobians(view_.springs, slots_, x.data(), nullptr, definite, dfdx, nullptr, view_.dimension);
  };
  view_.vertex_elastic = [this](int node, const Eigen::Ref<const Eigen::VectorXd>& x, bool definite, bool derivatives, VertexElastic& out) {
    add_springs_at_node(view_.springs, by_node_[static_cast<size_t>(node)], node, x.data(), definite, derivatives, out, view_.dimension);
  };
}

void SpringNetwork::force_jacobians(const double* x, const double* v, bool definite, Eigen::SparseMatrix<double>& dfdx,
                                    Eigen::SparseMatrix<double>& dfdv) const {
  pattern_.zero(dfdx);
  pattern_.zero(dfdv);
  for (int i = 0; i < view_.nodes; ++i)
    pattern_.add(dfdv, i, i, -view_.mass[static_cast<size_t>(i)] * drag_ * Eigen::Matrix3d::Identity());
  add_spring_force_jacobians(view_.springs, slots_, x, v, definite, dfdx, &dfdv, view_.dimension);
}

}  // namespace stepwise
