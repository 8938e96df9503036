#include "c_source.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string_view>
#include <unordered_map>

namespace stepwise::equations {
namespace {

// x^n as integer_power (tape.hpp) computes it: the same loop
constexpr std::string_view c_integer_power =
    "static double stepwise_ipow(double x, int n) {\n"
    "  double result = 1, base = x;\n"
    "  for (unsigned m = (unsigned)(n < 0 ? -n : n); m; m >>= 1) {\n"
    "    if (m & 1u) result *= base;\n"
    "    base *= base;\n"
    "  }\n"
    "  return n < 0 ? 1 / result : result;\n"
    "}\n";

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

// x^n for a small constant n as stepwise_ipow's loop computes it, written out: the same products in the same order
// (the loop's first product, 1 times a power, is exact and left out), without the loop, so that a loop over nodes
// calling f stays one block of arithmetic the compiler can vectorise (bench_pde). A larger n calls the function
std::string c_power(const std::string& x, int n) {
  const unsigned magnitude = static_cast<unsigned>(n < 0 ? -static_cast<long>(n) : n);
  if (magnitude > 16) return fmt::format("stepwise_ipow({}, {})", x, n);
  std::string result, base = x;
  for (unsigned m = magnitude; m; m >>= 1) {
    if (m & 1u) result = result.empty() ? base : fmt::format("({} * {})", result, base);
    if (m > 1) base = fmt::format("({} * {})", base, base);
  }
  if (result.empty()) result = "(0x1p+0)";
  return n < 0 ? fmt::format("(1 / {})", result) : result;
}

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
    case Op::integer_power: return c_power(x[0], node.arg);
    case Op::call: return fmt::format("{}({})", functions1[static_cast<size_t>(node.arg)].c, x[0]);
    case Op::atan2: return fmt::format("atan2({}, {})", x[0], x[1]);
    default: return x[0];
  }
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

}  // namespace

std::string bytes_text(size_t bytes) {
  return bytes < (1u << 20) ? fmt::format("{:.0f} kB", bytes / 1e3) : fmt::format("{:.3g} MB", bytes / 1e6);
}

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

}  // namespace stepwise::equations
