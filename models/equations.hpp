// A user's own system, written as equations in a scene file (docs/scenes.md, "Your own equations"):
//
//   model = "equations"
//   variables = ["x", "v"]            # the state, in this order
//   [initial]   x = 2.9  v = 0.0       # one value per variable
//   [parameters] g = 9.81              # optional; every name overridable by --set, as the initial values are
//   [equations] x = "v"  v = "-g*sin(x)"   # d(variable)/dt in the variables, the parameters and t
//   [exact]     ...                    # optional: each variable as a formula in t and the parameters
//   energy = "..."                     # optional: an invariant to chart, in the variables and parameters
//
// GiNaC parses each formula against a symbol table holding only those names (and the functions of the
// whitelist in equations/tape.cpp), differentiates it for the exact Jacobian and its sparsity pattern, and prints C
// source from the expression tree; that source is compiled once into a shared object cached by content hash
// (models/native_code.hpp). Where no compiler is, a tape interpreter over the same tree evaluates f and df/dy.
// The parts, a file each in models/equations/: tape.* (the tape and its interpreter), c_source.* (the C printed
// from the tapes), symbolic.* (GiNaC: parsing, differentiation, the tape builder; GiNaC's types stay there and in
// the model), spec_checks.* (the scene's shape and values), model.cpp (the model, its events, its Jacobian and
// its compiled code). The model then is an ordinary Model.
#pragma once

#include <stepwise/models/model.hpp>

#include <optional>
#include <string>
#include <vector>

namespace stepwise {

// one formula of the scene file, as written
struct Formula {
  std::string name;   // the variable it is for ("v"), or "energy"
  std::string text;   // the formula
  std::string file;   // the scene file
  std::string key;    // "equations.v", for messages
  int line = 0;       // where the formula's text starts in the file (0: unknown)
  int column = 0;     // the file column of its first character (0: unknown)
  // "file:line: key", or "file:line:column: key" for a column of the formula's text (from 1)
  std::string where(int column_in_text = 0) const;
};

// an event of the scene file ([events.NAME], docs/scenes.md): where `when` crosses zero in `direction`, the
// variables of `action` are set by formulas of the state just before it (all from that one state); `terminal`
// ends the run there; where `rest` holds at the event, the action's variables are set to 0 and held there, and
// the event is disarmed (the state gains a flag NAME.resting, 0 or 1, that says so)
struct EventSpec {
  std::string name;
  std::string where;        // "file:line: events.NAME"
  Formula when;
  int direction = 0;        // +1 rising, -1 falling, 0 either
  std::vector<Formula> action;  // each named by its variable
  bool terminal = false;
  std::optional<Formula> rest;  // "LEFT < RIGHT" (or <=, >, >=), each side a formula
};

// the scene file's equations, as written (checked for names and shape on making the model)
struct EquationsSpec {
  std::string file;
  std::vector<std::string> variables;
  std::string variables_where;  // "file:line: variables"
  Params initial;               // one per variable
  Params parameters;            // [parameters]
  std::vector<Formula> equations, exact;
  std::optional<Formula> energy;
  std::vector<EventSpec> events;
};

// the largest system and formula the equations model takes: hand-written equations are far below both, and a
// larger one would spend minutes differentiating (n^2 derivatives) before any step
inline constexpr size_t max_equations = 1000;
inline constexpr size_t max_formula_chars = 10000;
// the deepest nesting of parentheses and signs in a formula: GiNaC's parser recurses once a level
inline constexpr int max_formula_depth = 100;

// a formula or a system that cannot be made: the whole one-line message, naming the file, line, key and column
struct BadEquations : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// what the model says of itself, for summary.json: how f is evaluated (a compiled shared object, or the
// interpreter, and why), and whether [exact] is used
struct EquationsEvaluation {
  bool compiled = false;   // f is the compiled code now
  bool from_cache = false; // the compiled code was a verified cache entry (else compiled by this model)
  bool background = false; // compiled in the background while the interpreter ran (a large system)
  double compile_seconds = 0;  // the background compile's wall-clock time, once it ended
  size_t source_bytes = 0; // the C's size
  int units = 0;           // the compiler calls it is split into
  std::string detail;      // the cache file loaded, or why the interpreter runs
  std::string exact_note;  // empty, or why [exact] is not used (it does not match the initial state)
  int second_order = 0;    // positions n where the equations read x' = v (SecondOrderView), else 0
};

// the model with `values` (parameters and initial values by name, over the spec's) applied; BadParameter naming
// the key for an unknown name or a non-finite value, BadEquations for a system or formula at fault (one that does
// not parse, names an unknown symbol, calls a function outside the whitelist, or is not finite at the initial
// state), all before anything is compiled.
// how f is evaluated: compiled C, or the interpreter over the same tapes (the same bits). The C is split into
// functions and units whose sizes keep the compiler's time and memory linear in the system (measured in
// docs/performance.md); a large one is compiled in the background while the interpreter runs
struct EquationsOptions {
  bool compile = true;                    // false: the interpreter, as where no compiler is
  size_t function_bytes = 64 << 10;       // C in one function at most (a longer f is split into parts)
  size_t unit_bytes = 1 << 20;            // C in one compiler call at most (units compiled in parallel)
  size_t optimise_below = 1 << 20;        // -O2 below this much C, -O1 above
  size_t optimise_none_above = 4 << 20;   // -O0 above this much C (a MB at -O2, -O1, -O0: 9.1, 7.4, 2.9 s here)
  size_t background_above = 256 << 10;    // more C: compiled in the background while the interpreter runs
  double compile_seconds = 600;           // the compiler's time limit; past it, the interpreter, saying so
};

std::unique_ptr<Model> make_equations(const EquationsSpec& spec, const Params& values, const EquationsOptions& options);
// `compile`: try the compiler (false: the interpreter, as where none is)
std::unique_ptr<Model> make_equations(const EquationsSpec& spec, const Params& values, bool compile = true);

// the parameter and initial-value names a spec takes (for --set and messages)
std::vector<std::string> equations_keys(const EquationsSpec& spec);

// how the model evaluates f (empty for a model that is not an equations model)
std::optional<EquationsEvaluation> equations_evaluation(const Model& model);

}  // namespace stepwise
