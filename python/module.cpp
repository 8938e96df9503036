// The Python module's compiled half (`stepwise._stepwise`): the public surface (<stepwise/stepwise.hpp>) made
// callable from Python. python/stepwise/__init__.py gives it SciPy's shapes (solve_ivp's signature and result);
// what is here runs the solves: a Python `fun` as an OdeSystem, a system of equations compiled once, a scene
// file run as `stepwise run` runs it, the advice and the studies on a scene.
//
// Errors: bad input (a scene's, a method's, a formula's) raises ValueError with the command line's one-line
// message; an exception raised by `fun` propagates from inside the solve (every backend's resources are freed
// as it unwinds) with a note saying at which t; Ctrl-C raises KeyboardInterrupt at the next call of f or output.
// The GIL is released while a compiled system (equations, a scene's model) runs, and taken back to look for a
// signal every few thousand calls of f and at every output.
#include "stepwise/stepwise.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

namespace py = pybind11;

namespace stepwise {
namespace {

// a signal's Python handler has run (Ctrl-C: KeyboardInterrupt is set): raise it here, from inside the solve
void raise_if_signalled() {
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
}

// the same from a thread that released the GIL
void raise_if_signalled_released() {
  py::gil_scoped_acquire gil;
  raise_if_signalled();
}

// the same, at most once every 10 ms (the clock read is ~20 ns, taking the GIL back ~1 us): for the outputs of a
// compiled solve, which may come every few steps
class SignalCheck {
 public:
  void operator()() {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(10)) return;
    last_ = now;
    raise_if_signalled_released();
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// a Python callable f(t, y) -> dy/dt (and jac(t, y) -> df/dy, or a constant matrix) as an OdeSystem, in s = sign t
// (sign -1: a reversed t_span integrated forwards in s = -t, as every method steps forwards)
class PythonSystem final : public OdeSystem, public DenseJacobian {
 public:
  PythonSystem(py::object fun, py::object jac, int n, double sign) : fun_(std::move(fun)), jac_(std::move(jac)), n_(n), sign_(sign) {}

  int size() const override { return n_; }

  void rhs(double s, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    const double t = sign_ * s;
    raise_if_signalled();
    const auto out = call(fun_, t, y, "fun");
    if (out.ndim() != 1 || out.shape(0) != n_)
      throw py::value_error(fmt::format("fun returned an array of shape {} at t = {}; y0 has {} values, so it must return shape ({},)", shape(out), t, n_, n_));
    const double* v = out.data();
    for (int i = 0; i < n_; ++i) {
      if (!std::isfinite(v[i])) throw py::value_error(fmt::format("fun returned a value that is not finite ({}) in component {} at t = {}", v[i], i, t));
      dydt[i] = sign_ * v[i];
    }
  }

  // its Jacobian where `jac` was given
  const void* capability(const std::type_info& type) const override {
    return type == typeid(DenseJacobian) && !jac_.is_none() ? &as_part<DenseJacobian>(*this) : nullptr;
  }
  void jacobian(double s, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::MatrixXd> dfdy) const override {
    const double t = sign_ * s;
    const auto out = PyCallable_Check(jac_.ptr()) ? call(jac_, t, y, "jac") : as_array(jac_, t, "jac");
    if (out.ndim() != 2 || out.shape(0) != n_ || out.shape(1) != n_)
      throw py::value_error(fmt::format("jac gave an array of shape {} at t = {}; it must be ({}, {})", shape(out), t, n_, n_));
    for (int i = 0; i < n_; ++i)
      for (int j = 0; j < n_; ++j) {
        const double v = out.at(i, j);
        if (!std::isfinite(v)) throw py::value_error(fmt::format("jac gave a value that is not finite ({}) at ({}, {}), t = {}", v, i, j, t));
        dfdy(i, j) = sign_ * v;
      }
  }

 private:
  using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

  static std::string shape(const Array& a) {
    std::string text = "(";
    for (py::ssize_t k = 0; k < a.ndim(); ++k) text += fmt::format("{}{}", k ? ", " : "", a.shape(k));
    return text + (a.ndim() == 1 ? ",)" : ")");
  }

  static Array as_array(const py::object& value, double t, const char* what) {
    auto a = Array::ensure(value);
    if (!a) throw py::type_error(fmt::format("{} returned {} at t = {}, not an array of real numbers", what, std::string(py::str(py::type::of(value).attr("__name__"))), t));
    return a;
  }

  // f or jac at (t, y) on a fresh array (the callable may keep or change it); an exception it raises leaves with a
  // note saying where
  Array call(const py::object& callable, double t, const Eigen::Ref<const Eigen::VectorXd>& y, const char* what) const {
    py::array_t<double> ya(n_);
    std::copy(y.data(), y.data() + n_, ya.mutable_data());
    try {
      return as_array(callable(t, ya), t, what);
    } catch (py::error_already_set& e) {
      if (py::hasattr(e.value(), "add_note")) e.value().attr("add_note")(fmt::format("(raised by {} at t = {}, inside stepwise.solve_ivp)", what, t));
      throw;
    }
  }

  py::object fun_, jac_;
  int n_;
  double sign_;
};

// a compiled system (a user's equations, a scene's model) run with the GIL released: in s = sign t, and
// looking for a signal every `check_every` calls of f. Capabilities pass through forwards in time only (x' = v
// read backwards is no longer x' = v)
class ReleasedSystem final : public OdeSystem, public DenseJacobian, public SparseJacobian, public EventSource {
 public:
  ReleasedSystem(const OdeSystem& inner, double sign)
      : inner_(inner), sign_(sign), dense_(inner.as<DenseJacobian>()), sparse_(inner.as<SparseJacobian>()) {}
  static constexpr long check_every = 4096;

  int size() const override { return inner_.size(); }
  bool autonomous() const override { return inner_.autonomous(); }
  void rhs(double s, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    if (++calls_ % check_every == 0) raise_if_signalled_released();
    inner_.rhs(sign_ * s, y, dydt);
    if (sign_ < 0) dydt = -dydt;
  }
  void jacobian(double s, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::MatrixXd> dfdy) const override {
    dense_->jacobian(sign_ * s, y, dfdy);
    if (sign_ < 0) dfdy = -dfdy;
  }
  void sparse_jacobian(double s, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& dfdy) const override {
    sparse_->sparse_jacobian(sign_ * s, y, dfdy);
    if (sign_ < 0) dfdy = -dfdy;
  }
  std::span<const Event> events() const override { return events_of(inner_); }
  // the Jacobians in s, the events as the system has them; the other capabilities only forwards (in s, a
  // second-order layout read backwards is no longer x' = v)
  const void* capability(const std::type_info& type) const override {
    if (type == typeid(DenseJacobian)) return dense_ ? &as_part<DenseJacobian>(*this) : nullptr;
    if (type == typeid(SparseJacobian)) return sparse_ ? &as_part<SparseJacobian>(*this) : nullptr;
    if (type == typeid(EventSource)) return &as_part<EventSource>(*this);
    return sign_ > 0 ? inner_.capability(type) : nullptr;
  }

 private:
  const OdeSystem& inner_;
  double sign_;
  const DenseJacobian* dense_;
  const SparseJacobian* sparse_;
  mutable long calls_ = 0;
};

// SciPy's events: callables g(t, y) with optional `terminal` and `direction` attributes, watched beside the
// system's own (an Equations' [events]): each a sign-change event that keeps its state, read in s = sign t (so a
// rising event in t is a falling one in s when integrating backwards)
class EventfulSystem final : public OdeSystem, public EventSource {
 public:
  EventfulSystem(const OdeSystem& inner, const py::list& events, double sign, bool released) : inner_(inner), own_events_(events_of(inner)) {
    // forwards in time with no events of Python's: the system's own, as they are (no copy; a solve of a few
    // microseconds would spend one on copying them)
    if (sign > 0 && events.empty()) return;
    for (const Event& e : own_events_) {
      Event mapped = e;
      mapped.g = [g = e.g, sign](double s, const Eigen::VectorXd& y) { return g(sign * s, y); };
      if (e.rate) mapped.rate = [rate = e.rate, sign](double s, const Eigen::VectorXd& y) { return sign * rate(sign * s, y); };
      mapped.apply = [apply = e.apply, sign](double s, Eigen::VectorXd& y) { return apply(sign * s, y); };
      mapped.direction = static_cast<int>(sign) * e.direction;
      events_.push_back(std::move(mapped));
    }
    const int n = inner.size();
    for (size_t k = 0; k < events.size(); ++k) {
      py::object g = events[k];
      if (!PyCallable_Check(g.ptr())) throw py::type_error(fmt::format("events[{}] must be a callable g(t, y)", k));
      Event e;
      e.name = fmt::format("events[{}]", k);
      e.surface = false;
      e.keeps_state = true;
      e.terminal = py::hasattr(g, "terminal") && py::cast<bool>(py::bool_(g.attr("terminal")));
      const double direction = py::hasattr(g, "direction") ? py::cast<double>(g.attr("direction")) : 0.0;
      e.direction = static_cast<int>(sign) * (direction > 0 ? 1 : direction < 0 ? -1 : 0);
      e.g = [g, n, sign, released, k](double s, const Eigen::VectorXd& y) {
        std::optional<py::gil_scoped_acquire> gil;
        if (released) gil.emplace();
        py::array_t<double> ya(n);
        std::copy(y.data(), y.data() + n, ya.mutable_data());
        const double t = sign * s;
        try {
          const double v = py::cast<double>(g(t, ya));
          if (!std::isfinite(v)) throw py::value_error(fmt::format("events[{}] returned a value that is not finite ({}) at t = {}", k, v, t));
          return v;
        } catch (py::error_already_set& e) {
          if (py::hasattr(e.value(), "add_note")) e.value().attr("add_note")(fmt::format("(raised by events[{}] at t = {}, inside stepwise.solve_ivp)", k, t));
          throw;
        }
      };
      e.apply = [](double, Eigen::VectorXd&) { return std::string("crossing"); };
      events_.push_back(std::move(e));
    }
  }
  // which of the events are the system's own (they come first)
  size_t own() const { return own_events_.size(); }

  int size() const override { return inner_.size(); }
  bool autonomous() const override { return inner_.autonomous(); }
  void rhs(double s, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override { inner_.rhs(s, y, dydt); }
  std::span<const Event> events() const override { return events_.empty() ? own_events_ : std::span<const Event>(events_); }
  // its events in place of the system's; the system's other capabilities (its Jacobians) as they are
  const void* capability(const std::type_info& type) const override {
    return type == typeid(EventSource) ? &as_part<EventSource>(*this) : inner_.capability(type);
  }

 private:
  const OdeSystem& inner_;
  std::span<const Event> own_events_;  // the system's own
  std::vector<Event> events_;          // its own mapped to s and Python's, or empty: its own as they are
};

// a system of equations written as text (models/equations.hpp), parsed, differentiated and compiled once when
// made; solve_ivp then runs it with no Python in the loop
class Equations {
 public:
  Equations(EquationsSpec spec, const Params& values, bool compile) : spec_(std::move(spec)), model_(make_equations(spec_, values, compile)) {}
  const Model& model() const { return *model_; }
  const EquationsSpec& spec() const { return spec_; }

 private:
  EquationsSpec spec_;
  std::unique_ptr<Model> model_;
};

Formula formula(const std::string& name, const std::string& text, const std::string& section) {
  Formula f;
  f.name = name;
  f.text = text;
  f.file = "stepwise.Equations";
  f.key = section + "." + name;
  return f;
}

// Equations(equations={"x": "v", "v": "-g*sin(x)"}, parameters={"g": 9.81}, ...): the variables in the order
// the equations are given
// a Python value of an event's table as TOML: a formula's text, a direction's word, terminal's boolean, or an
// action's table of formulas
std::string toml_value(const py::handle& value, const std::string& key) {
  if (py::isinstance<py::bool_>(value)) return py::cast<bool>(value) ? "true" : "false";
  if (py::isinstance<py::str>(value)) {
    std::string out = "\"";
    for (const char c : py::cast<std::string>(value)) {
      if (c == '"' || c == '\\') out += '\\';
      if (static_cast<unsigned char>(c) < 0x20) out += fmt::format("\\u{:04x}", static_cast<int>(c));
      else out += c;
    }
    return out + "\"";
  }
  if (py::isinstance<py::dict>(value)) {
    std::string out = "{ ";
    for (const auto& [k, v] : py::cast<py::dict>(value)) out += fmt::format("{}{} = {}", out.size() > 2 ? ", " : "", toml_value(k, key), toml_value(v, key));
    return out + " }";
  }
  throw py::type_error(fmt::format("stepwise.Equations: {}: expected a formula, a word, true/false or a dict of formulas", key));
}

Equations make_python_equations(const py::dict& equations, const std::map<std::string, double>& parameters, const std::optional<std::map<std::string, double>>& initial,
                                const std::optional<std::string>& energy, const std::optional<std::map<std::string, std::string>>& exact,
                                const std::optional<py::dict>& events, bool compile) {
  EquationsSpec spec;
  spec.file = "stepwise.Equations";
  spec.variables_where = "stepwise.Equations: equations";
  for (const auto& [key, value] : equations) {
    const auto name = py::cast<std::string>(key);
    spec.variables.push_back(name);
    spec.equations.push_back(formula(name, py::cast<std::string>(value), "equations"));
    spec.initial[name] = 0.0;
  }
  if (initial)
    for (const auto& [name, value] : *initial) {
      if (!spec.initial.contains(name)) throw py::value_error(fmt::format("stepwise.Equations: initial.{}: not one of the variables", name));
      spec.initial[name] = value;
    }
  for (const auto& [name, value] : parameters) spec.parameters[name] = value;
  if (energy) spec.energy = formula("energy", *energy, "energy");
  if (exact)
    for (const auto& [name, text] : *exact) spec.exact.push_back(formula(name, text, "exact"));
  // the events as the scene file's [events.NAME] tables, read by the scene's reader
  if (events) {
    std::string toml;
    for (const auto& [name, table] : *events) {
      if (!py::isinstance<py::dict>(table)) throw py::type_error(fmt::format("stepwise.Equations: events.{}: expected a dict (when, direction, action, terminal, rest)", std::string(py::str(name))));
      toml += fmt::format("[events.{}]\n", toml_value(name, "events"));
      for (const auto& [key, value] : py::cast<py::dict>(table)) {
        const std::string k = py::cast<std::string>(key);
        toml += fmt::format("{} = {}\n", toml_value(key, k), toml_value(value, "events." + k));
      }
    }
    spec.events = events_from_toml(toml, "stepwise.Equations");
  }
  return Equations(std::move(spec), {}, compile);
}

Equations equations_from_scene(const std::string& file, bool compile) {
  Scene scene = load_scene(file);
  if (!scene.equations) throw InputError(fmt::format("{}: model is \"{}\", not \"equations\"", scene.where("model"), scene.model));
  return Equations(*scene.equations, {}, compile);
}

// made empty and filled: pybind11's constructor from a pointer makes the array twice (one over the pointer, then
// its copy), 2.7 times the instructions
py::array_t<double> vector_array(const std::vector<double>& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

// samples as an (n, N) array, SciPy's layout: one row a component, one column a time; or (N, n), one row a time
py::array_t<double> columns_array(const std::vector<Eigen::VectorXd>& samples, py::ssize_t n, bool row_a_time = false) {
  const auto count = static_cast<py::ssize_t>(samples.size());
  py::array_t<double> a = row_a_time ? py::array_t<double>({count, n}) : py::array_t<double>({n, count});
  auto m = a.mutable_unchecked<2>();
  for (py::ssize_t k = 0; k < count; ++k)
    for (py::ssize_t i = 0; i < n; ++i) (row_a_time ? m(k, i) : m(i, k)) = samples[static_cast<size_t>(k)][i];
  return a;
}

// the keys of solve()'s result, made once rather than 19 strings a call (a compiled solve takes a few
// microseconds). Never destroyed: they would outlive the interpreter
struct SolveKeys {
  py::str t{"t"}, y{"y"}, status{"status"}, message{"message"}, t_stop{"t_stop"}, t_events{"t_events"}, y_events{"y_events"},
      own_events{"own_events"}, terminated{"terminated"}, stats{"stats"}, method{"method"};
  py::str steps{"steps"}, rejected{"rejected"}, rhs_evals{"rhs_evals"}, jac_evals{"jac_evals"}, linear_solves{"linear_solves"},
      factorizations{"factorizations"}, events{"events"}, projections{"projections"};
};
const SolveKeys& keys() {
  static const SolveKeys* made = new SolveKeys();
  return *made;
}

py::dict stats_dict(const Stats& s) {
  const SolveKeys& k = keys();
  py::dict d;
  d[k.steps] = s.steps;
  d[k.rejected] = s.rejected;
  d[k.rhs_evals] = s.rhs_evals;
  d[k.jac_evals] = s.jac_evals;
  d[k.linear_solves] = s.linear_solves;
  d[k.factorizations] = s.factorizations;
  d[k.events] = s.events;
  d[k.projections] = s.projections;
  return d;
}

// each event's times and the states there (of the variables), as arrays: the Python events' in their order
// (SciPy's t_events, and y_events one row an event), the system's own by name (own_events: name -> (t, y))
void put_events(py::dict& d, const EventfulSystem& system, const RunResult& r, double sign, int n) {
  const auto all = events_of(system);
  std::vector<std::vector<double>> times(all.size());
  std::vector<std::vector<Eigen::VectorXd>> states(all.size());
  for (const EventRecord& e : r.events)
    if (e.before.size() > 0 && e.event < all.size()) {
      times[e.event].push_back(sign * e.t);
      states[e.event].push_back(e.before.head(n));
    }
  py::list t_events, y_events;
  py::dict own_events;
  for (size_t k = 0; k < all.size(); ++k) {
    py::array_t<double> rows = columns_array(states[k], n, true);
    if (k < system.own()) own_events[py::str(all[k].name)] = py::make_tuple(vector_array(times[k]), rows);
    else {
      t_events.append(vector_array(times[k]));
      y_events.append(rows);
    }
  }
  d[keys().t_events] = t_events;
  d[keys().y_events] = y_events;
  d[keys().own_events] = own_events;
}

// solve_ivp's compiled half (the untimed solve(): a caller times it as it likes; the thread CPU clock's two reads
// would add ~1 us a solve): `fun` a Python callable or an Equations; t_eval, where given, sorted in the direction
// of integration and within t_span (checked here, SciPy's messages)
py::dict solve(const py::object& fun, double t0, double t1, const py::array_t<double, py::array::c_style | py::array::forcecast>& y0_array, const std::string& method_name, double rtol, double atol,
               std::optional<double> dt, double max_step, const std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>>& t_eval, const py::object& jac, std::optional<double> max_steps,
               const py::list& events, bool record_steps) {
  const Method* method = find_method(method_name);
  if (!method) throw BadMethod(fmt::format("unknown method \"{}\" (stepwise.methods() lists them)", method_name));
  if (!std::isfinite(t0) || !std::isfinite(t1)) throw py::value_error(fmt::format("t_span must be finite, not ({}, {})", t0, t1));
  if (t0 == t1) throw py::value_error(fmt::format("t_span has zero length ({}, {}): nothing to integrate", t0, t1));
  const double sign = t1 > t0 ? 1.0 : -1.0;
  if (y0_array.ndim() != 1) throw py::value_error("`y0` must be 1-dimensional.");
  const Eigen::VectorXd y0 = Eigen::Map<const Eigen::VectorXd>(y0_array.data(), y0_array.shape(0));
  const int n = static_cast<int>(y0.size());
  if (n == 0) throw py::value_error("y0 is empty");
  if (!y0.allFinite()) throw py::value_error("y0 has a value that is not finite");

  const Equations* equations = py::isinstance<Equations>(fun) ? &py::cast<const Equations&>(fun) : nullptr;
  if (!equations && !PyCallable_Check(fun.ptr())) throw py::type_error("fun must be a callable f(t, y) or a stepwise.Equations");
  if (equations && !jac.is_none()) throw py::value_error("jac: an Equations system has its exact Jacobian already");
  if (equations && equations->spec().variables.size() != static_cast<size_t>(n))
    throw py::value_error(fmt::format("y0 has {} values; the equations have {} variables ({})", n, equations->spec().variables.size(), fmt::join(equations->spec().variables, ", ")));
  std::unique_ptr<OdeSystem> inner;
  if (equations) inner = std::make_unique<ReleasedSystem>(equations->model(), sign);
  else inner = std::make_unique<PythonSystem>(fun, jac, n, sign);
  const auto system = std::make_unique<EventfulSystem>(*inner, events, sign, equations != nullptr);
  // an Equations' state goes on past its variables with a flag for each event with a rest rule (0 at the start)
  Eigen::VectorXd state0 = Eigen::VectorXd::Zero(system->size());
  state0.head(n) = y0;
  if (!method_applies(*method, *system)) throw BadMethod(fmt::format("{}: {}", method->name, method_requirement(*method, *system)));

  StepControl control;
  if (dt) {
    control = StepControl::fixed(*dt);
  } else {
    if (!method->adaptive()) throw BadMethod(fmt::format("{} steps with a fixed step: pass dt=", method->name));
    control = StepControl::adaptive(rtol, atol);
    control.max_step = max_step;
  }
  if (max_steps) {  // else StepControl's own cap
    if (!(*max_steps >= 1)) throw py::value_error(fmt::format("max_steps must be at least 1, not {}", *max_steps));
    control.max_steps = static_cast<long>(std::min(*max_steps, 1e15));
  }
  check_step_control(*method, control);
  if (dt && std::abs(t1 - t0) / *dt > static_cast<double>(control.max_steps))
    throw py::value_error(fmt::format("dt = {} takes {:.3g} steps over t_span, more than max_steps = {}", *dt, std::abs(t1 - t0) / *dt, control.max_steps));
  if (const double bytes = dense_matrix_bytes(*method, *system); over_memory_budget(bytes))
    throw BadMethod(fmt::format("{} keeps dense {}x{} matrices ({:.3g} GB): {}", method->name, n, n, bytes / 1e9, memory_budget_text()));

  // the output times in s; those at t0 itself are y0
  if (t_eval && t_eval->ndim() != 1) throw py::value_error("`t_eval` must be 1-dimensional.");
  const std::vector<double> times = t_eval ? std::vector<double>(t_eval->data(), t_eval->data() + t_eval->shape(0)) : std::vector<double>{t0, t1};
  for (const double t : times)
    if (!(std::min(t0, t1) <= t && t <= std::max(t0, t1))) throw py::value_error("Values in `t_eval` are not within `t_span`.");
  for (size_t k = 1; k < times.size(); ++k)
    if (!(sign * (times[k] - times[k - 1]) > 0)) throw py::value_error("Values in `t_eval` are not properly sorted.");
  const size_t at_start = times.empty() || times.front() != t0 ? 0 : 1;
  std::vector<double> s_out;
  for (size_t k = at_start; k < times.size(); ++k) s_out.push_back(sign * times[k]);

  // the samples as they come (a Python fun's solve holds the GIL; a compiled system's released it)
  std::vector<double> t_done;
  std::vector<Eigen::VectorXd> y_done;
  if (at_start) {
    t_done.push_back(t0);
    y_done.push_back(y0);
  }
  control.record_steps = record_steps;
  control.sink_events = false;
  control.sink = [&t_done, &y_done, sign, released = equations != nullptr, check = SignalCheck()](double s, const Eigen::VectorXd& y) mutable {
    if (released) check();
    else raise_if_signalled();
    t_done.push_back(sign * s);
    y_done.push_back(y);
    return std::string();
  };
  RunResult r;
  if (s_out.empty()) {
    r.t_stop = sign * t0;
    r.y_stop = y0;
  } else if (equations) {
    py::gil_scoped_release released;
    r = method->make(*method, control)->solve(*system, sign * t0, state0, s_out);  // (checked above: not looked up again)
  } else {
    r = method->make(*method, control)->solve(*system, sign * t0, state0, s_out);
  }
  const SolveKeys& k = keys();
  py::dict d;
  d[k.t] = vector_array(t_done);
  d[k.y] = columns_array(y_done, n);
  d[k.status] = std::string(to_string(r.status));
  d[k.message] = r.message;
  d[k.t_stop] = sign * r.t_stop;
  put_events(d, *system, r, sign, n);
  d[k.terminated] = r.terminated;
  d[k.stats] = stats_dict(r.stats);
  d[k.method] = std::string(method->name);
  return d;
}

// the scene file: a path, or a shipped scene by name ("pendulum" is scenes/pendulum.toml)
std::string scene_path(const std::string& scene) {
  if (std::filesystem::exists(scene) || scene.find('/') != std::string::npos || scene.ends_with(".toml")) return scene;
  return (std::filesystem::path(scenes_directory()) / (scene + ".toml")).string();
}

RunOptions run_options(const std::string& scene, const std::map<std::string, double>& sets) {
  RunOptions o;
  o.scene_file = scene_path(scene);
  for (const auto& [key, value] : sets) o.sets.push_back(fmt::format("{}={:.17g}", key, value));
  return o;
}

// a JSON value as Python's: objects as dicts, arrays as lists, numbers as int or float; a number that is not
// finite as None, as summary.json and advice.json write it
py::object to_python(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::object: {
      py::dict d;
      for (const auto& [key, value] : j.items()) d[py::str(key)] = to_python(value);
      return d;
    }
    case nlohmann::json::value_t::array: {
      py::list l;
      for (const auto& value : j) l.append(to_python(value));
      return l;
    }
    case nlohmann::json::value_t::string: return py::str(j.get<std::string>());
    case nlohmann::json::value_t::boolean: return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer: return py::int_(j.get<long long>());
    case nlohmann::json::value_t::number_unsigned: return py::int_(j.get<unsigned long long>());
    case nlohmann::json::value_t::number_float: {
      const double x = j.get<double>();
      return std::isfinite(x) ? py::object(py::float_(x)) : py::object(py::none());
    }
    default: return py::none();
  }
}

// a scene run as `stepwise run` runs it: the trajectory's columns and rows (trajectory.csv's numbers) and summary.json's fields
py::dict run(const std::string& scene, const std::optional<std::string>& method, std::optional<double> dt, std::optional<double> rtol, std::optional<double> atol,
             std::optional<double> t_end, std::optional<double> output_dt, const std::map<std::string, double>& sets, std::optional<double> max_steps,
             const std::map<std::string, std::string>& options) {
  RunOptions o = run_options(scene, sets);
  o.method_options.insert(options.begin(), options.end());
  o.method = method;
  o.dt = dt;
  o.rtol = rtol;
  o.atol = atol;
  o.t_end = t_end;
  o.output_dt = output_dt;
  o.max_steps = max_steps;
  PreparedRun p = prepare_run(o);
  if (over_memory_budget(p.output_bytes))
    throw InputError(fmt::format("{}: the trajectory would take {:.3g} GB in memory, {} (raise output_dt)", p.output_dt_origin, p.output_bytes / 1e9, memory_budget_text()));
  const TrajectoryRows rows(*p.model);
  std::vector<std::vector<Cell>> table;
  std::string ignored;
  table.push_back(rows.row(0.0, p.model->summary(p.model->initial_state()), ignored));
  // a PDE's fields, whole at every output time (its rows are their summary)
  const PdeGrid* grid = pde_grid(*p.model);
  std::vector<Eigen::VectorXd> states;
  if (grid) {
    states.push_back(p.model->initial_state());
    p.control.observe = [](const Eigen::VectorXd& y) { return y; };
  }
  Measured m;
  {
    py::gil_scoped_release released;
    p.control.sink = [&, check = SignalCheck()](double t, const Eigen::VectorXd& sample) mutable {
      check();
      std::string problem;
      if (grid) states.push_back(sample);
      table.push_back(rows.row(t, grid ? p.model->summary(sample) : sample, problem));
      return problem;
    };
    m = run_and_measure(*p.model, p.method, p.control, p.t_end, p.output_dt);
    if (const auto last = rows.stop_row(m, std::get<double>(table.back().front()))) table.push_back(*last);
  }
  const auto columns = static_cast<py::ssize_t>(rows.columns().size());
  py::array_t<double> values({columns, static_cast<py::ssize_t>(table.size())});
  auto v = values.mutable_unchecked<2>();
  for (size_t k = 0; k < table.size(); ++k)
    for (py::ssize_t i = 0; i < columns; ++i) v(i, static_cast<py::ssize_t>(k)) = std::get<double>(table[k][static_cast<size_t>(i)]);
  py::dict d;
  d["columns"] = rows.columns();
  d["values"] = values;
  d["summary"] = to_python(summary_json(p, m, rows.constraint_drift()));
  if (grid) {
    // each field as (time x nodes), or (time x ny x nx) in 2-D; the nodes' coordinates beside
    py::dict fields;
    const auto times = static_cast<py::ssize_t>(states.size());
    const py::ssize_t nx = grid->nx, ny = grid->ny;
    for (size_t f = 0; f < grid->fields.size(); ++f) {
      py::array_t<double> field(ny > 1 ? std::vector<py::ssize_t>{times, ny, nx} : std::vector<py::ssize_t>{times, nx});
      double* out = field.mutable_data();
      for (py::ssize_t k = 0; k < times; ++k)
        std::copy_n(states[static_cast<size_t>(k)].data() + static_cast<Eigen::Index>(f) * grid->nodes(), grid->nodes(), out + k * grid->nodes());
      fields[py::str(grid->fields[f])] = field;
    }
    d["fields"] = fields;
    d["x"] = vector_array(grid->x);
    d["y"] = vector_array(grid->y);
  }
  return d;
}

// a study's or the advice's Table as {column: numpy array (numbers) or list (text)}
py::dict table_dict(const Table& table) {
  py::dict d;
  for (size_t c = 0; c < table.columns.size(); ++c) {
    const bool numbers = std::all_of(table.rows.begin(), table.rows.end(), [c](const auto& row) { return !std::holds_alternative<std::string>(row[c]); });
    if (numbers) {
      std::vector<double> v;
      for (const auto& row : table.rows) v.push_back(std::visit([](const auto& x) -> double {
        if constexpr (std::is_same_v<std::decay_t<decltype(x)>, std::string>) return 0;
        else return static_cast<double>(x);
      }, row[c]));
      d[py::str(table.columns[c])] = vector_array(v);
    } else {
      py::list l;
      for (const auto& row : table.rows) l.append(std::holds_alternative<std::string>(row[c]) ? py::cast(std::get<std::string>(row[c])) : py::none());
      d[py::str(table.columns[c])] = l;
    }
  }
  return d;
}

py::dict advise_scene(const std::string& scene, double error, double budget, const std::map<std::string, double>& sets, int threads) {
  check_advice_request(error, budget);
  const RunOptions o = run_options(scene, sets);
  Advice a;
  std::string markdown;
  AdviceTables tables;
  {
    py::gil_scoped_release released;
    const StudyScene s = user_study_scene(o);
    a = advise(s, error, budget, threads_or_default(threads));
    markdown = advice_markdown(a, fmt::format("stepwise.advise({:?}, error={})", scene, error), "#");
    tables = advice_tables({a});
  }
  py::dict d;
  d["advice"] = to_python(advice_json(a, o.scene_file));
  d["markdown"] = markdown;
  d["sweep"] = table_dict(tables.sweep);
  return d;
}

// the studies that take a scene of the user's (`stepwise study NAME --scene FILE`)
py::dict study_scene(const std::string& name, const std::string& scene, const std::map<std::string, double>& sets, bool quick, int threads) {
  const Study* study = find_study(name);
  if (!study) throw py::value_error(fmt::format("study: unknown study '{}' (the studies: `stepwise study --list`)", name));
  const RunOptions o = run_options(scene, sets);
  StudyOutput out;
  {
    py::gil_scoped_release released;
    const std::vector<StudyScene> scenes{study_scene_of(name, o)};
    StudyContext ctx{quick, threads_or_default(threads), nullptr};
    ctx.distribute = false;
    ctx.scenes = &scenes;
    out = study->run(ctx);
  }
  py::dict tables;
  for (const auto& [stem, table] : out.tables) tables[py::str(stem)] = table_dict(table);
  py::dict d;
  d["tables"] = tables;
  d["markdown"] = out.markdown;
  return d;
}

py::list method_list() {
  py::list l;
  for (const Method& m : methods()) {
    py::dict d;
    d["name"] = std::string(m.name);
    d["family"] = std::string(to_string(m.family));
    d["source"] = std::string(to_string(m.source));
    d["description"] = std::string(m.description);
    d["order"] = std::string(m.order.text);
    d["order_min"] = m.order.min;
    d["order_max"] = m.order.max;
    d["stepping"] = m.stepping == Stepping::fixed ? "fixed" : m.stepping == Stepping::adaptive ? "adaptive" : "fixed or adaptive";
    d["needs"] = std::string(m.needs.what);
    d["options"] = to_python(method_options_json(m));
    l.append(d);
  }
  return l;
}

}  // namespace
}  // namespace stepwise

PYBIND11_MODULE(_stepwise, m) {
  using namespace stepwise;
  m.doc() = "stepwise's compiled half; use the package `stepwise` (python/stepwise/__init__.py)";
  // the command line's exit-2 errors are Python's ValueError, with the same message
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const BadMethod& e) {
      PyErr_SetString(PyExc_ValueError, fmt::format("method: {}", e.what()).c_str());
    }
  });
  m.def("version", [] { return std::string(version()); });
  m.def("methods", &method_list);
  m.def("solve", &solve, py::arg("fun"), py::arg("t0"), py::arg("t1"), py::arg("y0"), py::arg("method"), py::arg("rtol"), py::arg("atol"), py::arg("dt"),
        py::arg("max_step"), py::arg("t_eval"), py::arg("jac"), py::arg("max_steps"), py::arg("events") = py::list(), py::arg("record_steps") = false);
  m.def("run", &run, py::arg("scene"), py::arg("method"), py::arg("dt"), py::arg("rtol"), py::arg("atol"), py::arg("t_end"), py::arg("output_dt"), py::arg("set"),
        py::arg("max_steps"), py::arg("options"));
  m.def("advise", &advise_scene, py::arg("scene"), py::arg("error"), py::arg("budget"), py::arg("set"), py::arg("threads"));
  m.def("study", &study_scene, py::arg("name"), py::arg("scene"), py::arg("set"), py::arg("quick"), py::arg("threads"));
  py::class_<Equations>(m, "Equations", R"doc(A system written as equations: parsed, differentiated and compiled once (models/equations.hpp).

Parameters
----------
equations : dict of str to str
    Each variable's derivative as a formula: {"x": "v", "v": "-g/L*sin(x)"}; the variables are its keys, in order.
parameters : dict of str to float, optional
    The names the formulas may use besides the variables and t.
initial : dict of str to float, optional
    The initial state, by variable.
energy : str, optional
    An invariant to chart, in the variables and parameters.
exact : dict of str to str, optional
    Each variable as a formula in t and the parameters (errors are measured against it).
events : dict of str to dict, optional
    Events by name: {"when": g, "direction": -1|0|1, "action": {variable: formula}, "terminal": bool, "rest": rule}.
compile : bool, optional
    Compile f and its Jacobian to machine code (default True); else the tape interpreter runs.

Attributes
----------
variables : list of str
parameters : dict of str to float
compiled : bool
    Whether the compiled code runs.
evaluation : str
    Why the compiled code or the interpreter runs.

Raises
------
ValueError
    A formula that does not parse or cannot be evaluated, an unknown symbol, a variable without an equation or an
    initial value (the message names the formula and its column).
TypeError
    An events entry that is not a dict.
)doc")
      .def(py::init(&make_python_equations), py::arg("equations"), py::arg("parameters") = std::map<std::string, double>{}, py::arg("initial") = py::none(),
           py::arg("energy") = py::none(), py::arg("exact") = py::none(), py::arg("events") = py::none(), py::arg("compile") = true)
      .def_static("from_scene", &equations_from_scene, py::arg("file"), py::arg("compile") = true)
      .def_property_readonly("variables", [](const Equations& e) { return e.spec().variables; })
      .def_property_readonly("parameters", [](const Equations& e) { return std::map<std::string, double>(e.spec().parameters.begin(), e.spec().parameters.end()); })
      .def_property_readonly("compiled", [](const Equations& e) { return equations_evaluation(e.model())->compiled; })
      .def_property_readonly("evaluation", [](const Equations& e) { return equations_evaluation(e.model())->detail; })
      .def("__repr__", [](const Equations& e) { return fmt::format("stepwise.Equations(variables=[{}])", fmt::join(e.spec().variables, ", ")); });
}
