#include "operators.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdint>

namespace stepwise::pde {
namespace {

// the operators as GiNaC functions: parsed, then expanded
DECLARE_FUNCTION_1P(dx)
DECLARE_FUNCTION_1P(dy)
DECLARE_FUNCTION_1P(dxx)
DECLARE_FUNCTION_1P(dyy)
DECLARE_FUNCTION_1P(laplace)
DECLARE_FUNCTION_2P(upwind_dx)
DECLARE_FUNCTION_2P(upwind_dy)
REGISTER_FUNCTION(dx, dummy())
REGISTER_FUNCTION(dy, dummy())
REGISTER_FUNCTION(dxx, dummy())
REGISTER_FUNCTION(dyy, dummy())
REGISTER_FUNCTION(laplace, dummy())
REGISTER_FUNCTION(upwind_dx, dummy())
REGISTER_FUNCTION(upwind_dy, dummy())

// what the expansion reads
struct Context {
  PdeSymbols* symbols = nullptr;
  const Stencil* stencil = nullptr;
  int order = 2, dimension = 1;
};
Context context;

// the field an operator is applied to: its argument must be a field's name
int field_of(const GiNaC::ex& e, const char* op) {
  const auto& s = context.symbols->symbols;
  if (GiNaC::is_a<GiNaC::symbol>(e)) {
    const std::string name = GiNaC::ex_to<GiNaC::symbol>(e).get_name();
    for (int f = 0; f < context.symbols->fields; ++f)
      if (s.variable_names[static_cast<size_t>(f * context.symbols->slots)] == name) return f;
  }
  std::vector<std::string> fields;
  for (int f = 0; f < context.symbols->fields; ++f) fields.push_back(s.variable_names[static_cast<size_t>(f * context.symbols->slots)]);
  throw OperatorError(fmt::format("{} applies to a field ({}), not to {}", op, fmt::join(fields, ", "), equations::text_of(e)), op);
}

// field f's value at offset (dx, dy) from the node
GiNaC::ex value(int f, int dx, int dy) {
  const int slot = context.stencil->slot(dx, dy);
  return context.symbols->symbols.variables[static_cast<size_t>(f * context.symbols->slots + slot)];
}

GiNaC::ex spacing(int axis) { return context.symbols->symbols.parameters[static_cast<size_t>(context.symbols->spacing + axis)]; }

void need_axis(int axis, const char* op) {
  if (axis >= context.dimension) throw OperatorError(fmt::format("{} in a 1-D scene (its [grid] has no y)", op), op);
}

// the central first and second differences along an axis, of the grid's order
GiNaC::ex first(int f, int axis, const char* op) {
  need_axis(axis, op);
  const auto at = [&](int d) { return axis == 0 ? value(f, d, 0) : value(f, 0, d); };
  if (context.order == 4) return (-at(2) + 8 * at(1) - 8 * at(-1) + at(-2)) / (12 * spacing(axis));
  return (at(1) - at(-1)) / (2 * spacing(axis));
}
GiNaC::ex second(int f, int axis, const char* op) {
  need_axis(axis, op);
  const auto at = [&](int d) { return axis == 0 ? value(f, d, 0) : value(f, 0, d); };
  if (context.order == 4) return (-at(2) + 16 * at(1) - 30 * at(0) + 16 * at(-1) - at(-2)) / (12 * GiNaC::pow(spacing(axis), 2));
  return (at(1) - 2 * at(0) + at(-1)) / GiNaC::pow(spacing(axis), 2);
}

// a d f / d axis, the one-sided difference taken against the flow: the backward one where a >= 0 (a switch, 1
// there), the forward one where a < 0
GiNaC::ex upwind(const GiNaC::ex& a, int f, int axis, const char* op) {
  need_axis(axis, op);
  PdeSymbols& s = *context.symbols;
  const auto k = static_cast<int>(s.upwind_coefficients.size());
  if (k == PdeSymbols::max_upwinds) throw OperatorError(fmt::format("more than {} upwind operators in one scene", PdeSymbols::max_upwinds), op);
  for (int w = 0; w < PdeSymbols::max_upwinds; ++w)
    if (a.has(s.symbols.variables[static_cast<size_t>(s.switches + w)]))
      throw OperatorError(fmt::format("{}'s coefficient holds another upwind operator", op), op);
  s.upwind_coefficients.push_back(a);
  const GiNaC::ex w = s.symbols.variables[static_cast<size_t>(s.switches + k)];
  const auto at = [&](int d) { return axis == 0 ? value(f, d, 0) : value(f, 0, d); };
  return a * (w * (at(0) - at(-1)) + (1 - w) * (at(1) - at(0))) / spacing(axis);
}

// every operator replaced, innermost first (an upwind coefficient may hold operators)
struct Expansion : GiNaC::map_function {
  GiNaC::ex operator()(const GiNaC::ex& e) override {
    if (!GiNaC::is_a<GiNaC::function>(e)) return e.map(*this);
    const unsigned serial = GiNaC::ex_to<GiNaC::function>(e).get_serial();
    if (serial == dx_SERIAL::serial) return first(field_of(e.op(0), "dx"), 0, "dx");
    if (serial == dy_SERIAL::serial) return first(field_of(e.op(0), "dy"), 1, "dy");
    if (serial == dxx_SERIAL::serial) return second(field_of(e.op(0), "dxx"), 0, "dxx");
    if (serial == dyy_SERIAL::serial) return second(field_of(e.op(0), "dyy"), 1, "dyy");
    if (serial == laplace_SERIAL::serial) {
      const int f = field_of(e.op(0), "laplace");
      return context.dimension == 2 ? second(f, 0, "laplace") + second(f, 1, "laplace") : second(f, 0, "laplace");
    }
    if (serial == upwind_dx_SERIAL::serial) return upwind(e.op(0).map(*this), field_of(e.op(1), "upwind_dx"), 0, "upwind_dx");
    if (serial == upwind_dy_SERIAL::serial) return upwind(e.op(0).map(*this), field_of(e.op(1), "upwind_dy"), 1, "upwind_dy");
    return e.map(*this);
  }
};

// a function's entry in GiNaC's prototype table: its serial number, shifted, with the low bit set (a real pointer's
// is clear: GiNaC's parser tells them apart so)
GiNaC::reader_func serial_entry(unsigned serial) { return reinterpret_cast<GiNaC::reader_func>((static_cast<std::uintptr_t>(serial) << 1) | 1); }

}  // namespace

const GiNaC::prototype_table& operator_table() {
  static const GiNaC::prototype_table table = [] {
    GiNaC::prototype_table t = GiNaC::get_default_reader();
    for (const auto& [name, serial] : {std::pair{"dx", dx_SERIAL::serial}, {"dy", dy_SERIAL::serial}, {"dxx", dxx_SERIAL::serial},
                                       {"dyy", dyy_SERIAL::serial}, {"laplace", laplace_SERIAL::serial}})
      t[{name, 1}] = serial_entry(serial);
    t[{"upwind_dx", 2}] = serial_entry(upwind_dx_SERIAL::serial);
    t[{"upwind_dy", 2}] = serial_entry(upwind_dy_SERIAL::serial);
    return t;
  }();
  return table;
}

GiNaC::ex expand(const GiNaC::ex& e, PdeSymbols& symbols, const Stencil& stencil, int order, int dimension) {
  context = Context{&symbols, &stencil, order, dimension};
  Expansion expansion;
  return expansion(e);
}

}  // namespace stepwise::pde
