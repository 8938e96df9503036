// A scene's formulas through GiNaC: parsed against the system's symbols, differentiated, and turned into tapes
// (models/equations/tape.hpp) with their parameter-only parts folded into derived slots. GiNaC's types stay in
// this layer and in the model that keeps the parsed formulas until its Jacobian is made.
#pragma once

#include "models/equations.hpp"
#include "models/equations/tape.hpp"

#include <ginac/ginac.h>

#include <map>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

namespace stepwise::equations {

// GiNaC is not thread-safe (its reference counts and shared numbers are plain integers): every use of it, from
// parsing to the last expression's destruction, holds this lock (a sweep's threads may make models at once)
extern std::mutex ginac_mutex;

// one symbol per name for the life of the process: GiNaC orders a sum's terms by hash, which follows the
// symbols' serial numbers, and normalises by that order (cos(a - b) or cos(b - a)); fresh symbols for each
// parse of the same formula could make a different tree, and differently rounded code
const GiNaC::realsymbol& symbol_named(const std::string& name);

struct Symbols {
  std::vector<GiNaC::realsymbol> variables, parameters;
  GiNaC::realsymbol t = symbol_named("t");
  std::vector<std::string> variable_names, parameter_names;
  std::unordered_map<std::string, std::pair<bool, int>> index;  // name -> (a variable, else a parameter; its position)
  std::string defined;  // the names in words, for a message about an unknown one
};

// the column (from 1) of the whole word `word` in `text`, searching back from `before`; 0 if absent
int column_of(const std::string& text, const std::string& word, size_t before = std::string::npos);

// the formula's text parsed against the symbols (the variables only where allowed, t only where allowed); a
// BadEquations naming the file, line and column of what is wrong. `functions`: GiNaC's own, or a table with more
// (the PDE model's operators, read into expressions of the stencil's values)
GiNaC::ex parse(const Formula& f, const Symbols& symbols, bool allow_variables, bool allow_time,
                const GiNaC::prototype_table& functions = GiNaC::get_default_reader());

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

// an expression as GiNaC prints it
std::string text_of(const GiNaC::ex& e);

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

// the tape of a parsed formula: what the interpreter runs, and the check that it can be evaluated at all.
// `formula`: the user's text the tree was parsed from, where a message can point to a column; null for a derivative
Tape build_tape(const Symbols& s, Derived& derived, std::string where, const Formula* formula, const GiNaC::ex& e);

}  // namespace stepwise::equations
