// A method is one registered object: its name, family and order, what it needs of a system, how it is made,
// and what the project knows of its stability. Each method family registers its methods from its own file
// (solvers/methods/*.cpp, solvers/gpu/*.cpp); solvers/method_table.hpp is the table they make, and the only
// place a method's name is looked up.
#pragma once

#include <stepwise/solvers/capabilities/wave_grid.hpp>
#include <stepwise/solvers/integrator.hpp>

#include <complex>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace stepwise {

// the family file that registers a method (solvers/methods/*.cpp, solvers/gpu/); named in methods.csv and
// `stepwise methods --json` as to_string spells it
enum class Family {
  euler, symplectic_euler, rk4, embedded_pairs, odeint, gsl, cvode, arkode, rosenbrock, implicit_euler, fast_mass_spring,
  position_based, vertex_block_descent, constrained, rigid_splitting, sequential_impulses, wave_fd, stable_fluids, gpu
};
std::string_view to_string(Family family);  // "euler", "symplectic-euler", ..., "gpu"

// whose code steps a method
enum class Source { hand_written, gsl, cvode, arkode, ida, odeint, opengl_shader };
std::string_view to_string(Source source);  // "hand-written", "GSL odeiv2", "SUNDIALS CVODE", ..., "OpenGL shader"

// how a method can be stepped
enum class Stepping { fixed, adaptive, fixed_or_adaptive };

// when a method keeps dense n x n matrices (a Jacobian and a Newton matrix), which the memory rule counts
enum class DenseMatrices {
  none,                    // explicit, or no Newton iteration: no matrix
  always,                  // every system
  unless_sparse_jacobian,  // KLU on the system's fixed sparse pattern when it has one (CVODE BDF)
  unless_mass_spring_or_sparse,  // CHOLMOD on a mass-spring system's pattern, UMFPACK on a sparse Jacobian (backward Euler)
  constrained_dae,         // every system, of its size plus two multipliers a distance constraint (IDA)
};

// the documented order range; text as `stepwise methods` shows it ("4", "1-12", "variable")
struct Order {
  int min = 0, max = 0;
  std::string_view text;
};

// what the project knows of a method's stability, where it knows it
struct Stability {
  // R(z) of a one-step method on y' = lambda y, z = h lambda (empty for a map on (x, v) pairs, multistep and
  // adaptive methods): the regions and every spectrum's stable step (stability.hpp) come from it
  std::complex<double> (*R)(std::complex<double> z) = nullptr;
  // the largest stable step on a damped oscillator mode x'' = -omega^2 x - 2 a x' (omega rad/s, a 1/s): the
  // stiffest mode of a mass-spring system (verification/stability.hpp) sets the method's limit there
  std::function<double(double omega, double damping)> oscillator_dt;
  // the largest stable step on a height-field grid (solvers/wave_step.hpp's derived limits)
  std::function<double(const WaveGridView& grid)> wave_dt;
};

// how a method runs on MPI ranks, where it can (its own family file says): the grid split among the ranks by the
// hand-written scheme (run/distributed_run.hpp: wave-fd), or the height field's method of lines on SUNDIALS'
// parallel vector (solvers/distributed_lines.hpp) under CVODE, Adams or BDF, or under ARKODE with the method's tables
enum class OnRanks { no, split_grid, cvode_adams, cvode_bdf, arkode };

// one setting of a method's own (vbd's sweeps a step, vbd-chebyshev's rate), declared with the method: the command
// line's --NAME for `run` and `render`, Python's keyword NAME, the refusals (a value out of range, a method that does
// not take it), `stepwise methods --json`, the echo in summary.json and, through those, docs/cli.md and the schema
// all come from this one declaration. Methods that declare one name declare it of one kind (MethodTable::add)
struct MethodOption {
  enum class Kind { whole, real, choice };
  std::string_view name;  // lower case and dashes: --NAME; Python's keyword with '_' for '-'
  Kind kind = Kind::whole;
  // the range: whole numbers in [min, max]; real numbers in the open (min, max); unused for a choice
  double min = 1, max = 1;
  double fallback = 1;  // the default (a choice's: the index of its default in `choices`)
  std::string_view unit;  // "s", "1/s"; empty for a count or a ratio
  std::string_view help;  // one line: what it sets
  std::vector<std::string_view> choices;  // a choice's values
  std::string_view echo;  // summary.json's key where it is not the name (a key published before the option was)

  std::string_view key() const { return echo.empty() ? name : echo; }
  std::string type_text() const;  // "INT", "FLOAT", or the choices joined by '|'
  std::string range_text() const;      // "1..1000000", "(0, 1)", "inertial or adaptive"
  std::string value_text(double value) const;  // as the user writes it: "4", "0.99", "adaptive"
  // "" when the value is in range, else why not (without the option's name)
  std::string refusal(double value) const;
  // the value a user's text names: a number in range, or one of the choices; BadMethod saying what is allowed (the
  // caller names the option and the text)
  double parse(std::string_view text) const;
};

struct Method;
// the integrator for one run of `method` with `control` (the control already checked against the method)
using MakeIntegrator = std::function<std::unique_ptr<Integrator>(const Method& method, const StepControl& control)>;

struct Method {
  std::string_view name;         // as docs/methods.md spells it, everywhere: CLI, CSV, plots
  Family family;
  Source source;
  std::string_view description;  // one line: what it is
  Order order;
  Stepping stepping = Stepping::fixed;
  Requirement needs;  // the capability it needs of a system (solvers/capabilities/), if any
  DenseMatrices dense = DenseMatrices::none;
  std::vector<MethodOption> options;  // its own settings, in the order --help and methods --json list them
  OnRanks on_ranks = OnRanks::no;
  MakeIntegrator make;
  Stability stability;
  // "" or why this system cannot be run on the method's device (a GPU method's grid past the largest texture),
  // asked before a run starts; empty for a method with no device of its own
  std::function<std::string(const OdeSystem& system)> device_problem;
  // the method whose numbers this one computes by other means: to the bit (a compute pass beside its fragment
  // twin: the tests hold them equal), or to float32's round-off (gpu-vbd-compute beside vbd); left out of the
  // report's sweeps, which would only repeat the twin's points, and timed beside it in the benches; empty for most
  std::string_view twin;

  bool fixed_step() const { return stepping != Stepping::adaptive; }
  const MethodOption* option(std::string_view option_name) const;  // nullptr where the method declares none of that name
  // the value of its option `option_name` in this control: the caller's, or the declared default (std::logic_error
  // for an option the method does not declare: a method's own code asking for the wrong name)
  double setting(const StepControl& control, std::string_view option_name) const;
  int whole_setting(const StepControl& control, std::string_view option_name) const;
  bool adaptive() const { return stepping != Stepping::fixed; }
};

// the methods in the order they were registered; a family file adds its own with add()
class MethodTable {
 public:
  // std::logic_error for a name already taken, or an option declared of another kind than another method's of
  // that name (the command line's --NAME is one option for every method that takes it)
  void add(Method method);
  const std::deque<Method>& all() const { return methods_; }
  const Method* find(std::string_view name) const;

 private:
  std::deque<Method> methods_;  // a method's address kept as more are added
};

// whether the method can run this system at all (the structure it needs: y = (x, v), a wave grid; bodies in
// contact need a method that resolves contacts), and if not, why, in words naming the structure
bool method_applies(const Method& method, const OdeSystem& system);
std::string method_requirement(const Method& method, const OdeSystem& system);

// thrown for an unknown method or a step control the method cannot use
struct BadMethod : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// the most substeps a frame, and iterations a substep, a position-based or vbd method takes (their options' range)
inline constexpr int max_substeps = 1000000;
// the most threads a method's own parallel loops run on (vbd's colour sweeps), and a sweep's points (--threads)
inline constexpr int max_threads = 1024;

// "its own: --substeps, --iterations", or that it has none: what a refusal of another option says
std::string options_text(const Method& method);

// BadMethod unless the method can be stepped with this control (fixed against adaptive; a finite positive dt,
// rtol and atol; each of control.settings an option the method declares, in its range): the one check every way
// into a method goes through
void check_step_control(const Method& method, const StepControl& control);

// bytes of the dense n x n matrices the method would keep for this system (0 when it keeps none): a large
// system (a particle system) cannot be run by such a method, and the caller says so before trying
double dense_matrix_bytes(const Method& method, const OdeSystem& system);

}  // namespace stepwise
