// The equations model: a scene's own system (models/equations.hpp) from its tapes, with its events, its
// Jacobian made on first use (in the background for a large system) and its compiled code adopted when loaded.
#include "models/equations.hpp"

#include "models/equations/c_source.hpp"
#include "models/equations/spec_checks.hpp"
#include "models/equations/symbolic.hpp"
#include "models/equations/tape.hpp"
#include "models/native_code.hpp"
#include "solvers/capabilities/inline_rhs.hpp"
#include "solvers/capabilities/second_order.hpp"

#include <boost/container/small_vector.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <set>
#include <thread>

namespace stepwise {
namespace {

using namespace equations;

using NativeFn = void (*)(double t, const double* y, const double* p, double* out);

// what the Jacobian is made from: the parsed formulas and their symbols, kept until it is made
struct JacobianWork {
  Symbols symbols;
  std::vector<GiNaC::ex> f;
  std::vector<std::string> where;  // each formula's place, for a message about its derivative
  Derived derived;                 // the derived slots so far (f's), which the Jacobian's continue
  Differentiator differentiate{symbols};
};

// the exact Jacobian: its nonzeros' tapes column by column (CSC order) with the pattern, and the parameter
// array its tapes read (f's, then the derived slots of the Jacobian's own)
struct JacobianTapes {
  std::vector<Tape> tapes;
  std::vector<int> columns, rows;  // column c's entries are [columns[c], columns[c+1])
  std::vector<double> p;
  int depth = 1;
};

// a model destroyed while its Jacobian is made in the background stops that
struct Cancelled {};

class Equations final : public Model, public DenseJacobian, public SparseJacobian, public EventSource {
 public:
  Equations(const EquationsSpec& spec, const Params& values, const EquationsOptions& options) {
    std::lock_guard lock(ginac_mutex);
    try {
      build(spec, values, options);
    } catch (...) {
      work_.reset();  // GiNaC's objects go under the lock
      throw;
    }
  }
  // a compile still running in the background is stopped (its compiler's process group killed)
  ~Equations() override {
    cancel_.store(true);
    if (background_.joinable()) background_.join();
    std::lock_guard lock(ginac_mutex);
    work_.reset();
  }
  Equations(const Equations&) = delete;
  Equations& operator=(const Equations&) = delete;

  std::string_view name() const override { return "equations"; }
  // the variables, then a resting flag for each event with a rest rule
  int size() const override { return static_cast<int>(names_.size() + flag_names_.size()); }
  bool autonomous() const override { return autonomous_; }
  std::vector<std::string> state_names() const override {
    std::vector<std::string> names = names_;
    names.insert(names.end(), flag_names_.begin(), flag_names_.end());
    return names;
  }
  Eigen::VectorXd initial_state() const override { return y0_; }
  std::span<const Event> events() const override { return events_; }

  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    if (const NativeFn native = native_rhs_.load(std::memory_order_acquire)) native(t, y.data(), p_.data(), dydt.data());
    else {
      TapeStack tape_stack(depth_);
      double* stack = tape_stack.get();
      for (size_t i = 0; i < rhs_.size(); ++i) dydt[static_cast<Eigen::Index>(i)] = run(rhs_[i], t, y.data(), p_.data(), stack);
    }
    if (!flag_names_.empty()) hold(y, [&](int variable) { dydt[variable] = 0; });
  }

  void jacobian(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::MatrixXd> dfdy) const override {
    const JacobianTapes& J = jacobian_tapes();
    thread_local std::vector<double> values;
    values.resize(J.rows.size());
    jacobian_values(t, y.data(), values.data());
    dfdy.setZero();
    for (size_t c = 0; c < names_.size(); ++c)
      for (int k = J.columns[c]; k < J.columns[c + 1]; ++k) dfdy(J.rows[static_cast<size_t>(k)], static_cast<Eigen::Index>(c)) = values[static_cast<size_t>(k)];
    if (!flag_names_.empty()) hold(y, [&](int variable) { dfdy.row(variable).setZero(); });
  }
  void sparse_jacobian(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& dfdy) const override {
    const JacobianTapes& J = jacobian_tapes();
    if (dfdy.rows() != size() || dfdy.cols() != size() || dfdy.nonZeros() != static_cast<Eigen::Index>(J.rows.size()) || !dfdy.isCompressed()) {
      std::vector<Eigen::Triplet<double>> pattern;
      for (size_t c = 0; c < names_.size(); ++c)
        for (int k = J.columns[c]; k < J.columns[c + 1]; ++k) pattern.emplace_back(J.rows[static_cast<size_t>(k)], static_cast<int>(c), 1.0);
      dfdy.resize(size(), size());
      dfdy.setFromTriplets(pattern.begin(), pattern.end());
      dfdy.makeCompressed();
    }
    jacobian_values(t, y.data(), dfdy.valuePtr());
    if (!flag_names_.empty())
      hold(y, [&](int variable) {
        for (Eigen::Index c = 0; c < dfdy.outerSize(); ++c)
          for (Eigen::SparseMatrix<double>::InnerIterator it(dfdy, c); it; ++it)
            if (it.row() == variable) it.valueRef() = 0;
      });
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    if (!energy_) return std::nullopt;
    return run(*energy_, 0, y.data(), p_.data(), TapeStack(depth_).get());
  }
  bool has_exact() const override { return !exact_.empty() && evaluation_.exact_note.empty(); }
  Eigen::VectorXd exact(double t) const override {
    if (exact_.empty()) return Model::exact(t);
    Eigen::VectorXd y = Eigen::VectorXd::Zero(size());
    for (size_t i = 0; i < exact_.size(); ++i) y[static_cast<Eigen::Index>(i)] = run(exact_[i], t, nullptr, p_.data(), TapeStack(depth_).get());
    return y;
  }
  const void* capability(const std::type_info& type) const override {
    if (const void* part = offer(type, as_part<DenseJacobian>(*this), as_part<SparseJacobian>(*this), as_part<EventSource>(*this))) return part;
    // a resting flag is held by rhs(): the inline f and the (x, v) layout would pass it by
    if (!flag_names_.empty()) return nullptr;
    if (second_order_.positions > 0 && inline_rhs_) return offer(type, second_order_, *inline_rhs_);
    if (second_order_.positions > 0) return offer(type, second_order_);
    return inline_rhs_ ? offer(type, *inline_rhs_) : nullptr;
  }
  EquationsEvaluation evaluation() const {
    std::lock_guard lock(evaluation_mutex_);
    return evaluation_;
  }

 private:
  void jacobian_values(double t, const double* y, double* values) const {
    const JacobianTapes& J = jacobian_tapes();
    if (const NativeFn native = native_jacobian_.load(std::memory_order_acquire)) return native(t, y, J.p.data(), values);
    TapeStack tape_stack(J.depth);
    double* stack = tape_stack.get();
    for (size_t k = 0; k < J.tapes.size(); ++k) values[k] = run(J.tapes[k], t, y, J.p.data(), stack);
  }
  // the Jacobian, made on first use: by the constructor for a small system; for a large one by the background
  // compile or the first method that asks, whichever comes first (the other waits)
  const JacobianTapes& jacobian_tapes(bool ginac_held = false) const {
    std::call_once(jacobian_once_, [&] { make_jacobian(ginac_held); });
    return *jacobian_;
  }
  void make_jacobian(bool ginac_held) const;

  // the scene's events: g, its rate along the solution, the action's formulas, the rest rule's two sides
  struct EventTapes {
    Tape g, rate;
    std::vector<std::pair<int, Tape>> action;  // the variable set, and its formula
    std::optional<std::pair<Tape, Tape>> rest; // left, right
    std::string comparison;                    // "<", "<=", ">", ">="
    int flag = -1;                             // where its resting flag is in the state, or -1 (no rest rule)
  };
  void make_events(const EquationsSpec& spec);
  std::string fire(const EventTapes& e, double t, Eigen::VectorXd& y) const;
  // calls held(variable) for each variable an event's rest rule holds at 0 in the state y
  template <class Held>
  void hold(const Eigen::Ref<const Eigen::VectorXd>& y, Held&& held) const {
    for (const EventTapes& e : event_tapes_)
      if (e.flag >= 0 && y[e.flag] != 0)
        for (const auto& [variable, tape] : e.action) held(variable);
    for (size_t k = 0; k < flag_names_.size(); ++k) held(static_cast<int>(names_.size() + k));
  }

  // build's steps, in order
  void build(const EquationsSpec& spec, const Params& values, const EquationsOptions& options);
  void make_symbols(const EquationsSpec& spec, const Params& parameters, const Params& initial);
  std::vector<const Formula*> make_tapes(const EquationsSpec& spec);
  void find_second_order();
  void check_start(const EquationsSpec& spec, const std::vector<const Formula*>& formula_of);
  void start_native(const EquationsOptions& options);
  bool adopt(std::shared_ptr<const NativeCode> code);
  NativeSource native_source(const EquationsOptions& options);

  std::vector<std::string> names_;
  std::vector<std::string> flag_names_;  // "NAME.resting", one for each event with a rest rule
  std::vector<EventTapes> event_tapes_;
  std::vector<Event> events_;
  Eigen::VectorXd y0_;
  std::vector<double> p_;
  std::vector<Tape> rhs_, exact_;
  std::optional<Tape> energy_;
  int depth_ = 1;
  // made once (jacobian_tapes()); work_ from build until then
  mutable std::unique_ptr<JacobianWork> work_;
  mutable std::unique_ptr<const JacobianTapes> jacobian_;
  mutable std::once_flag jacobian_once_;
  bool autonomous_ = true;
  SecondOrderView second_order_;
  std::shared_ptr<const NativeCode> native_;
  std::atomic<NativeFn> native_rhs_{nullptr}, native_jacobian_{nullptr};  // null: the interpreter
  std::optional<InlineRhs> inline_rhs_;  // the compiled f for the steppers that call it inline (sizes 2-4)
  mutable std::mutex evaluation_mutex_;  // the background compile writes evaluation_ and native_
  EquationsEvaluation evaluation_;
  std::atomic<bool> cancel_{false};
  std::thread background_;               // the compile of a large system, while the interpreter runs
};

// the symbols of the variables and parameters, the parameters' values, the state's names and initial values
void Equations::make_symbols(const EquationsSpec& spec, const Params& parameters, const Params& initial) {
  const size_t n = spec.variables.size();
  work_ = std::make_unique<JacobianWork>();
  Symbols& s = work_->symbols;
  for (const auto& v : spec.variables) {
    s.index[v] = {true, static_cast<int>(s.variables.size())};
    s.variables.push_back(symbol_named(v));
    s.variable_names.push_back(v);
  }
  for (const auto& [name, value] : parameters) {
    s.index[name] = {false, static_cast<int>(s.parameters.size())};
    s.parameters.push_back(symbol_named(name));
    s.parameter_names.push_back(name);
    p_.push_back(value);
  }
  s.defined = fmt::format("variables {}{}", fmt::join(s.variable_names, ", "),
                          s.parameter_names.empty() ? std::string() : fmt::format("; parameters {}", fmt::join(s.parameter_names, ", ")));
  names_ = spec.variables;
  y0_.resize(static_cast<Eigen::Index>(n));
  for (size_t i = 0; i < n; ++i) y0_[static_cast<Eigen::Index>(i)] = initial.at(spec.variables[i]);

}

// the formulas parsed, and their tapes: f's, [exact]'s and the energy's, with the derived slots' values
std::vector<const Formula*> Equations::make_tapes(const EquationsSpec& spec) {
  const size_t n = spec.variables.size();
  Symbols& s = work_->symbols;
  std::vector<GiNaC::ex>& f = work_->f;
  f.resize(n);
  std::vector<const Formula*> formula_of(n);
  work_->where.resize(n);
  for (const auto& formula : spec.equations) {
    const size_t i = static_cast<size_t>(std::find(names_.begin(), names_.end(), formula.name) - names_.begin());
    f[i] = parse(formula, s, true, true);
    formula_of[i] = &formula;
    work_->where[i] = formula.where();
  }
  autonomous_ = std::none_of(f.begin(), f.end(), [&](const GiNaC::ex& e) { return e.has(s.t); });
  Derived& derived = work_->derived;
  derived.first_slot = static_cast<int>(p_.size());
  for (size_t i = 0; i < n; ++i) rhs_.push_back(build_tape(s, derived, formula_of[i]->where(), formula_of[i], f[i]));
  exact_.resize(spec.exact.size());  // one per variable (checked above), in the variables' order
  for (const auto& formula : spec.exact) {
    const size_t i = static_cast<size_t>(std::find(names_.begin(), names_.end(), formula.name) - names_.begin());
    exact_[i] = build_tape(s, derived, formula.where(), &formula, parse(formula, s, false, true));
  }
  if (spec.energy) energy_ = build_tape(s, derived, spec.energy->where(), &*spec.energy, parse(*spec.energy, s, true, false));
  make_events(spec);
  // the derived slots, from the parameters (each reads parameters and numbers only)
  for (const Tape& t : derived.tapes) depth_ = std::max(depth_, t.depth);
  for (const Tape& t : derived.tapes) p_.push_back(run(t, 0, nullptr, p_.data(), TapeStack(depth_).get()));
  for (const auto* tapes : {&rhs_, &exact_})
    for (const Tape& t : *tapes) depth_ = std::max(depth_, t.depth);
  if (energy_) depth_ = std::max(depth_, energy_->depth);
  for (const EventTapes& e : event_tapes_) {
    depth_ = std::max({depth_, e.g.depth, e.rate.depth});
    for (const auto& [variable, tape] : e.action) depth_ = std::max(depth_, tape.depth);
    if (e.rest) depth_ = std::max({depth_, e.rest->first.depth, e.rest->second.depth});
  }

  return formula_of;
}

// the rest rule's comparison: where it splits the text, and which it is ("abs(v) < 1e-3": at 7, "<")
std::pair<size_t, std::string> comparison_in(const Formula& f) {
  for (size_t i = 0; i < f.text.size(); ++i)
    if (f.text[i] == '<' || f.text[i] == '>') return {i, f.text.substr(i, i + 1 < f.text.size() && f.text[i + 1] == '=' ? 2 : 1)};
  throw BadEquations(fmt::format("{}: a rest rule compares two formulas (\"abs(v) < 1e-3\"; <, <=, > or >=)", f.where()));
}

// the events' tapes (before the derived slots are valued: their parameter parts join them), their resting flags
// and the Events the integrators see
void Equations::make_events(const EquationsSpec& spec) {
  Symbols& s = work_->symbols;
  Derived& derived = work_->derived;
  const auto variable_of = [&](const Formula& f) {
    const auto it = std::find(names_.begin(), names_.end(), f.name);
    if (it == names_.end())
      throw BadEquations(fmt::format("{}: '{}' is not a variable, so an action cannot set it (variables: {})", f.where(), f.name, fmt::join(names_, ", ")));
    return static_cast<int>(it - names_.begin());
  };
  const auto tape = [&](const Formula& f) { return build_tape(s, derived, f.where(), &f, parse(f, s, true, true)); };
  std::set<std::string, std::less<>> seen;
  for (const EventSpec& spec_event : spec.events) {
    if (!identifier(spec_event.name))
      throw BadEquations(fmt::format("{}: '{}' is not an event's name (a letter, then letters, digits or _)", spec_event.where, spec_event.name));
    EventTapes e;
    const GiNaC::ex g = parse(spec_event.when, s, true, true);
    e.g = build_tape(s, derived, spec_event.when.where(), &spec_event.when, g);
    // dg/dt along the solution: its partial in t, and in each variable times that variable's equation
    GiNaC::ex rate = g.diff(s.t);
    for (size_t i = 0; i < names_.size(); ++i) rate += g.diff(s.variables[i]) * work_->f[i];
    e.rate = build_tape(s, derived, spec_event.when.where() + " (its rate along the solution)", nullptr, rate);
    for (const Formula& f : spec_event.action) e.action.emplace_back(variable_of(f), tape(f));
    if (spec_event.rest) {
      const Formula& rule = *spec_event.rest;
      if (spec_event.action.empty())
        throw BadEquations(fmt::format("{}: a rest rule needs an action (the variables it holds at 0 when the event comes to rest)", rule.where()));
      const auto [at, comparison] = comparison_in(rule);
      Formula left = rule, right = rule;
      left.text = rule.text.substr(0, at);
      right.text = rule.text.substr(at + comparison.size());
      if (right.column > 0) right.column += static_cast<int>(at + comparison.size());
      e.rest = std::pair{tape(left), tape(right)};
      e.comparison = comparison;
      e.flag = static_cast<int>(names_.size() + flag_names_.size());
      flag_names_.push_back(spec_event.name + ".resting");
    }
    event_tapes_.push_back(std::move(e));
    Event event{.name = spec_event.name, .direction = spec_event.direction};
    event.surface = false;
    event.terminal = spec_event.terminal;
    event.keeps_state = true;
    event.may_rest = spec_event.rest.has_value();
    events_.push_back(std::move(event));
  }
  // the Events read the tapes by index, once the vector no longer moves
  for (size_t k = 0; k < events_.size(); ++k) {
    events_[k].g = [this, k](double t, const Eigen::VectorXd& y) {
      const EventTapes& e = event_tapes_[k];
      if (e.flag >= 0 && y[e.flag] != 0) return 1.0;  // disarmed: at rest
      return run(e.g, t, y.data(), p_.data(), TapeStack(depth_).get());
    };
    events_[k].rate = [this, k](double t, const Eigen::VectorXd& y) {
      const EventTapes& e = event_tapes_[k];
      if (e.flag >= 0 && y[e.flag] != 0) return 0.0;
      return run(e.rate, t, y.data(), p_.data(), TapeStack(depth_).get());
    };
    events_[k].apply = [this, k](double t, Eigen::VectorXd& y) { return fire(event_tapes_[k], t, y); };
  }
  y0_.conservativeResize(static_cast<Eigen::Index>(names_.size() + flag_names_.size()));
  y0_.tail(static_cast<Eigen::Index>(flag_names_.size())).setZero();
}

// an event's handler: its rest rule tested and its action's formulas all evaluated on the state at the event,
// then written
std::string Equations::fire(const EventTapes& e, double t, Eigen::VectorXd& y) const {
  TapeStack tape_stack(depth_);
  double* stack = tape_stack.get();
  if (e.rest) {
    const double left = run(e.rest->first, t, y.data(), p_.data(), stack), right = run(e.rest->second, t, y.data(), p_.data(), stack);
    const bool rests = e.comparison == "<" ? left < right : e.comparison == "<=" ? left <= right : e.comparison == ">" ? left > right : left >= right;
    if (rests) {
      for (const auto& [variable, tape] : e.action) y[variable] = 0;
      y[e.flag] = 1;
      return "rest";
    }
  }
  boost::container::small_vector<double, 4> values;
  for (const auto& [variable, tape] : e.action) values.push_back(run(tape, t, y.data(), p_.data(), stack));
  for (size_t i = 0; i < values.size(); ++i) y[e.action[i].first] = values[i];
  return "crossing";
}

// x' = v: the first half of the variables' equations are the second half's names
void Equations::find_second_order() {
  const size_t n = names_.size();
  const auto& f = work_->f;
  const auto& s = work_->symbols;
  if (n % 2 == 0 && flag_names_.empty()) {  // a resting flag is held by rhs(), which the (x, v) layout's steppers pass by
    const size_t half = n / 2;
    bool pairs = true;
    for (size_t i = 0; i < half && pairs; ++i) pairs = f[i].is_equal(s.variables[half + i]);
    if (pairs) second_order_.positions = static_cast<int>(half);
  }
  evaluation_.second_order = second_order_.positions;

}

// finite at the start (each formula named), before anything is compiled; [exact] noted where it is not the
// initial state's
void Equations::check_start(const EquationsSpec& spec, const std::vector<const Formula*>& formula_of) {
  const size_t n = names_.size();
  {
    TapeStack tape_stack(depth_);
    double* stack = tape_stack.get();
    for (size_t i = 0; i < n; ++i)
      if (const double v = run(rhs_[i], 0, y0_.data(), p_.data(), stack); !std::isfinite(v))
        throw BadEquations(fmt::format("{}: the formula is {} at the initial state (t = 0, {})", formula_of[i]->where(), v, [&] {
          std::string state;
          for (size_t k = 0; k < n; ++k) state += fmt::format("{}{} = {:g}", k ? ", " : "", names_[k], y0_[static_cast<Eigen::Index>(k)]);
          return state;
        }()));
    if (energy_)
      if (const double e = run(*energy_, 0, y0_.data(), p_.data(), stack); !std::isfinite(e))
        throw BadEquations(fmt::format("{}: the formula is {} at the initial state", spec.energy->where(), e));
    // an event whose g is not finite at the start could never be seen to cross
    for (size_t k = 0; k < event_tapes_.size(); ++k)
      if (const double g = run(event_tapes_[k].g, 0, y0_.data(), p_.data(), stack); !std::isfinite(g))
        throw BadEquations(fmt::format("{}: event '{}' is not finite at the initial state ({}): it could never be seen to cross zero",
                                       spec.events[k].when.where(), spec.events[k].name, g));
  }
  if (!exact_.empty()) {
    const Eigen::VectorXd at0 = exact(0);
    const double mismatch = (at0 - y0_).cwiseAbs().maxCoeff();
    if (!(mismatch <= 1e-9 * std::max(1.0, y0_.cwiseAbs().maxCoeff())))
      evaluation_.exact_note = fmt::format("[exact] at t = 0 is {:.3g} from the initial state (the initial values or parameters differ from those it "
                                           "solves): errors are not measured against it", mismatch);
  }

}

// the Jacobian and the compiled code, now or (a large system) in the background
void Equations::start_native(const EquationsOptions& options) {
  // Their size told before either is made: f's instructions and the
  // nodes of the derivatives (about one instruction a node), at about 20 bytes of C an instruction (measured)
  size_t instructions = 0;
  for (const Tape& t : rhs_) instructions += t.code.size();
  for (const auto& e : work_->f) instructions += work_->differentiate.derivative_nodes(e);
  const bool large = instructions * 20 > options.background_above;
  if (!large || !options.compile) jacobian_tapes(true);  // small, or no compile to make it in the background
  if (!options.compile) {
    evaluation_.detail = "the interpreter was asked for";
    return;
  }
  if (!large) {
    const NativeSource source = native_source(options);
    std::string why;
    const auto code = load_native(source, CompileLimits{options.compile_seconds, nullptr}, why);
    if (!adopt(code)) evaluation_.detail = why.empty() ? "the compiled object lacks its functions" : why;
    return;
  }
  // large: the interpreter runs while the C is printed and compiled, and f switches to the compiled code when it
  // is loaded (the same bits: the same operations in the same order)
  evaluation_.background = true;
  evaluation_.detail = fmt::format("the interpreter, while f and its Jacobian (about {} operations) are made and compiled in the background", instructions);
  background_ = std::thread([this, options] {
    const auto start = std::chrono::steady_clock::now();
    try {
      jacobian_tapes();
    } catch (const Cancelled&) {
      return;
    }
    const NativeSource source = native_source(options);
    std::string why;
    auto code = cached_native(source);
    if (!code) code = load_native(source, CompileLimits{options.compile_seconds, &cancel_}, why);
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::lock_guard lock(evaluation_mutex_);
    evaluation_.compile_seconds = took;
    evaluation_.source_bytes = source.bytes();
    evaluation_.units = static_cast<int>(source.units.size());
    if (!adopt(code))
      evaluation_.detail = fmt::format("the interpreter: the background compile of {} of C ended after {:.3g} s: {}", bytes_text(source.bytes()), took,
                                       why.empty() ? "the compiled object lacks its functions" : why);
  });
}

void Equations::build(const EquationsSpec& spec, const Params& values, const EquationsOptions& options) {
  check_shape(spec);
  const auto [parameters, initial] = resolved_values(spec, values);
  make_symbols(spec, parameters, initial);
  const std::vector<const Formula*> formula_of = make_tapes(spec);
  find_second_order();
  check_start(spec, formula_of);
  start_native(options);
}

// the exact Jacobian and its pattern, column by column, the diagonal always in it (the Newton matrix I - h J has
// it); then the formulas are let go. `ginac_held`: the caller holds ginac_mutex (the constructor); else it is taken
// a column at a time, so that a large system's Jacobian made in the background does not hold other models back
void Equations::make_jacobian(bool ginac_held) const {
  auto J = std::make_unique<JacobianTapes>();
  JacobianWork& w = *work_;
  const size_t n = names_.size();
  J->columns.push_back(0);
  for (size_t c = 0; c < n; ++c) {
    std::unique_lock lock(ginac_mutex, std::defer_lock);
    if (!ginac_held) lock.lock();
    if (cancel_.load()) throw Cancelled{};
    for (size_t r = 0; r < n; ++r) {
      const GiNaC::ex d = w.differentiate.derivative(w.f[r], static_cast<int>(c));
      if (d.is_zero() && r != c) continue;
      J->rows.push_back(static_cast<int>(r));
      J->tapes.push_back(build_tape(w.symbols, w.derived, fmt::format("{} (its derivative in {})", w.where[r], names_[c]), nullptr, d));
    }
    J->columns.push_back(static_cast<int>(J->rows.size()));
  }
  // the derived slots: f's (p_), then the Jacobian's own, each from the parameters
  J->p = p_;
  for (const Tape& t : J->tapes) J->depth = std::max(J->depth, t.depth);
  for (size_t k = J->p.size() - static_cast<size_t>(w.derived.first_slot); k < w.derived.tapes.size(); ++k) {
    J->depth = std::max(J->depth, w.derived.tapes[k].depth);
    J->p.push_back(run(w.derived.tapes[k], 0, nullptr, J->p.data(), TapeStack(J->depth).get()));
  }
  jacobian_ = std::move(J);
  std::unique_lock lock(ginac_mutex, std::defer_lock);
  if (!ginac_held) lock.lock();
  work_.reset();
}

// f and its Jacobian as C in units, at the optimisation level for its size; its size noted in the evaluation
// (by the constructor, or by the background compile under evaluation_mutex_)
NativeSource Equations::native_source(const EquationsOptions& options) {
  NativeSource source = c_source(rhs_, jacobian_tapes().tapes, options.function_bytes, options.unit_bytes);
  if (source.bytes() > options.optimise_none_above) source.optimisation = "-O0";
  else if (source.bytes() > options.optimise_below) source.optimisation = "-O1";
  if (!evaluation_.background) {
    evaluation_.source_bytes = source.bytes();
    evaluation_.units = static_cast<int>(source.units.size());
  }
  return source;
}

// the compiled object's functions in use from now on (they compute what the interpreter does); false if it has
// none (null, or without them). Called by the constructor, or by the background compile under evaluation_mutex_
bool Equations::adopt(std::shared_ptr<const NativeCode> code) {
  if (!code) return false;
  const auto rhs = reinterpret_cast<NativeFn>(code->symbol("stepwise_rhs"));
  const auto jacobian = reinterpret_cast<NativeFn>(code->symbol("stepwise_jacobian"));
  if (!rhs || !jacobian) return false;
  native_ = std::move(code);
  native_jacobian_.store(jacobian, std::memory_order_release);
  native_rhs_.store(rhs, std::memory_order_release);
  evaluation_.compiled = true;
  evaluation_.from_cache = !native_->compiled();
  evaluation_.detail = evaluation_.background
                           ? fmt::format("{} (compiled in the background in {:.3g} s; the interpreter ran until then)", native_->path(), evaluation_.compile_seconds)
                           : native_->path();
  // the inline path only from the constructor: a capability is not to change under a running stepper
  if (void* values = native_->symbol("stepwise_rhs_values"); values && !evaluation_.background) {
    const auto n = size();
    if (n == 2) inline_rhs_ = InlineRhs{NativeRhs<2>{reinterpret_cast<NativeValuesFn<2>::type>(values), p_.data()}};
    else if (n == 3) inline_rhs_ = InlineRhs{NativeRhs<3>{reinterpret_cast<NativeValuesFn<3>::type>(values), p_.data()}};
    else if (n == 4) inline_rhs_ = InlineRhs{NativeRhs<4>{reinterpret_cast<NativeValuesFn<4>::type>(values), p_.data()}};
  }
  return true;
}

}  // namespace

std::string Formula::where(int column_in_text) const {
  if (column_in_text > 0 && line > 0 && column > 0) return fmt::format("{}:{}:{}: {}", file, line, column + column_in_text - 1, key);
  if (column_in_text > 0) return fmt::format("{}: {}, column {}", file, key, column_in_text);
  return line > 0 ? fmt::format("{}:{}: {}", file, line, key) : fmt::format("{}: {}", file, key);
}

std::unique_ptr<Model> make_equations(const EquationsSpec& spec, const Params& values, const EquationsOptions& options) {
  return std::make_unique<Equations>(spec, values, options);
}

std::unique_ptr<Model> make_equations(const EquationsSpec& spec, const Params& values, bool compile) {
  EquationsOptions options;
  options.compile = compile;
  return make_equations(spec, values, options);
}

std::vector<std::string> equations_keys(const EquationsSpec& spec) {
  std::vector<std::string> keys;
  for (const auto& [name, value] : spec.parameters) keys.push_back(name);
  for (const auto& v : spec.variables) keys.push_back(v);
  return keys;
}

std::optional<EquationsEvaluation> equations_evaluation(const Model& model) {
  if (const auto* e = dynamic_cast<const Equations*>(&model)) return e->evaluation();
  return std::nullopt;
}

}  // namespace stepwise
