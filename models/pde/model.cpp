// The pde model: a scene's own PDE (models/pde.hpp) on its grid. The pointwise formulas are tapes of the stencil's
// values (models/pde/operators.hpp), with their derivatives by each stencil value (the Jacobian's entries), run at
// every node: compiled into one function of a node's values through the equations model's cache, or interpreted.
#include "models/pde.hpp"

#include "models/equations/c_source.hpp"
#include "models/equations/spec_checks.hpp"
#include "models/equations/symbolic.hpp"
#include "models/equations/tape.hpp"
#include "models/native_code.hpp"
#include "models/pde/operators.hpp"
#include "models/pde/stencil.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace stepwise {
namespace {

using namespace equations;
using namespace pde;

using NativeFn = void (*)(double t, const double* y, const double* p, double* out);
// the pointwise f over runs of consecutive nodes (pde_loop below): run r is nodes runs[3r] .. runs[3r] + runs[3r + 1]
// - 1, whose state entries are each node's number plus the offsets tables[runs[3r + 2] * width ..]
using NativeGridFn = void (*)(double t, const double* y, const double* p, double* out, const int* runs, int count, const int* tables, int total,
                              const double* x, const double* y_coordinate);

// f over the nodes whose every stencil value is a node of the state (no side's value or ghost, no upwind switch), in
// C beside the pointwise f it calls, so that the compiler inlines that into the loop: a node's cost is its formula's
// and its values' loads at offsets fixed along a run (the interior of a row is one run, a wrapped edge another), not
// a call through a pointer nor a gather through an index per value (bench_pde). Its sizes are the formula's, never
// the grid's
std::string pde_loop(int width, int fields) {
  // written out value by value: the loop over a run's nodes is then one block of arithmetic, which the compiler
  // vectorises (restrict: f's values never overlap the state's, nor the parameters)
  std::string offsets, gather, scatter;
  for (int k = 0; k < width; ++k) {
    offsets += fmt::format("    const int offset{0} = table[{0}];\n", k);
    gather += fmt::format("      local[{0}] = y[n + offset{0}];\n", k);
  }
  for (int f = 0; f < fields; ++f) scatter += fmt::format("      out[(long){} * total + n] = o[{}];\n", f, f);
  return fmt::format(
      // a local alias: a call through it binds here, and is inlined (one through the exported name goes through the
      // PLT, which another object could interpose)
      "static void stepwise_point(double t, const double* y, const double* p, double* out) __attribute__((alias(\"stepwise_rhs\")));\n"
      "void stepwise_grid_rhs(double t, const double* restrict y, const double* restrict p, double* restrict out, const int* runs,\n"
      "                       int count, const int* tables, int total, const double* restrict x, const double* restrict y_coordinate) {{\n"
      "  for (int r = 0; r < count; ++r) {{\n"
      "    const int first = runs[3 * r], end = first + runs[3 * r + 1];\n"
      "    const int* table = tables + (long)runs[3 * r + 2] * {0};\n"
      "{3}"
      "    for (int n = first; n < end; ++n) {{\n"
      "      double local[{0} + 2 + {2}], o[{1}];\n"
      "{4}"
      "      local[{0}] = x[n];\n"
      "      local[{0} + 1] = y_coordinate[n];\n"
      "      stepwise_point(t, local, p, o);\n"
      "{5}"
      "    }}\n"
      "  }}\n"
      "}}\n",
      width, fields, PdeSymbols::max_upwinds, offsets, gather, scatter);
}

// a Jacobian entry of the pointwise formulas: d f_row / d (field's value at slot)
struct Entry {
  int row, field, slot;
  Tape tape;
};

// one field's boundary formulas on the grid: per side its tape (a value or a normal derivative) and, for a value,
// its time derivative (the rate of the nodes that follow it)
struct SideTapes {
  std::optional<Tape> formula, rate;
};

class Pde final : public Model, public DenseJacobian, public SparseJacobian {
 public:
  Pde(const PdeSpec& spec, const Params& values, bool compile) {
    std::lock_guard lock(ginac_mutex);
    build(spec, values, compile);
  }

  std::string_view name() const override { return "pde"; }
  int size() const override { return fields() * grid_.nodes(); }
  bool autonomous() const override { return autonomous_; }
  std::vector<std::string> state_names() const override {
    std::vector<std::string> names;
    for (const auto& field : info_.fields)
      for (int n = 0; n < grid_.nodes(); ++n) names.push_back(fmt::format("{}[{}]", field, n));
    return names;
  }
  // each field's mean, min, max and L2 norm (sqrt of the sum of u^2 times a node's cell)
  std::vector<std::string> summary_names() const override {
    std::vector<std::string> names;
    for (const auto& field : info_.fields)
      for (const char* what : {"mean", "min", "max", "l2"}) names.push_back(field + "." + what);
    return names;
  }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override {
    Eigen::VectorXd s(4 * fields());
    const double cell = grid_.h[0] * (grid_.ny > 1 ? grid_.h[1] : 1.0);
    for (int f = 0; f < fields(); ++f) {
      const auto u = y.segment(Eigen::Index{f} * grid_.nodes(), grid_.nodes());
      s.segment<4>(4 * f) << u.mean(), u.minCoeff(), u.maxCoeff(), std::sqrt(u.squaredNorm() * cell);
    }
    return s;
  }
  // the initial formulas, and a Dirichlet side's value on its nodes
  Eigen::VectorXd initial_state() const override {
    Eigen::VectorXd y = on_grid(initial_, 0);
    const SideValues sides = side_values(0);
    for (int f = 0; f < fields(); ++f)
      for (int n = 0; n < grid_.nodes(); ++n)
        if (const int side = boundaries_[static_cast<size_t>(f)].dirichlet_side[static_cast<size_t>(n)]; side >= 0)
          y[index(f, n)] = sides.at(f, side, boundaries_[static_cast<size_t>(f)].dirichlet_position[static_cast<size_t>(n)]);
    return y;
  }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override;

  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    // the plain nodes in the compiled loop, the others (by a side, or upwinded) one by one below
    if (native_grid_)
      native_grid_(t, y.data(), p_.data(), dydt.data(), runs_.data(), static_cast<int>(runs_.size() / 3), tables_.data(), grid_.nodes(), info_.x.data(),
                   info_.y.data());
    if (native_grid_ && other_nodes_.empty()) return;
    const SideValues sides = side_values(t);
    thread_local std::vector<double> local, out;
    local.resize(static_cast<size_t>(locals_));
    out.resize(static_cast<size_t>(fields()));
    TapeStack stack(depth_);
    const NativeFn native = native_rhs_;
    const int count = native_grid_ ? static_cast<int>(other_nodes_.size()) : grid_.nodes();
    for (int m = 0; m < count; ++m) {
      const int n = native_grid_ ? other_nodes_[static_cast<size_t>(m)] : m;
      gather(t, y, sides, n, local.data(), stack.get());
      if (native) native(t, local.data(), p_.data(), out.data());
      else
        for (int f = 0; f < fields(); ++f) out[static_cast<size_t>(f)] = run(rhs_[static_cast<size_t>(f)], t, local.data(), p_.data(), stack.get());
      for (int f = 0; f < fields(); ++f) {
        const FieldBoundary& b = boundaries_[static_cast<size_t>(f)];
        const int side = b.dirichlet_side[static_cast<size_t>(n)];
        dydt[index(f, n)] = side < 0 ? out[static_cast<size_t>(f)] : sides.rate(f, side, b.dirichlet_position[static_cast<size_t>(n)]);
      }
    }
  }

  void sparse_jacobian(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& dfdy) const override {
    if (dfdy.rows() != size() || dfdy.nonZeros() != pattern_.nonZeros()) dfdy = pattern_;
    double* values = dfdy.valuePtr();
    std::fill(values, values + dfdy.nonZeros(), 0.0);
    const SideValues sides = side_values(t);
    thread_local std::vector<double> local, out;
    local.resize(static_cast<size_t>(locals_));
    out.resize(entries_.size());
    TapeStack stack(depth_);
    const NativeFn native = native_jacobian_;
    const size_t per_node = entries_.size();
    for (int n = 0; n < grid_.nodes(); ++n) {
      gather(t, y, sides, n, local.data(), stack.get());
      if (native) native(t, local.data(), p_.data(), out.data());
      else
        for (size_t e = 0; e < per_node; ++e) out[e] = run(entries_[e].tape, t, local.data(), p_.data(), stack.get());
      const int* from = &contributions_[static_cast<size_t>(n) * per_node];
      for (size_t e = 0; e < per_node; ++e)
        for (int c = from[e]; c < from[e + 1]; ++c) values[positions_[static_cast<size_t>(c)]] += weights_[static_cast<size_t>(c)] * out[e];
    }
  }
  void jacobian(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::MatrixXd> dfdy) const override {
    Eigen::SparseMatrix<double> sparse;
    sparse_jacobian(t, y, sparse);
    dfdy = Eigen::MatrixXd(sparse);
  }

  const void* capability(const std::type_info& type) const override {
    return offer(type, as_part<DenseJacobian>(*this), as_part<SparseJacobian>(*this), info_);
  }

 private:
  int fields() const { return static_cast<int>(info_.fields.size()); }
  Eigen::Index index(int field, int node) const { return Eigen::Index{field} * grid_.nodes() + node; }

  // each field's boundary formulas at time t, side by side, along each side (a value's rate beside it)
  struct SideValues {
    std::vector<std::array<std::vector<double>, 4>> values, rates;
    double rate(int f, int side, int position) const { return rates[static_cast<size_t>(f)][static_cast<size_t>(side)][static_cast<size_t>(position)]; }
    double at(int f, int side, int position) const { return values[static_cast<size_t>(f)][static_cast<size_t>(side)][static_cast<size_t>(position)]; }
  };
  SideValues side_values(double t) const {
    SideValues s;
    s.values.resize(static_cast<size_t>(fields()));
    s.rates.resize(static_cast<size_t>(fields()));
    TapeStack stack(depth_);
    for (int f = 0; f < fields(); ++f)
      for (int side = 0; side < 4; ++side) {
        const SideTapes& tapes = sides_[static_cast<size_t>(f)][static_cast<size_t>(side)];
        if (!tapes.formula) continue;
        auto& values = s.values[static_cast<size_t>(f)][static_cast<size_t>(side)];
        auto& rates = s.rates[static_cast<size_t>(f)][static_cast<size_t>(side)];
        for (int k = 0; k < grid_.along(side); ++k) {
          const auto point = side_point(grid_, side, k);
          values.push_back(run(*tapes.formula, t, point.data(), p_.data(), stack.get()));
          rates.push_back(tapes.rate ? run(*tapes.rate, t, point.data(), p_.data(), stack.get()) : 0.0);
        }
      }
    return s;
  }

  // node n's stencil values of every field, its coordinates and its upwind switches, into `local`
  void gather(double t, const Eigen::Ref<const Eigen::VectorXd>& y, const SideValues& sides, int n, double* local, double* stack) const {
    const int slots = stencil_.size();
    for (int f = 0; f < fields(); ++f) {
      const FieldBoundary& b = boundaries_[static_cast<size_t>(f)];
      const Source* source = &b.sources[static_cast<size_t>(n) * static_cast<size_t>(slots)];
      double* out = local + f * slots;
      for (int s = 0; s < slots; ++s) {
        const Source& from = source[s];
        switch (from.kind) {
          case Source::Kind::node: out[s] = y[index(f, from.node)]; break;
          case Source::Kind::dirichlet: out[s] = sides.at(f, from.side, from.position); break;
          case Source::Kind::ghost: {
            // outside the side: its combination of the values inside, plus slope h times the outward normal derivative
            const Ghost& ghost = b.ghosts[static_cast<size_t>(from.node)];
            double value = 0;
            for (const auto& [term, weight] : ghost.terms)
              value += weight * (term.kind == Source::Kind::node ? y[index(f, term.node)] : sides.at(f, term.side, term.position));
            out[s] = ghost.slope == 0 ? value : value + ghost.slope * grid_.h[from.side < 2 ? 0 : 1] * sides.at(f, from.side, from.position);
            break;
          }
        }
      }
    }
    local[coordinates_] = info_.x[static_cast<size_t>(n)];
    local[coordinates_ + 1] = info_.y[static_cast<size_t>(n)];
    for (size_t k = 0; k < upwinds_.size(); ++k) local[switches_ + static_cast<int>(k)] = run(upwinds_[k], t, local, p_.data(), stack) >= 0 ? 1.0 : 0.0;
  }

  // a formula of x, y (and t) at every node of each field
  Eigen::VectorXd on_grid(const std::vector<Tape>& tapes, double t) const {
    Eigen::VectorXd y(size());
    TapeStack stack(depth_);
    for (int f = 0; f < fields(); ++f)
      for (int n = 0; n < grid_.nodes(); ++n) {
        const double point[2] = {info_.x[static_cast<size_t>(n)], info_.y[static_cast<size_t>(n)]};
        y[index(f, n)] = run(tapes[static_cast<size_t>(f)], t, point, p_.data(), stack.get());
      }
    return y;
  }

  void build(const PdeSpec& spec, const Params& values, bool compile);
  void check_start(const PdeSpec& s, const Eigen::VectorXd& y0) const;
  void make_grid(const PdeSpec& s);
  PdeSymbols make_symbols(const PdeSpec& s);
  void make_field_tapes(const PdeSpec& s, PdeSymbols& ps, Derived& derived);
  void make_coordinate_tapes(const PdeSpec& s, const Symbols& sym, Derived& derived);
  void make_boundaries(const PdeSpec& spec, const Symbols& coordinates, Derived& derived);
  void make_pattern();
  void start_native(bool compile);

  PdeGrid info_;
  std::vector<std::array<double, 2>> drawn_range_;  // each field's least and greatest initial value: a 1-D curve's scale
  Layout grid_;
  Stencil stencil_{2, 1};
  std::vector<FieldBoundary> boundaries_;
  std::vector<std::array<SideTapes, 4>> sides_;
  std::vector<Tape> rhs_, initial_, exact_, upwinds_;
  std::vector<Entry> entries_;
  std::vector<double> p_;
  int locals_ = 0, coordinates_ = 0, switches_ = 0, depth_ = 1;
  bool autonomous_ = true;
  Eigen::SparseMatrix<double> pattern_;
  // node-major, entry e of node n adds weights_[c] times its value at the place positions_[c] among the Jacobian's
  // values, for c from contributions_[n * entries + e] to the next
  std::vector<int> contributions_, positions_;
  std::vector<double> weights_;
  std::shared_ptr<const NativeCode> native_;
  NativeFn native_rhs_ = nullptr, native_jacobian_ = nullptr;
  NativeGridFn native_grid_ = nullptr;  // null: every node one by one
  std::vector<int> other_nodes_;    // the nodes the compiled loop leaves, one by one
  std::vector<int> runs_, tables_;  // the loop's runs of nodes and their offsets tables (NativeGridFn)
};

// a formula's text parsed with the operators, and expanded; the operator misapplied named at its column
GiNaC::ex parse_field_formula(const Formula& f, PdeSymbols& symbols, const Stencil& stencil, int order, int dimension) {
  try {
    // expanded: GiNaC keeps a sum that is a factor of a product with its sign made canonical by its terms' hash order,
    // and its hashes follow the addresses of type names (ASLR): (u(x+1) - 2u + u(x-1)) D/h^2 came out as that or as
    // (2u - u(x+1) - u(x-1)) (-D/h^2) from run to run, rounding differently. A sum of products has one form
    return expand(parse(f, symbols.symbols, true, true, operator_table()), symbols, stencil, order, dimension).expand();
  } catch (const OperatorError& e) {
    throw BadEquations(fmt::format("{}: {}", f.where(std::max(1, column_of(f.text, e.name))), e.what()));
  }
}

// the formula of each field, in the fields' order: every field has exactly one, and no other name has one
std::vector<const Formula*> by_field(const std::vector<Formula>& formulas, const std::vector<std::string>& fields, const std::string& file,
                                     const char* table, bool all) {
  std::vector<const Formula*> out(fields.size(), nullptr);
  for (const Formula& f : formulas) {
    const auto it = std::find(fields.begin(), fields.end(), f.name);
    if (it == fields.end()) throw BadEquations(fmt::format("{}: '{}' is not a field (fields: {})", f.where(), f.name, fmt::join(fields, ", ")));
    out[static_cast<size_t>(it - fields.begin())] = &f;
  }
  for (size_t i = 0; i < fields.size() && all; ++i)
    if (!out[i]) throw BadEquations(fmt::format("{}: [{}] has no formula for the field '{}'", file, table, fields[i]));
  return out;
}

// the spec with `values` applied: the parameters, and the grid's points and order
PdeSpec with_values(const PdeSpec& spec, const Params& values) {
  PdeSpec s = spec;
  for (const auto& [key, value] : values) {
    if (key == "points") {
      if (!(value >= 1 && value <= 1e9 && std::floor(value) == value)) throw BadParameter(key, fmt::format("points = {}: a whole number of nodes", value));
      s.points = {static_cast<int>(value), s.dimension == 2 ? static_cast<int>(value) : 1};
      s.points_where = "--set points";
    } else if (key == "order") {
      if (value != 2 && value != 4) throw BadParameter(key, fmt::format("order = {}: the central stencils are of order 2 or 4", value));
      s.order = static_cast<int>(value);
      s.order_where = "--set order";
    } else if (s.parameters.count(key)) {
      if (!std::isfinite(value)) throw BadParameter(key, fmt::format("{} = {} is not finite", key, value));
      s.parameters[key] = value;
    } else {
      throw BadParameter(key, fmt::format("unknown parameter '{}' (the scene's parameters, points and order)", key));
    }
  }
  return s;
}

void Pde::build(const PdeSpec& spec, const Params& values, bool compile) {
  const PdeSpec s = with_values(spec, values);
  make_grid(s);
  PdeSymbols ps = make_symbols(s);
  Derived derived;
  derived.first_slot = static_cast<int>(p_.size());
  make_field_tapes(s, ps, derived);
  make_coordinate_tapes(s, ps.symbols, derived);
  // the derived slots' values, and the tapes' deepest stack
  for (const Tape& t : derived.tapes) depth_ = std::max(depth_, t.depth);
  for (const Tape& t : derived.tapes) p_.push_back(run(t, 0, nullptr, p_.data(), TapeStack(depth_).get()));
  for (const auto* tapes : {&rhs_, &initial_, &exact_, &upwinds_})
    for (const Tape& t : *tapes) depth_ = std::max(depth_, t.depth);
  for (const Entry& e : entries_) depth_ = std::max(depth_, e.tape.depth);
  for (const auto& field : sides_)
    for (const SideTapes& side : field)
      for (const auto* tape : {&side.formula, &side.rate})
        if (*tape) depth_ = std::max(depth_, (*tape)->depth);
  make_pattern();
  start_native(compile);
  if (!exact_.empty()) info_.exact = [this](double t) { return on_grid(exact_, t); };
  const Eigen::VectorXd y0 = initial_state();
  check_start(s, y0);
  for (int f = 0; f < fields(); ++f) {
    const auto u = y0.segment(Eigen::Index{f} * grid_.nodes(), grid_.nodes());
    std::array<double, 2> range{u.minCoeff(), u.maxCoeff()};
    if (!(range[1] > range[0])) range[1] = range[0] + std::max(1.0, std::abs(range[0]));
    drawn_range_.push_back(range);
  }
}

// each field's rate finite at the initial state (a coefficient the parameters make infinite, 1/(k - 0.06) at
// k = 0.06, or a side's value sqrt(t), would have every method diverge at t = 0): the formula that gives the first
// node where it is not (the field's equation, or on a Dirichlet side's node that side's value, whose rate in t the
// state holds), before any method runs. A start that is itself not finite is the run's to refuse (run/prepare.cpp)
void Pde::check_start(const PdeSpec& s, const Eigen::VectorXd& y0) const {
  if (!y0.allFinite()) return;
  Eigen::VectorXd dydt(y0.size());
  rhs(0, y0, dydt);
  if (dydt.allFinite()) return;
  Eigen::Index at = 0;
  while (std::isfinite(dydt[at])) ++at;
  const auto field = static_cast<size_t>(at / grid_.nodes());
  const auto node = static_cast<size_t>(at % grid_.nodes());
  std::string where;
  if (const int side = boundaries_[field].dirichlet_side[node]; side >= 0) {
    const auto b = std::find_if(s.boundary.begin(), s.boundary.end(), [&](const auto& entry) { return entry.first == s.fields[field]; });
    where = b->second.sides[static_cast<size_t>(side)]->formula.where() + " (its rate in t)";
  } else {
    where = by_field(s.equations, s.fields, s.file, "equations", true)[field]->where();
  }
  throw BadEquations(fmt::format("{}: the formula is {} at the initial state (t = 0, x = {:g}{})", where, dydt[at], info_.x[node],
                                 s.dimension == 2 ? fmt::format(", y = {:g}", info_.y[node]) : std::string()));
}

// a 2-D grid's fields as pictures side by side, one colour range over an animation; a 1-D grid's as curves
// u(x) over the domain, one above the other, each drawn 0.6 of the domain's length high over its initial range
std::optional<Shapes> Pde::shapes(const Eigen::VectorXd& y) const {
  Shapes s;
  s.planar = true;
  s.up = Eigen::Vector3d::UnitY();
  const double length = info_.domain[0][1] - info_.domain[0][0];
  for (int f = 0; f < fields(); ++f) {
    const auto u = y.segment(Eigen::Index{f} * grid_.nodes(), grid_.nodes());
    if (info_.ny > 1) {
      s.fields.push_back({.nx = info_.nx, .ny = info_.ny,
                          .origin = {info_.domain[0][0] + drawn_offset(info_, static_cast<size_t>(f)), info_.domain[1][0]},
                          .extent = {length, info_.domain[1][1] - info_.domain[1][0]},
                          .periodic = info_.periodic, .values = u, .same_range = true});
      continue;
    }
    const double height = 0.6 * length, base = -1.4 * height * f;
    const auto [low, high] = drawn_range_[static_cast<size_t>(f)];
    std::vector<Eigen::Vector3d> curve;
    for (int i = 0; i < info_.nx; ++i) curve.emplace_back(info_.x[static_cast<size_t>(i)], base + height * (u[i] - low) / (high - low), 0);
    // a periodic axis's curve closes at the domain's far end, the first node's image
    if (info_.periodic[0]) curve.emplace_back(info_.domain[0][1], curve.front().y(), 0);
    s.lines.push_back(std::move(curve));
  }
  return s;
}


// the nodes, the stencil and the grid's coordinates: a PDE's axis is periodic where every field's is
void Pde::make_grid(const PdeSpec& s) {
  info_.fields = s.fields;
  std::array<bool, 2> periodic{true, true};
  for (const auto& [field, boundary] : s.boundary)
    for (int axis = 0; axis < s.dimension; ++axis) periodic[static_cast<size_t>(axis)] = periodic[static_cast<size_t>(axis)] && boundary.periodic[static_cast<size_t>(axis)];
  stencil_ = Stencil(s.order, s.dimension);
  for (int axis = 0; axis < s.dimension; ++axis)
    if (s.points[static_cast<size_t>(axis)] < 2 * stencil_.radius + 1)
      throw BadEquations(fmt::format("{}: {} nodes along {}, fewer than the order-{} stencil's {}", s.points_where, s.points[static_cast<size_t>(axis)],
                                     axis == 0 ? "x" : "y", s.order, 2 * stencil_.radius + 1));
  if (const double unknowns = static_cast<double>(s.points[0]) * s.points[1] * static_cast<double>(s.fields.size()); unknowns > max_pde_unknowns)
    throw BadEquations(fmt::format("{}: {:.3g} unknowns, more than the {:.3g} that fit in memory", s.points_where, unknowns, max_pde_unknowns));
  grid_ = layout_of(s, periodic);
  info_.nx = grid_.nx;
  info_.ny = grid_.ny;
  info_.domain = s.domain;
  if (s.dimension == 1) info_.domain[1] = {0, 0};
  info_.periodic = {periodic[0], s.dimension == 2 && periodic[1]};
  for (int j = 0; j < grid_.ny; ++j)
    for (int i = 0; i < grid_.nx; ++i) {
      info_.x.push_back(grid_.origin[0] + i * grid_.h[0]);
      info_.y.push_back(grid_.origin[1] + j * grid_.h[1]);
    }

}

// the symbols: each field's stencil values, x, y, the switches; the parameters, hx, hy (their values into p_)
PdeSymbols Pde::make_symbols(const PdeSpec& s) {
  PdeSymbols ps;
  ps.fields = fields();
  ps.slots = stencil_.size();
  Symbols& sym = ps.symbols;
  const auto variable = [&](const std::string& name) {
    sym.index[name] = {true, static_cast<int>(sym.variables.size())};
    sym.variables.push_back(symbol_named(name));
    sym.variable_names.push_back(name);
  };
  for (const auto& field : s.fields)
    for (const auto& o : stencil_.offsets)
      variable(o == std::array{0, 0} ? field : fmt::format("{}({}{:+d})", field, o[0] != 0 ? 'x' : 'y', o[0] != 0 ? o[0] : o[1]));
  // (a 1-D scene's y is no name a formula can use: its slot is 0)
  ps.coordinates = coordinates_ = static_cast<int>(sym.variables.size());
  variable("x");
  variable(s.dimension == 2 ? "y" : "grid.y");
  ps.switches = switches_ = static_cast<int>(sym.variables.size());
  for (int k = 0; k < PdeSymbols::max_upwinds; ++k) variable(fmt::format("upwind#{}", k));
  locals_ = static_cast<int>(sym.variables.size());
  for (const auto& [name, value] : s.parameters) {
    sym.index[name] = {false, static_cast<int>(sym.parameters.size())};
    sym.parameters.push_back(symbol_named(name));
    sym.parameter_names.push_back(name);
    p_.push_back(value);
  }
  ps.spacing = static_cast<int>(sym.parameters.size());
  for (int axis = 0; axis < 2; ++axis) {
    sym.index[axis == 0 ? "grid.hx" : "grid.hy"] = {false, static_cast<int>(sym.parameters.size())};
    sym.parameters.push_back(symbol_named(axis == 0 ? "grid.hx" : "grid.hy"));
    sym.parameter_names.push_back(axis == 0 ? "grid.hx" : "grid.hy");
    p_.push_back(grid_.h[static_cast<size_t>(axis)]);
  }
  sym.defined = fmt::format("fields {}; x{}{}{}", fmt::join(s.fields, ", "), s.dimension == 2 ? ", y" : "",
                            sym.parameter_names.size() > 2 ? "; parameters " : "",
                            fmt::join(std::vector(sym.parameter_names.begin(), sym.parameter_names.end() - 2), ", "));

  return ps;
}

// the pointwise formulas' tapes: f's, its Jacobian's entries (each formula by each stencil value), the upwind
// coefficients
void Pde::make_field_tapes(const PdeSpec& s, PdeSymbols& ps, Derived& derived) {
  Symbols& sym = ps.symbols;
  const auto equations = by_field(s.equations, s.fields, s.file, "equations", true);
  std::vector<GiNaC::ex> f;
  for (size_t i = 0; i < s.fields.size(); ++i) {
    f.push_back(parse_field_formula(*equations[i], ps, stencil_, s.order, s.dimension));
    rhs_.push_back(build_tape(sym, derived, equations[i]->where(), equations[i], f.back()));
  }
  autonomous_ = std::none_of(f.begin(), f.end(), [&](const GiNaC::ex& e) { return e.has(sym.t); });
  for (size_t k = 0; k < ps.upwind_coefficients.size(); ++k)
    upwinds_.push_back(build_tape(sym, derived, fmt::format("{} (upwind coefficient {})", s.file, k + 1), nullptr, ps.upwind_coefficients[k]));
  Differentiator differentiate(sym);
  for (int row = 0; row < fields(); ++row)
    for (int c = 0; c < ps.fields * ps.slots; ++c) {
      const GiNaC::ex d = differentiate.derivative(f[static_cast<size_t>(row)], c);
      if (d.is_zero()) continue;
      entries_.push_back({row, c / ps.slots, c % ps.slots,
                          build_tape(sym, derived, fmt::format("{} (its derivative in {})", equations[static_cast<size_t>(row)]->where(), sym.variable_names[static_cast<size_t>(c)]), nullptr, d)});
    }

}

// the formulas of x, y and t: initial values, [exact], the boundaries
void Pde::make_coordinate_tapes(const PdeSpec& s, const Symbols& sym, Derived& derived) {
  Symbols coordinates;
  for (const char* name : {"x", s.dimension == 2 ? "y" : "grid.y"}) {
    coordinates.index[name] = {true, static_cast<int>(coordinates.variables.size())};
    coordinates.variables.push_back(symbol_named(name));
    coordinates.variable_names.push_back(name);
  }
  coordinates.parameters = sym.parameters;
  coordinates.parameter_names = sym.parameter_names;
  for (size_t k = 0; k < sym.parameter_names.size(); ++k) coordinates.index[sym.parameter_names[k]] = {false, static_cast<int>(k)};
  coordinates.defined = fmt::format("x{}{}", s.dimension == 2 ? ", y" : "", sym.parameter_names.size() > 2 ? "; and the parameters" : "");
  for (const Formula* formula : by_field(s.initial, s.fields, s.file, "initial", true))
    initial_.push_back(build_tape(coordinates, derived, formula->where(), formula, parse(*formula, coordinates, true, false)));
  if (!s.exact.empty())
    for (const Formula* formula : by_field(s.exact, s.fields, s.file, "exact", true))
      exact_.push_back(build_tape(coordinates, derived, formula->where(), formula, parse(*formula, coordinates, true, true)));
  make_boundaries(s, coordinates, derived);

}

// each field's boundary on the grid, and its sides' formulas (a value's time derivative beside it)
void Pde::make_boundaries(const PdeSpec& s, const Symbols& coordinates, Derived& derived) {
  const char* side_names[] = {"left", "right", "bottom", "top"};
  for (const auto& field : s.fields) {
    const auto it = std::find_if(s.boundary.begin(), s.boundary.end(), [&](const auto& b) { return b.first == field; });
    if (it == s.boundary.end()) throw BadEquations(fmt::format("{}: the field '{}' has no [boundary.{}]", s.fields_where, field, field));
    const PdeBoundary& b = it->second;
    for (int axis = 0; axis < s.dimension; ++axis) {
      const bool periodic = b.periodic[static_cast<size_t>(axis)];
      for (int side = 2 * axis; side < 2 * axis + 2; ++side) {
        if (periodic && b.sides[static_cast<size_t>(side)])
          throw BadEquations(fmt::format("{}: {} is periodic and has a {} condition too", b.where, axis == 0 ? "x" : "y", side_names[side]));
        if (!periodic && !b.sides[static_cast<size_t>(side)])
          throw BadEquations(fmt::format("{}: no condition on the {} side ({} = \"periodic\", or {} = {{ value = \"...\" }} or {{ derivative = \"...\" }})",
                                         b.where, side_names[side], axis == 0 ? "x" : "y", side_names[side]));
      }
    }
    std::array<SideTapes, 4> tapes;
    for (int side = 0; side < 4; ++side)
      if (const auto& condition = b.sides[static_cast<size_t>(side)]) {
        if (side >= 2 && s.dimension == 1) throw BadEquations(fmt::format("{}: {} in a 1-D scene (its [grid] has no y)", condition->formula.where(), side_names[side]));
        const GiNaC::ex e = parse(condition->formula, coordinates, true, true);
        SideTapes& t = tapes[static_cast<size_t>(side)];
        t.formula = build_tape(coordinates, derived, condition->formula.where(), &condition->formula, e);
        if (condition->kind == PdeSide::Kind::value)
          t.rate = build_tape(coordinates, derived, condition->formula.where() + " (its rate in t)", nullptr, e.diff(symbol_named("t")));
      }
    sides_.push_back(std::move(tapes));
    boundaries_.push_back(field_boundary(grid_, stencil_, b));
  }
}

// the Jacobian's pattern (every diagonal in it: the Newton matrix I - h J has it), and where each entry of each
// node adds its value, by what weight: a stencil value read from a node adds to that node's column; one from a
// ghost to each node the ghost is made from, by its weight; one from a Dirichlet side to none
void Pde::make_pattern() {
  const int nodes = grid_.nodes(), slots = stencil_.size();
  // an entry's columns at node n, with their weights
  const auto columns_of = [&](const Entry& e, int n, const auto& visit) {
    const FieldBoundary& b = boundaries_[static_cast<size_t>(e.field)];
    const Source& from = b.sources[static_cast<size_t>(n) * static_cast<size_t>(slots) + static_cast<size_t>(e.slot)];
    if (from.kind == Source::Kind::node) visit(index(e.field, from.node), 1.0);
    if (from.kind == Source::Kind::ghost)
      for (const auto& [term, weight] : b.ghosts[static_cast<size_t>(from.node)].terms)
        if (term.kind == Source::Kind::node) visit(index(e.field, term.node), weight);
  };
  const auto evaluated = [&](const Entry& e, int n) { return boundaries_[static_cast<size_t>(e.row)].dirichlet_side[static_cast<size_t>(n)] < 0; };
  std::vector<Eigen::Triplet<double>> triplets;
  for (Eigen::Index i = 0; i < size(); ++i) triplets.emplace_back(i, i, 0.0);
  for (int n = 0; n < nodes; ++n)
    for (const Entry& e : entries_)
      if (evaluated(e, n)) columns_of(e, n, [&](Eigen::Index c, double) { triplets.emplace_back(index(e.row, n), c, 0.0); });
  pattern_.resize(size(), size());
  pattern_.setFromTriplets(triplets.begin(), triplets.end());
  pattern_.makeCompressed();
  contributions_.assign(static_cast<size_t>(nodes) * entries_.size() + 1, 0);
  for (int n = 0; n < nodes; ++n)
    for (size_t k = 0; k < entries_.size(); ++k) {
      const Entry& e = entries_[k];
      const size_t at = static_cast<size_t>(n) * entries_.size() + k;
      contributions_[at + 1] = contributions_[at];
      if (!evaluated(e, n)) continue;
      const Eigen::Index r = index(e.row, n);
      columns_of(e, n, [&](Eigen::Index c, double weight) {
        const int* rows = pattern_.innerIndexPtr();
        const int begin = pattern_.outerIndexPtr()[c], end = pattern_.outerIndexPtr()[c + 1];
        positions_.push_back(static_cast<int>(std::lower_bound(rows + begin, rows + end, r) - rows));
        weights_.push_back(weight);
        ++contributions_[at + 1];
      });
    }
}

// the pointwise formulas and their derivatives compiled into one function each of a node's values
void Pde::start_native(bool compile) {
  if (!compile) return;
  std::vector<Tape> jacobian;
  for (const Entry& e : entries_) jacobian.push_back(e.tape);
  NativeSource source = c_source(rhs_, jacobian, 64 << 10, 1 << 20);
  const int width = fields() * stencil_.size();
  source.units.front() += pde_loop(width, fields());
  // -O3, which vectorises the loop over a run (bench_pde: 2.3x -O2's time at Gray-Scott 256^2), where the formulas are
  // of a size the equations model compiles at -O2; -O1 above
  source.optimisation = source.bytes() <= EquationsOptions{}.optimise_below ? "-O3" : "-O1";
  std::string why;
  native_ = load_native(source, CompileLimits{}, why);
  if (!native_) return;
  native_rhs_ = reinterpret_cast<NativeFn>(native_->symbol("stepwise_rhs"));
  native_jacobian_ = reinterpret_cast<NativeFn>(native_->symbol("stepwise_jacobian"));
  if (!native_rhs_ || !native_jacobian_) {
    native_rhs_ = native_jacobian_ = nullptr;
    return;
  }
  // an upwinded formula reads its switches, which the loop does not set: every node one by one
  if (!upwinds_.empty()) return;
  native_grid_ = reinterpret_cast<NativeGridFn>(native_->symbol("stepwise_grid_rhs"));
  // a run: consecutive plain nodes whose state entries lie at the same offsets from the node, fields x slots
  std::map<std::vector<int>, int> table_of;
  std::vector<int> offsets(static_cast<size_t>(width));
  int last_table = -1;
  for (int n = 0; n < grid_.nodes(); ++n) {
    bool plain = true;
    for (int f = 0; f < fields() && plain; ++f) {
      const FieldBoundary& b = boundaries_[static_cast<size_t>(f)];
      plain = b.dirichlet_side[static_cast<size_t>(n)] < 0;
      for (int k = 0; k < stencil_.size() && plain; ++k) {
        const Source& from = b.sources[static_cast<size_t>(n * stencil_.size() + k)];
        plain = from.kind == Source::Kind::node;
        offsets[static_cast<size_t>(f * stencil_.size() + k)] = static_cast<int>(index(f, from.node) - n);
      }
    }
    if (!plain) {
      other_nodes_.push_back(n);
      last_table = -1;
      continue;
    }
    const auto [it, added] = table_of.emplace(offsets, static_cast<int>(table_of.size()));
    if (added) tables_.insert(tables_.end(), offsets.begin(), offsets.end());
    if (it->second == last_table && runs_[runs_.size() - 3] + runs_[runs_.size() - 2] == n) ++runs_[runs_.size() - 2];
    else runs_.insert(runs_.end(), {n, 1, it->second});
    last_table = it->second;
  }
}

}  // namespace

std::unique_ptr<Model> make_pde(const PdeSpec& spec, const Params& values, bool compile) { return std::make_unique<Pde>(spec, values, compile); }

const PdeGrid* pde_grid(const Model& model) { return model.as<PdeGrid>(); }

double drawn_offset(const PdeGrid& grid, size_t field) { return 1.1 * static_cast<double>(field) * (grid.domain[0][1] - grid.domain[0][0]); }

}  // namespace stepwise
