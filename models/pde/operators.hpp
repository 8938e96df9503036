// The PDE operators of a scene's formulas (dx, dy, dxx, dyy, laplace, upwind_dx, upwind_dy): GiNaC functions its
// parser reads, then replaced by expressions of the stencil's values. Every call happens under
// equations::ginac_mutex.
#pragma once

#include "models/equations/symbolic.hpp"
#include "models/pde/stencil.hpp"

#include <ginac/ginac.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace stepwise::pde {

// the symbols a field's formula is written in: for each field its stencil's values (the centre named as the field),
// then x and y, then the upwind switches (1 where an upwind operator's coefficient is >= 0 at the node, else 0);
// the parameters, then the spacings hx and hy
struct PdeSymbols {
  equations::Symbols symbols;
  int fields = 0, slots = 0;          // stencil values: fields x slots, field-major
  int coordinates = 0;                // where x (and y after it) are among the variables
  int switches = 0;                   // where the upwind switches start
  static constexpr int max_upwinds = 16;
  int spacing = 0;                    // where hx (and hy after it) are among the parameters
  std::vector<GiNaC::ex> upwind_coefficients;  // the `a` of each upwind operator read so far, in order
};

// an operator applied wrongly (to a formula that is not a field, dy in a 1-D scene): its message, and the
// operator's name (to point at its column)
struct OperatorError : std::runtime_error {
  OperatorError(const std::string& message, std::string name_) : std::runtime_error(message), name(std::move(name_)) {}
  std::string name;
};

// GiNaC's functions and the operators, each read as a GiNaC function of that name (the parser's table holds a
// function's serial number, GiNaC's way); expand() then replaces them by the stencil's expressions
const GiNaC::prototype_table& operator_table();

// e with every operator replaced by its expression in the stencil's values of `symbols` (the upwind operators'
// coefficients join symbols.upwind_coefficients, each with its switch); OperatorError for one applied wrongly
GiNaC::ex expand(const GiNaC::ex& e, PdeSymbols& symbols, const Stencil& stencil, int order, int dimension);

}  // namespace stepwise::pde
