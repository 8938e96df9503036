#include "symbolic.hpp"

#include <cln/number_io.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace stepwise::equations {

std::mutex ginac_mutex;

const GiNaC::realsymbol& symbol_named(const std::string& name) {
  static std::map<std::string, GiNaC::realsymbol, std::less<>> symbols;
  const auto it = symbols.find(name);
  return it != symbols.end() ? it->second : symbols.emplace(name, GiNaC::realsymbol(name)).first->second;
}


int column_of(const std::string& text, const std::string& word, size_t before) {
  if (word.empty()) return 0;
  const bool identifier = std::isalpha(static_cast<unsigned char>(word[0])) || word[0] == '_';
  for (size_t at = text.rfind(word, before); at != std::string::npos; at = at == 0 ? std::string::npos : text.rfind(word, at - 1)) {
    const auto part_of_word = [&](size_t i) { return i < text.size() && (std::isalnum(static_cast<unsigned char>(text[i])) || text[i] == '_'); };
    if (!identifier || ((at == 0 || !part_of_word(at - 1)) && !part_of_word(at + word.size()))) return static_cast<int>(at) + 1;
  }
  return 0;
}


GiNaC::ex parse(const Formula& f, const Symbols& symbols, bool allow_variables, bool allow_time, const GiNaC::prototype_table& functions) {
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
  // a call without arguments, `exp()`: GiNaC's parser takes an empty list for a variadic call, finds the function's
  // one-argument reader and reads its missing argument (a null dereference inside libginac)
  for (size_t open = text.find('('); open != std::string::npos; open = text.find('(', open + 1)) {
    const size_t inside = text.find_first_not_of(" \t", open + 1), before = text.find_last_not_of(" \t", open == 0 ? 0 : open - 1);
    const auto in_name = [&](size_t k) { return std::isalnum(static_cast<unsigned char>(text[k])) || text[k] == '_'; };
    if (open == 0 || before == std::string::npos || !in_name(before) || inside == std::string::npos || text[inside] != ')') continue;
    size_t start = before;
    while (start > 0 && in_name(start - 1)) --start;
    throw BadEquations(fmt::format("{}: {}() has no argument (a formula may call {})", f.where(static_cast<int>(start) + 1),
                                   text.substr(start, before + 1 - start), function_list));
  }
  GiNaC::symtab table;
  table["pi"] = GiNaC::Pi;  // a variable or parameter of that name takes its place
  if (allow_variables)
    for (size_t i = 0; i < symbols.variables.size(); ++i) table[symbols.variable_names[i]] = symbols.variables[i];
  for (size_t i = 0; i < symbols.parameters.size(); ++i) table[symbols.parameter_names[i]] = symbols.parameters[i];
  if (allow_time) table["t"] = symbols.t;
  GiNaC::parser reader(table, true, functions);
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
  } catch (const cln::read_number_exception& e) {
    // a number CLN cannot read ("0.2.", which GiNaC's lexer takes whole): CLN says `Illegal number syntax:
    // "+0.2.e0_17"`, the number as GiNaC handed it on (a sign before, its precision after)
    const std::string what = e.what();
    const auto open = what.find('"'), close = what.rfind('"');
    std::string number = open != std::string::npos && close > open ? what.substr(open + 1, close - open - 1) : std::string();
    if (number.starts_with('+')) number.erase(0, 1);
    if (const auto precision = number.rfind("e0_"); precision != std::string::npos) number.erase(precision);
    throw BadEquations(fmt::format("{}: '{}' is not a number", f.where(std::max(1, column_of(text, number))), number));
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
  } catch (const std::domain_error& e) {
    // GiNaC evaluates as it reads: `/0` is its pole_error, "power::eval(): division by zero"
    throw BadEquations(fmt::format("{}: {}", f.where(), e.what()));
  }
}

std::string text_of(const GiNaC::ex& e) {
  std::ostringstream text;
  text << e;
  return text.str();
}

namespace {

class TapeBuilder {
 public:
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
  // (its key stays its content's: a slot's number follows the order the parts are met in, which is GiNaC's, and
  // GiNaC orders a sum's terms by hashes seeded from the addresses of type names, so a key naming the slot would
  // sort a sum's terms differently from run to run: D u(x+1)/h^2 + ... rounded two ways, seen on the PDE model)
  Emitted folded(Emitted e, Tape& part) {
    if (e.varying || part.code.size() <= 1) return e;
    const int slot = derived_.slot(e.key, std::move(part));
    part = Tape{{{Op::parameter, slot, 0}}, 1};
    return {"d" + e.key, false};
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

}  // namespace

Tape build_tape(const Symbols& s, Derived& derived, std::string where, const Formula* formula, const GiNaC::ex& e) {
  return TapeBuilder(s, derived, std::move(where), formula).build(e);
}

}  // namespace stepwise::equations
