#include "equations.hpp"

#include "native_code.hpp"
#include "solvers/capabilities/inline_rhs.hpp"
#include "solvers/capabilities/second_order.hpp"

#include <boost/container/small_vector.hpp>
#include <fmt/format.h>
#include <ginac/ginac.h>

#include <algorithm>
#include <iterator>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <map>
#include <mutex>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <thread>
#include <unordered_map>

namespace stepwise {
namespace {

// ---- what a formula may call: GiNaC parses many more functions (zeta, gamma, ...); these are the ones
// evaluated, by the interpreter (fn) and in the generated C (c). Their derivatives are in the same set
struct Function1 {
  std::string_view name;
  double (*fn)(double);
  std::string_view c;
};
const std::array functions1{
    Function1{"sin", [](double x) { return std::sin(x); }, "sin"},    Function1{"cos", [](double x) { return std::cos(x); }, "cos"},
    Function1{"tan", [](double x) { return std::tan(x); }, "tan"},    Function1{"asin", [](double x) { return std::asin(x); }, "asin"},
    Function1{"acos", [](double x) { return std::acos(x); }, "acos"}, Function1{"atan", [](double x) { return std::atan(x); }, "atan"},
    Function1{"sinh", [](double x) { return std::sinh(x); }, "sinh"}, Function1{"cosh", [](double x) { return std::cosh(x); }, "cosh"},
    Function1{"tanh", [](double x) { return std::tanh(x); }, "tanh"}, Function1{"asinh", [](double x) { return std::asinh(x); }, "asinh"},
    Function1{"acosh", [](double x) { return std::acosh(x); }, "acosh"}, Function1{"atanh", [](double x) { return std::atanh(x); }, "atanh"},
    Function1{"exp", [](double x) { return std::exp(x); }, "exp"},    Function1{"log", [](double x) { return std::log(x); }, "log"},
    Function1{"sqrt", [](double x) { return std::sqrt(x); }, "sqrt"}, Function1{"abs", [](double x) { return std::abs(x); }, "fabs"},
};
constexpr std::string_view functions2 = "atan2";  // atan2(y, x)
const std::string function_list = "sin, cos, tan, asin, acos, atan, atan2, sinh, cosh, tanh, asinh, acosh, atanh, exp, log, sqrt, abs, pow and ^";

// names a variable or parameter may not take: the functions, the time, and GiNaC's constants
bool reserved(std::string_view name) {
  if (name == "t" || name == "pow" || name == functions2 || name == "Pi" || name == "I" || name == "Euler" || name == "Catalan") return true;
  return std::any_of(functions1.begin(), functions1.end(), [&](const Function1& f) { return f.name == name; });
}

// ---- the tape: a formula in postfix, what the interpreter runs and the C is printed from (so both compute the
// same operations in the same order: the compiled and interpreted f agree to the bit)
enum class Op : std::uint8_t { number, variable, parameter, time, add, mul, power, integer_power, call, atan2 };
struct Instruction {
  Op op;
  int arg = 0;       // variable, parameter or function index; operand count of add and mul; integer exponent
  double value = 0;  // number
};
struct Tape {
  std::vector<Instruction> code;
  int depth = 0;  // the deepest the value stack goes
};

// x^n by binary powering (the generated C's stepwise_ipow is the same loop)
double integer_power(double x, int n) {
  double result = 1, base = x;
  for (unsigned m = static_cast<unsigned>(n < 0 ? -n : n); m; m >>= 1) {
    if (m & 1u) result *= base;
    base *= base;
  }
  return n < 0 ? 1 / result : result;
}
constexpr std::string_view c_integer_power =
    "static double stepwise_ipow(double x, int n) {\n"
    "  double result = 1, base = x;\n"
    "  for (unsigned m = (unsigned)(n < 0 ? -n : n); m; m >>= 1) {\n"
    "    if (m & 1u) result *= base;\n"
    "    base *= base;\n"
    "  }\n"
    "  return n < 0 ? 1 / result : result;\n"
    "}\n";

double run(const Tape& tape, double t, const double* y, const double* p, double* stack) {
  int top = 0;
  for (const Instruction& in : tape.code) {
    switch (in.op) {
      case Op::number: stack[top++] = in.value; break;
      case Op::variable: stack[top++] = y[in.arg]; break;
      case Op::parameter: stack[top++] = p[in.arg]; break;
      case Op::time: stack[top++] = t; break;
      case Op::add: {
        top -= in.arg;
        double s = stack[top];
        for (int k = 1; k < in.arg; ++k) s += stack[top + k];
        stack[top++] = s;
        break;
      }
      case Op::mul: {
        top -= in.arg;
        double s = stack[top];
        for (int k = 1; k < in.arg; ++k) s *= stack[top + k];
        stack[top++] = s;
        break;
      }
      case Op::power: --top; stack[top - 1] = std::pow(stack[top - 1], stack[top]); break;
      case Op::integer_power: stack[top - 1] = integer_power(stack[top - 1], in.arg); break;
      case Op::call: stack[top - 1] = functions1[static_cast<size_t>(in.arg)].fn(stack[top - 1]); break;
      case Op::atan2: --top; stack[top - 1] = std::atan2(stack[top - 1], stack[top]); break;
    }
  }
  return stack[0];
}

// the scratch stack of the calling thread (a sweep's threads share one model)
double* scratch(int depth) {
  thread_local std::vector<double> stack;
  if (stack.size() < static_cast<size_t>(depth)) stack.resize(static_cast<size_t>(depth));
  return stack.data();
}

// a tape's stack: on the caller's stack where the tapes are shallow (most are), else the thread's scratch. A
// thread_local in a shared library is reached through __tls_get_addr, as costly as an event's one-line tape,
// which a solve runs at every step
class TapeStack {
 public:
  explicit TapeStack(int depth) : data_(depth <= on_stack ? local_.data() : scratch(depth)) {}
  double* get() { return data_; }

 private:
  static constexpr int on_stack = 32;
  std::array<double, on_stack> local_;
  double* data_;
};

// the largest system whose compiled f a stepper calls inline (solvers/capabilities/inline_rhs.hpp)
constexpr size_t max_inline_size = 4;

// a list of tapes (f's, or its Jacobian's nonzeros) as one computation in which each operation is done once: a
// value is numbered by its operation and operands, and an entry that computes one already computed reads it (a
// mean field's Jacobian: the cos(x_j - x_i) of the off-diagonal entries are the terms of the diagonal ones). The
// operations and their order are the tapes', so each value rounds as the interpreter's does
struct Dag {
  struct Operand {
    int value = -1;    // a computed value's number, or -1 for a leaf
    std::string leaf;  // a leaf's C: a number, y[i], p[k] or t
  };
  struct Node {
    Op op;
    int arg;
    std::vector<Operand> operands;
  };
  std::vector<Node> nodes;        // in the order they are first computed
  std::vector<Operand> outputs;   // out[k]
  std::vector<size_t> ready;      // outputs[k] can be written once nodes[0, ready[k]) are

  explicit Dag(const std::vector<Tape>& tapes) {
    std::unordered_map<std::string, int> numbered;
    std::vector<Operand> stack;
    for (const Tape& tape : tapes) {
      stack.clear();
      for (const Instruction& in : tape.code) {
        switch (in.op) {
          case Op::number: stack.push_back({-1, fmt::format("({:a})", in.value)}); continue;
          case Op::variable: stack.push_back({-1, fmt::format("y[{}]", in.arg)}); continue;
          case Op::parameter: stack.push_back({-1, fmt::format("p[{}]", in.arg)}); continue;
          case Op::time: stack.push_back({-1, "t"}); continue;
          default: break;
        }
        const size_t arity = in.op == Op::add || in.op == Op::mul ? static_cast<size_t>(in.arg)
                             : in.op == Op::power || in.op == Op::atan2 ? 2 : 1;
        Node node{in.op, in.arg, {stack.end() - static_cast<std::ptrdiff_t>(arity), stack.end()}};
        stack.resize(stack.size() - arity);
        std::string key = fmt::format("{}:{}", static_cast<int>(in.op), in.arg);
        for (const auto& o : node.operands) key += o.value >= 0 ? fmt::format(",#{}", o.value) : "," + o.leaf;
        const auto [it, added] = numbered.emplace(std::move(key), static_cast<int>(nodes.size()));
        if (added) nodes.push_back(std::move(node));
        stack.push_back({it->second, {}});
      }
      outputs.push_back(stack.back());
      ready.push_back(nodes.size());
    }
  }
};

// the C of one operation on its operands' C
std::string c_of(const Dag::Node& node, const std::vector<std::string>& x) {
  switch (node.op) {
    case Op::add:
    case Op::mul: {
      std::string expr = x[0];
      for (size_t k = 1; k < x.size(); ++k) expr = fmt::format("({} {} {})", expr, node.op == Op::add ? '+' : '*', x[k]);
      return expr;
    }
    case Op::power: return fmt::format("pow({}, {})", x[0], x[1]);
    case Op::integer_power: return fmt::format("stepwise_ipow({}, {})", x[0], node.arg);
    case Op::call: return fmt::format("{}({})", functions1[static_cast<size_t>(node.arg)].c, x[0]);
    case Op::atan2: return fmt::format("atan2({}, {})", x[0], x[1]);
    default: return x[0];
  }
}

std::string bytes_text(size_t bytes) {
  return bytes < (1u << 20) ? fmt::format("{:.0f} kB", bytes / 1e3) : fmt::format("{:.3g} MB", bytes / 1e6);
}

// one of f's or the Jacobian's functions as C: `name` (t, y, p, out). Its values are computed in parts of about
// `function_bytes` of C (the compiler's time and memory grow faster than a function's length), called in order;
// a value one part computes and a later part reads goes through a thread's workspace (a sweep's threads share
// the object), the others stay local
std::vector<std::string> c_functions(const std::string& name, const std::vector<Tape>& tapes, size_t function_bytes, std::string& declarations) {
  const Dag dag(tapes);
  // each value's part, and each output's: a part ends once its C passes function_bytes (told
  // from each value's operands, before any is written)
  std::vector<int> part_of(dag.nodes.size()), output_part(dag.outputs.size());
  {
    int part = 0;
    size_t bytes = 0, k = 0;
    for (size_t v = 0; v <= dag.nodes.size(); ++v) {
      for (; k < dag.outputs.size() && dag.ready[k] <= v; ++k) output_part[k] = part, bytes += 20;
      if (v == dag.nodes.size()) break;
      if (bytes > function_bytes) ++part, bytes = 0;
      part_of[v] = part;
      bytes += 30;
      for (const auto& o : dag.nodes[v].operands) bytes += o.value >= 0 ? 8 : o.leaf.size() + 2;
    }
  }
  // the values read by a later part than their own: a slot each in the workspace
  std::vector<int> slot(dag.nodes.size(), -1);
  int slots = 0;
  const auto read_in = [&](const Dag::Operand& o, int part) {
    if (o.value >= 0 && part_of[static_cast<size_t>(o.value)] != part && slot[static_cast<size_t>(o.value)] < 0) slot[static_cast<size_t>(o.value)] = slots++;
  };
  for (size_t v = 0; v < dag.nodes.size(); ++v)
    for (const auto& o : dag.nodes[v].operands) read_in(o, part_of[v]);
  for (size_t k = 0; k < dag.outputs.size(); ++k) read_in(dag.outputs[k], output_part[k]);

  const int parts = dag.nodes.empty() ? 1 : part_of.back() + 1;
  std::vector<std::string> bodies(static_cast<size_t>(std::max(parts, output_part.empty() ? 1 : output_part.back() + 1)));
  const auto text = [&](const Dag::Operand& o, int part) {
    if (o.value < 0) return o.leaf;
    const auto v = static_cast<size_t>(o.value);
    return part_of[v] == part ? fmt::format("v{}", v) : fmt::format("w[{}]", slot[v]);
  };
  size_t k = 0;
  const auto write_outputs = [&](size_t upto) {
    for (; k < dag.outputs.size() && dag.ready[k] <= upto; ++k)
      bodies[static_cast<size_t>(output_part[k])] += fmt::format("  out[{}] = {};\n", k, text(dag.outputs[k], output_part[k]));
  };
  for (size_t v = 0; v < dag.nodes.size(); ++v) {
    write_outputs(v);
    const int part = part_of[v];
    std::vector<std::string> x;
    for (const auto& o : dag.nodes[v].operands) x.push_back(text(o, part));
    std::string& body = bodies[static_cast<size_t>(part)];
    body += fmt::format("  const double v{} = {};\n", v, c_of(dag.nodes[v], x));
    if (slot[v] >= 0) body += fmt::format("  w[{}] = v{};\n", slot[v], v);
  }
  write_outputs(dag.nodes.size());

  constexpr std::string_view signature = "(double t, const double* y, const double* p, double* out)";
  const std::string opening = "{\n  (void)t; (void)y; (void)p; (void)out;\n";
  if (bodies.size() == 1) return {fmt::format("void {}{} {}{}}}\n", name, signature, opening, bodies[0])};
  std::vector<std::string> functions;
  std::string calls;
  for (size_t part = 0; part < bodies.size(); ++part) {
    declarations += fmt::format("void {}_part{}(double t, const double* y, const double* p, double* out, double* w);\n", name, part);
    functions.push_back(fmt::format("void {}_part{}(double t, const double* y, const double* p, double* out, double* w) {}  (void)w;\n{}}}\n",
                                    name, part, opening, bodies[part]));
    calls += fmt::format("  {}_part{}(t, y, p, out, w);\n", name, part);
  }
  functions.push_back(fmt::format("static _Thread_local double {}_workspace[{}];\nvoid {}{} {{\n  double* w = {}_workspace;\n{}}}\n", name,
                                  std::max(slots, 1), name, signature, name, calls));
  return functions;
}

// f and its Jacobian's nonzeros as C: `stepwise_rhs` and `stepwise_jacobian` (t, y, p, out), their parts
// gathered into units of about `unit_bytes`, each compiled apart and in parallel (JiTCODE's chunking)
NativeSource c_source(const std::vector<Tape>& rhs, const std::vector<Tape>& jacobian, size_t function_bytes, size_t unit_bytes) {
  NativeSource source;
  source.common = fmt::format("#include <math.h>\n{}", c_integer_power);
  std::string declarations;
  std::vector<std::string> functions = c_functions("stepwise_rhs", rhs, function_bytes, declarations);
  // for 2 to 4 unknowns, f with the state in and f out by value (solvers/capabilities/inline_rhs.hpp: NativeRhs);
  // f's body is a static inline function both call, so the two compute the same operations
  if (const size_t n = rhs.size(); n >= 2 && n <= max_inline_size && functions.size() == 1) {
    std::string& f = functions.front();
    const std::string head = "void stepwise_rhs(double t, const double* y, const double* p, double* out) ";
    f = "static inline void stepwise_rhs_body(double t, const double* y, const double* p, double* out) " + f.substr(head.size());
    std::string args, state;
    for (size_t i = 0; i < n; ++i) args += fmt::format("double y{}, ", i), state += fmt::format("{}y{}", i ? ", " : "", i);
    f += fmt::format("void stepwise_rhs(double t, const double* y, const double* p, double* out) {{ stepwise_rhs_body(t, y, p, out); }}\n"
                     "typedef struct {{ double v[{0}]; }} stepwise_values;\n"
                     "stepwise_values stepwise_rhs_values(double t, {1}const double* p) {{\n"
                     "  const double y[{0}] = {{{2}}};\n  stepwise_values r;\n  stepwise_rhs_body(t, y, p, r.v);\n  return r;\n}}\n", n, args, state);
  }
  for (auto& f : c_functions("stepwise_jacobian", jacobian, function_bytes, declarations)) functions.push_back(std::move(f));
  source.common += declarations;
  source.units.emplace_back();
  for (const auto& f : functions) {
    if (!source.units.back().empty() && source.units.back().size() + f.size() > unit_bytes) source.units.emplace_back();
    source.units.back() += f;
  }
  return source;
}

// ---- GiNaC: the symbols of a system and the formulas parsed against them.
// GiNaC is not thread-safe (its reference counts and shared numbers are plain integers): every use of it, from
// parsing to the last expression's destruction, holds this lock (a sweep's threads may make models at once)
std::mutex ginac_mutex;

// one symbol per name for the life of the process: GiNaC orders a sum's terms by hash, which follows the
// symbols' serial numbers, and normalises by that order (cos(a - b) or cos(b - a)); fresh symbols for each
// parse of the same formula could make a different tree, and differently rounded code
const GiNaC::realsymbol& symbol_named(const std::string& name) {
  static std::map<std::string, GiNaC::realsymbol, std::less<>> symbols;
  const auto it = symbols.find(name);
  return it != symbols.end() ? it->second : symbols.emplace(name, GiNaC::realsymbol(name)).first->second;
}

struct Symbols {
  std::vector<GiNaC::realsymbol> variables, parameters;
  GiNaC::realsymbol t = symbol_named("t");
  std::vector<std::string> variable_names, parameter_names;
  std::unordered_map<std::string, std::pair<bool, int>> index;  // name -> (a variable, else a parameter; its position)
  std::string defined;  // the names in words, for a message about an unknown one
};

// the column (from 1) of the whole word `word` in `text`, searching back from `before`; 0 if absent
int column_of(const std::string& text, const std::string& word, size_t before = std::string::npos) {
  if (word.empty()) return 0;
  const bool identifier = std::isalpha(static_cast<unsigned char>(word[0])) || word[0] == '_';
  for (size_t at = text.rfind(word, before); at != std::string::npos; at = at == 0 ? std::string::npos : text.rfind(word, at - 1)) {
    const auto part_of_word = [&](size_t i) { return i < text.size() && (std::isalnum(static_cast<unsigned char>(text[i])) || text[i] == '_'); };
    if (!identifier || ((at == 0 || !part_of_word(at - 1)) && !part_of_word(at + word.size()))) return static_cast<int>(at) + 1;
  }
  return 0;
}

GiNaC::ex parse(const Formula& f, const Symbols& symbols, bool allow_variables, bool allow_time) {
  const std::string& text = f.text;
  if (text.size() > max_formula_chars)
    throw BadEquations(fmt::format("{}: the formula is {} characters long, more than the {} a formula may hold", f.where(), text.size(), max_formula_chars));
  if (text.find_first_not_of(" \t") == std::string::npos) throw BadEquations(fmt::format("{}: the formula is empty", f.where()));
  // nesting: parentheses, and runs of signs (GiNaC's parser recurses once for each)
  int depth = 0, deepest = 0, signs = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    depth += c == '(' ? 1 : c == ')' ? -1 : 0;
    signs = c == '+' || c == '-' ? signs + 1 : c == ' ' || c == '\t' ? signs : 0;
    deepest = std::max({deepest, depth, signs});
    if (deepest > max_formula_depth)
      throw BadEquations(fmt::format("{}: nested more than {} deep", f.where(static_cast<int>(i) + 1), max_formula_depth));
  }
  GiNaC::symtab table;
  if (allow_variables)
    for (size_t i = 0; i < symbols.variables.size(); ++i) table[symbols.variable_names[i]] = symbols.variables[i];
  for (size_t i = 0; i < symbols.parameters.size(); ++i) table[symbols.parameter_names[i]] = symbols.parameters[i];
  if (allow_time) table["t"] = symbols.t;
  GiNaC::parser reader(table, true);
  std::istringstream in(text);
  try {
    return reader(in);
  } catch (const GiNaC::parse_error& e) {
    // GiNaC says "parse error at line 0, column 0: WHAT, got: TOKEN" and where in its source: kept is WHAT and
    // TOKEN, and the column is found from the token and how far the parser read
    std::string what = e.what();
    what = what.substr(0, what.find('\n'));
    if (const auto colon = what.find(": "); what.starts_with("GiNaC: parse error") && colon != std::string::npos)
      if (const auto second = what.find(": ", colon + 2); second != std::string::npos) what = what.substr(second + 2);
    in.clear();
    const auto read = in.tellg();
    const size_t stop = read < 0 ? text.size() : static_cast<size_t>(read);
    int column = static_cast<int>(text.size()) + 1;
    if (const auto got = what.rfind("got: \""); got != std::string::npos) {
      const std::string token = what.substr(got + 6, what.size() - got - 7);
      if (const int c = column_of(text, token, stop); c > 0) column = c;
    } else if (const auto name = what.find("no function \""); name != std::string::npos) {
      const std::string function = what.substr(name + 13, what.find('"', name + 13) - name - 13);
      column = std::max(1, column_of(text, function, stop));
      const bool known = function == "pow" || function == functions2 ||
                         std::any_of(functions1.begin(), functions1.end(), [&](const Function1& g) { return g.name == function; });
      what = fmt::format("{} '{}' (a formula may call {})", known ? "wrong number of arguments to" : "unknown function", function, function_list);
    }
    throw BadEquations(fmt::format("{}: {}", f.where(column), what));
  } catch (const std::invalid_argument& e) {
    // the strict symbol table: `find_or_insert_symbol: symbol "y" not found`
    const std::string what = e.what();
    const auto open = what.find('"'), close = what.rfind('"');
    const std::string name = open != std::string::npos && close > open ? what.substr(open + 1, close - open - 1) : what;
    std::string defined = allow_variables ? symbols.defined : fmt::format("parameters {}", fmt::join(symbols.parameter_names, ", "));
    if (!allow_variables && symbols.parameter_names.empty()) defined = "no parameters";
    const bool variable = std::find(symbols.variable_names.begin(), symbols.variable_names.end(), name) != symbols.variable_names.end();
    throw BadEquations(fmt::format("{}: {} '{}' (defined: {}{})", f.where(std::max(1, column_of(text, name))),
                                   variable ? "this formula cannot use the variable" : "unknown symbol", name, defined, allow_time ? "; and t" : ""));
  }
}

// derivatives in the variables, differentiating only the parts that hold the variable. GiNaC's diff walks every
// operand of a sum or product, and differentiates a function (sin, exp, ...) by first trying an explicit
// derivative that throws, and catching: a dense system's n^2 derivatives of n-term formulas cost n^3 of those
// throws (300 mean-field oscillators: two minutes before the first step). Here a part without the variable is
// skipped (its variables found once per part), so each derivative costs the terms that hold its variable
class Differentiator {
 public:
  explicit Differentiator(const Symbols& s) : s_(s) {}
  // d e / d variables[c]
  GiNaC::ex derivative(const GiNaC::ex& e, int c) {
    using namespace GiNaC;
    const Part& part = part_of(e);
    if (!std::binary_search(part.variables.begin(), part.variables.end(), c)) return 0;
    const bool sum = is_a<add>(e);
    if (!sum && !is_a<mul>(e)) return e.diff(s_.variables[static_cast<size_t>(c)]);
    // the operands that hold the variable: a sum's derivatives added, a product's by the product rule
    const auto [first, last] = std::equal_range(part.holders.begin(), part.holders.end(), std::pair{c, 0},
                                                [](const auto& a, const auto& b) { return a.first < b.first; });
    exvector terms;
    for (auto it = first; it != last; ++it) {
      const ex d = derivative(part.operands[static_cast<size_t>(it->second)], c);
      if (sum) {
        terms.push_back(d);
        continue;
      }
      exvector factors(part.operands);
      factors[static_cast<size_t>(it->second)] = d;
      terms.push_back(mul(factors));
    }
    return add(terms);
  }

  // about how many nodes the derivatives of e in all its variables hold together (the Jacobian's size before
  // any is made, from the parts alone): a sum's are its operands'; a product's add, for each operand's variables,
  // the other factors; a function's or power's repeat the whole once per variable, as its outer derivative
  size_t derivative_nodes(const GiNaC::ex& e) { return part_of(e).derivative_nodes; }

 private:
  // an expression's operands (GiNaC makes a sum's or product's anew at each op()), the variables it holds (in
  // order), and for a sum or product which operand holds which variable, by variable
  struct Part {
    GiNaC::exvector operands;
    std::vector<int> variables;
    std::vector<std::pair<int, int>> holders;  // (variable, operand)
    size_t nodes = 1, derivative_nodes = 0;    // the tree's size; derivative_nodes() of it
  };
  const Part& part_of(const GiNaC::ex& e) {
    if (const auto it = memo_.find(e); it != memo_.end()) return it->second;
    Part part;
    if (GiNaC::is_a<GiNaC::symbol>(e)) {
      if (const auto it = s_.index.find(GiNaC::ex_to<GiNaC::symbol>(e).get_name()); it != s_.index.end() && it->second.first) {
        part.variables.push_back(it->second.second);
        part.derivative_nodes = 1;
      }
    } else {
      for (size_t k = 0; k < e.nops(); ++k) part.operands.push_back(e.op(k));
      for (size_t k = 0; k < part.operands.size(); ++k)
        for (const int v : part_of(part.operands[k]).variables) part.holders.emplace_back(v, static_cast<int>(k));
      std::sort(part.holders.begin(), part.holders.end());
      for (const auto& [v, k] : part.holders)
        if (part.variables.empty() || part.variables.back() != v) part.variables.push_back(v);
      for (const auto& operand : part.operands) part.nodes += part_of(operand).nodes;
      const bool sum = GiNaC::is_a<GiNaC::add>(e), product = GiNaC::is_a<GiNaC::mul>(e);
      for (const auto& operand : part.operands) {
        const Part& o = part_of(operand);
        part.derivative_nodes += o.derivative_nodes + (product ? o.variables.size() * (part.nodes - o.nodes) : 0);
      }
      if (!sum && !product) part.derivative_nodes += part.variables.size() * part.nodes;
    }
    return memo_.emplace(e, std::move(part)).first->second;
  }
  const Symbols& s_;
  std::unordered_map<GiNaC::ex, Part> memo_;  // by GiNaC's hash and equality
};

std::string text_of(const GiNaC::ex& e) {
  std::ostringstream text;
  text << e;
  return text.str();
}

// ---- the tape of a parsed formula: what the interpreter runs, and the check that it can be evaluated at all
int depth_of(const Tape& tape) {
  int depth = 0, deepest = 0;
  for (const Instruction& in : tape.code) {
    switch (in.op) {
      case Op::number: case Op::variable: case Op::parameter: case Op::time: ++depth; break;
      case Op::add: case Op::mul: depth -= in.arg - 1; break;
      case Op::power: case Op::atan2: --depth; break;
      default: break;
    }
    deepest = std::max(deepest, depth);
  }
  return deepest;
}

// the parts of the formulas that depend on the parameters alone (g / L in -(g/L) sin x), computed once when the
// model is made rather than at every call of f: each is a slot after the parameters in the array f reads, so the
// C source stays free of the parameters' values (one cache entry whatever --set says)
struct Derived {
  int first_slot = 0;  // the number of parameters
  std::vector<Tape> tapes;
  std::map<std::string, int, std::less<>> slot_of;  // by key: one slot for a part that recurs (f and its Jacobian)
  int slot(const std::string& key, Tape tape) {
    if (const auto it = slot_of.find(key); it != slot_of.end()) return it->second;
    tape.depth = depth_of(tape);
    tapes.push_back(std::move(tape));
    return slot_of[key] = first_slot + static_cast<int>(tapes.size()) - 1;
  }
};

// ---- the tape of a parsed formula: what the interpreter runs, and the check that it can be evaluated at all
class TapeBuilder {
 public:
  // `formula`: the user's text the tree was parsed from, where a message can point to a column; null for a
  // derivative
  TapeBuilder(const Symbols& s, Derived& derived, std::string where, const Formula* formula = nullptr)
      : s_(s), derived_(derived), where_(std::move(where)), formula_(formula) {}
  Tape build(const GiNaC::ex& e) {
    Tape tape;
    emit(e, tape);
    tape.depth = depth_of(tape);
    return tape;
  }

 private:
  struct Emitted {
    std::string key;  // a text that names the expression whatever order GiNaC keeps its terms in
    bool varying;     // depends on the state or t (else on the parameters and numbers alone)
  };

  // a part on the parameters alone, longer than one instruction, as a derived slot; else as it is
  Emitted folded(Emitted e, Tape& part) {
    if (e.varying || part.code.size() <= 1) return e;
    const int slot = derived_.slot(e.key, std::move(part));
    part = Tape{{{Op::parameter, slot, 0}}, 1};
    return {fmt::format("p{}", slot), false};
  }

  // appends e's postfix to the tape. GiNaC orders a sum's or product's operands by hash, which follows the
  // symbols' serial numbers: the operands are emitted sorted by their keys, so one formula gives one tape. A sum
  // or product of both kinds has its parameter-only operands gathered into one derived slot
  Emitted emit(const GiNaC::ex& e, Tape& tape) {
    using namespace GiNaC;
    if (is_a<numeric>(e) || is_a<constant>(e) || is_a<symbol>(e)) return emit_leaf(e, tape);
    if (is_a<add>(e) || is_a<mul>(e)) return emit_sum_or_product(e, tape);
    if (is_a<power>(e)) return emit_power(e, tape);
    if (is_a<function>(e)) return emit_function(e, tape);
    throw BadEquations(fmt::format("{}: cannot evaluate {} (a formula may use numbers, its symbols, + - * / ^ and {})", where_, text_of(e), function_list));
  }

  struct Operand {
    Emitted emitted;
    Tape part;
  };

  static Emitted push(Tape& tape, Op op, int arg, double value, std::string key, bool varying) {
    tape.code.push_back({op, arg, value});
    return Emitted{std::move(key), varying};
  }

  // a number, a constant, a variable, a parameter or the time
  Emitted emit_leaf(const GiNaC::ex& e, Tape& tape) const {
    using namespace GiNaC;
    if (is_a<numeric>(e)) {
      const numeric& n = ex_to<numeric>(e);
      if (!n.is_real()) throw BadEquations(fmt::format("{}: {} is not a real number", at("I"), text_of(e)));
      const double v = n.to_double();
      if (!std::isfinite(v)) throw BadEquations(fmt::format("{}: the number {} is beyond the range of a double", where_, text_of(e)));
      return push(tape, Op::number, 0, v, fmt::format("{:a}", v), false);
    }
    if (is_a<constant>(e)) {
      const ex value = e.evalf();
      if (!is_a<numeric>(value) || !ex_to<numeric>(value).is_real()) throw BadEquations(fmt::format("{}: the constant {} is not a real number", at(text_of(e)), text_of(e)));
      const double v = ex_to<numeric>(value).to_double();
      return push(tape, Op::number, 0, v, fmt::format("{:a}", v), false);
    }
    // a symbol, by name: one symbol a name (symbol_named), and a comparison of symbols costs a copy of each
    if (const auto it = s_.index.find(ex_to<symbol>(e).get_name()); it != s_.index.end()) {
      const auto [variable, i] = it->second;
      return variable ? push(tape, Op::variable, i, 0, fmt::format("y{}", i), true) : push(tape, Op::parameter, i, 0, fmt::format("p{}", i), false);
    }
    if (e.is_equal(s_.t)) return push(tape, Op::time, 0, 0, "t", true);
    throw BadEquations(fmt::format("{}: unknown symbol {}", where_, text_of(e)));
  }

  // the parameter-only operands of a varying sum or product as one (their sum or product, in key order), then the others
  std::vector<Operand> gather_fixed(std::vector<Operand> operands, Op op, const std::string& name) {
    Operand fixed{{name + "c(", false}, {}};
    std::vector<Operand> kept;
    int count = 0;
    for (auto& o : operands) {
      if (o.emitted.varying) {
        kept.push_back(std::move(o));
        continue;
      }
      fixed.part.code.insert(fixed.part.code.end(), o.part.code.begin(), o.part.code.end());
      fixed.emitted.key += o.emitted.key + ",";
      ++count;
    }
    if (count > 1) fixed.part.code.push_back({op, count, 0});
    fixed.emitted.key += ")";
    if (count > 0) {
      fixed.emitted = folded(fixed.emitted, fixed.part);
      kept.insert(kept.begin(), std::move(fixed));
    }
    return kept;
  }

  Emitted emit_sum_or_product(const GiNaC::ex& e, Tape& tape) {
    const Op op = GiNaC::is_a<GiNaC::add>(e) ? Op::add : Op::mul;
    std::vector<Operand> operands(e.nops());
    for (size_t i = 0; i < e.nops(); ++i) operands[i].emitted = emit(e.op(i), operands[i].part);
    std::stable_sort(operands.begin(), operands.end(), [](const Operand& a, const Operand& b) { return a.emitted.key < b.emitted.key; });
    const bool varying = std::any_of(operands.begin(), operands.end(), [](const Operand& o) { return o.emitted.varying; });
    const std::string name = op == Op::add ? "+" : "*";
    if (varying) operands = gather_fixed(std::move(operands), op, name);
    std::string key = name + "(";
    for (const auto& o : operands) {
      tape.code.insert(tape.code.end(), o.part.code.begin(), o.part.code.end());
      key += o.emitted.key + ",";
    }
    if (operands.size() > 1) tape.code.push_back({op, static_cast<int>(operands.size()), 0});
    return {key + ")", varying};
  }

  // an operand of a node, on a tape of its own; `varying` says whether any of the node's operands varies
  Operand operand(const GiNaC::ex& x, bool& varying) {
    Operand o;
    o.emitted = emit(x, o.part);
    varying = varying || o.emitted.varying;
    return o;
  }

  // an operand's tape appended, folded where the node varies and the operand is on the parameters alone; its key
  std::string append(Operand& o, bool varying, Tape& tape) {
    if (varying) o.emitted = folded(o.emitted, o.part);
    tape.code.insert(tape.code.end(), o.part.code.begin(), o.part.code.end());
    return o.emitted.key;
  }

  Emitted emit_power(const GiNaC::ex& e, Tape& tape) {
    using namespace GiNaC;
    const ex exponent = e.op(1);
    bool varying = false;
    Operand base = operand(e.op(0), varying);
    if (is_a<numeric>(exponent) && ex_to<numeric>(exponent).is_integer() && abs(ex_to<numeric>(exponent)) <= 64) {
      const int n = ex_to<numeric>(exponent).to_int();
      const std::string b = append(base, varying, tape);
      return push(tape, Op::integer_power, n, 0, fmt::format("^({},{})", b, n), varying);
    }
    if (exponent.is_equal(numeric(1, 2)) || exponent.is_equal(numeric(-1, 2))) {
      const std::string b = append(base, varying, tape);
      const Emitted root = push(tape, Op::call, function_index("sqrt"), 0, fmt::format("sqrt({})", b), varying);
      return exponent.is_equal(numeric(1, 2)) ? root : push(tape, Op::integer_power, -1, 0, fmt::format("^({},-1)", root.key), varying);
    }
    Operand power_of = operand(exponent, varying);
    const std::string b = append(base, varying, tape), x = append(power_of, varying, tape);
    return push(tape, Op::power, 0, 0, fmt::format("pow({},{})", b, x), varying);
  }

  Emitted emit_function(const GiNaC::ex& e, Tape& tape) {
    const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
    bool varying = false;
    if (name == functions2 && e.nops() == 2) {
      Operand y = operand(e.op(0), varying), x = operand(e.op(1), varying);
      const std::string ky = append(y, varying, tape), kx = append(x, varying, tape);
      return push(tape, Op::atan2, 0, 0, fmt::format("atan2({},{})", ky, kx), varying);
    }
    const int f = function_index(name);
    if (f < 0 || e.nops() != 1) throw BadEquations(fmt::format("{}: the function {} is not one a formula may call ({})", at(name), name, function_list));
    Operand argument = operand(e.op(0), varying);
    const std::string k = append(argument, varying, tape);
    return push(tape, Op::call, f, 0, fmt::format("{}({})", name, k), varying);
  }

  static int function_index(std::string_view name) {
    const auto f = std::find_if(functions1.begin(), functions1.end(), [&](const Function1& g) { return g.name == name; });
    return f == functions1.end() ? -1 : static_cast<int>(f - functions1.begin());
  }
  // where a name (a function, a constant) is in the formula's text, where that can be told
  std::string at(const std::string& name) const {
    const int column = formula_ ? column_of(formula_->text, name) : 0;
    return column > 0 ? formula_->where(column) : where_;
  }
  const Symbols& s_;
  Derived& derived_;
  std::string where_;
  const Formula* formula_;
};

// the names GiNaC's lexer reads as one symbol: a letter, then letters, digits or _ (a leading _ is a token of its
// own there, so a name starting with one could be declared and never used)
bool identifier(const std::string& name) { return std::regex_match(name, std::regex("[A-Za-z][A-Za-z0-9_]*")); }

// the shape: names, one initial value and one equation per variable, nothing else
void check_shape(const EquationsSpec& spec) {
  const size_t n = spec.variables.size();
  if (n == 0) throw BadEquations(fmt::format("{}: the system is empty (variables = [\"x\", ...] names the state)", spec.variables_where));
  if (n > max_equations)
    throw BadEquations(fmt::format("{}: {} variables, more than the {} an equations scene may hold", spec.variables_where, n, max_equations));
  std::set<std::string, std::less<>> seen;
  for (const auto& name : spec.variables) {
    if (!identifier(name)) throw BadEquations(fmt::format("{}: '{}' is not a name (a letter, then letters, digits or _)", spec.variables_where, name));
    if (reserved(name)) throw BadEquations(fmt::format("{}: the variable '{}' would shadow {}", spec.variables_where, name, name == "t" ? "the time t" : "a function or constant of the formulas"));
    if (!seen.insert(name).second) throw BadEquations(fmt::format("{}: the variable '{}' is named twice", spec.variables_where, name));
  }
  for (const auto& [name, value] : spec.parameters) {
    const std::string where = fmt::format("{}: parameters.{}", spec.file, name);
    if (!identifier(name)) throw BadEquations(fmt::format("{}: '{}' is not a name a formula can use (a letter, then letters, digits or _)", where, name));
    if (reserved(name)) throw BadEquations(fmt::format("{}: the parameter '{}' would shadow {}", where, name, name == "t" ? "the time t" : "a function or constant of the formulas"));
    if (seen.count(name)) throw BadEquations(fmt::format("{}: '{}' is both a variable and a parameter", where, name));
  }
  const auto check_cover = [&](const std::vector<Formula>& formulas, std::string_view table, bool required) {
    for (const auto& f : formulas)
      if (!seen.count(f.name))
        throw BadEquations(fmt::format("{}: an {} for '{}', which is not a variable (variables: {}){}", f.where(), table == "equations" ? "equation" : "exact solution",
                                       f.name, fmt::join(spec.variables, ", "),
                                       f.name == "energy" ? "; an energy formula goes above the first [table], as TOML puts a key under the table before it" : ""));
    if (required || !formulas.empty())
      for (const auto& v : spec.variables)
        if (std::none_of(formulas.begin(), formulas.end(), [&](const Formula& f) { return f.name == v; }))
          throw BadEquations(fmt::format("{}: the variable '{}' has no {} ([{}] {} = \"...\")", spec.file, v, table == "equations" ? "equation" : "exact solution", table, v));
  };
  check_cover(spec.equations, "equations", true);
  check_cover(spec.exact, "exact", false);
  for (const auto& [name, value] : spec.initial)
    if (!seen.count(name)) throw BadEquations(fmt::format("{}: initial.{}: '{}' is not a variable (variables: {})", spec.file, name, name, fmt::join(spec.variables, ", ")));
  for (const auto& v : spec.variables)
    if (!spec.initial.count(v)) throw BadEquations(fmt::format("{}: the variable '{}' has no initial value ([initial] {} = ...)", spec.file, v, v));

}

// the spec's parameters and initial values, with the overrides (--set) applied to a parameter or an initial value
std::pair<Params, Params> resolved_values(const EquationsSpec& spec, const Params& values) {
  Params parameters = spec.parameters, initial = spec.initial;
  for (const auto& [key, value] : values) {
    Params* target = parameters.count(key) ? &parameters : initial.count(key) ? &initial : nullptr;
    if (!target) {
      std::vector<std::string> names;
      for (const auto& [name, v] : parameters) names.push_back(name);
      throw BadParameter(key, fmt::format("unknown parameter '{}' of this equations scene (parameters: {}; variables: {})", key,
                                          names.empty() ? std::string("none") : fmt::format("{}", fmt::join(names, ", ")), fmt::join(spec.variables, ", ")));
    }
    if (!std::isfinite(value)) throw BadParameter(key, fmt::format("'{}' must be a finite number, got {}", key, value));
    (*target)[key] = value;
  }

  return {parameters, initial};
}

// ---- the model
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
  for (size_t i = 0; i < n; ++i) rhs_.push_back(TapeBuilder(s, derived, formula_of[i]->where(), formula_of[i]).build(f[i]));
  exact_.resize(spec.exact.size());  // one per variable (checked above), in the variables' order
  for (const auto& formula : spec.exact) {
    const size_t i = static_cast<size_t>(std::find(names_.begin(), names_.end(), formula.name) - names_.begin());
    exact_[i] = TapeBuilder(s, derived, formula.where(), &formula).build(parse(formula, s, false, true));
  }
  if (spec.energy) energy_ = TapeBuilder(s, derived, spec.energy->where(), &*spec.energy).build(parse(*spec.energy, s, true, false));
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
  const auto tape = [&](const Formula& f) { return TapeBuilder(s, derived, f.where(), &f).build(parse(f, s, true, true)); };
  std::set<std::string, std::less<>> seen;
  for (const EventSpec& spec_event : spec.events) {
    if (!identifier(spec_event.name))
      throw BadEquations(fmt::format("{}: '{}' is not an event's name (a letter, then letters, digits or _)", spec_event.where, spec_event.name));
    EventTapes e;
    const GiNaC::ex g = parse(spec_event.when, s, true, true);
    e.g = TapeBuilder(s, derived, spec_event.when.where(), &spec_event.when).build(g);
    // dg/dt along the solution: its partial in t, and in each variable times that variable's equation
    GiNaC::ex rate = g.diff(s.t);
    for (size_t i = 0; i < names_.size(); ++i) rate += g.diff(s.variables[i]) * work_->f[i];
    e.rate = TapeBuilder(s, derived, spec_event.when.where() + " (its rate along the solution)").build(rate);
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
      J->tapes.push_back(TapeBuilder(w.symbols, w.derived, fmt::format("{} (its derivative in {})", w.where[r], names_[c])).build(d));
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
