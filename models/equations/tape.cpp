#include "tape.hpp"

#include <algorithm>
#include <cmath>

namespace stepwise::equations {

const std::array<Function1, 16> functions1{
    Function1{"sin", [](double x) { return std::sin(x); }, "sin"},    Function1{"cos", [](double x) { return std::cos(x); }, "cos"},
    Function1{"tan", [](double x) { return std::tan(x); }, "tan"},    Function1{"asin", [](double x) { return std::asin(x); }, "asin"},
    Function1{"acos", [](double x) { return std::acos(x); }, "acos"}, Function1{"atan", [](double x) { return std::atan(x); }, "atan"},
    Function1{"sinh", [](double x) { return std::sinh(x); }, "sinh"}, Function1{"cosh", [](double x) { return std::cosh(x); }, "cosh"},
    Function1{"tanh", [](double x) { return std::tanh(x); }, "tanh"}, Function1{"asinh", [](double x) { return std::asinh(x); }, "asinh"},
    Function1{"acosh", [](double x) { return std::acosh(x); }, "acosh"}, Function1{"atanh", [](double x) { return std::atanh(x); }, "atanh"},
    Function1{"exp", [](double x) { return std::exp(x); }, "exp"},    Function1{"log", [](double x) { return std::log(x); }, "log"},
    Function1{"sqrt", [](double x) { return std::sqrt(x); }, "sqrt"}, Function1{"abs", [](double x) { return std::abs(x); }, "fabs"},
};
const std::string function_list = "sin, cos, tan, asin, acos, atan, atan2, sinh, cosh, tanh, asinh, acosh, atanh, exp, log, sqrt, abs, pow and ^";

bool reserved(std::string_view name) {
  if (name == "t" || name == "pow" || name == functions2 || name == "Pi" || name == "I" || name == "Euler" || name == "Catalan") return true;
  return std::any_of(functions1.begin(), functions1.end(), [&](const Function1& f) { return f.name == name; });
}

double integer_power(double x, int n) {
  double result = 1, base = x;
  for (unsigned m = static_cast<unsigned>(n < 0 ? -n : n); m; m >>= 1) {
    if (m & 1u) result *= base;
    base *= base;
  }
  return n < 0 ? 1 / result : result;
}

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

double* scratch(int depth) {
  thread_local std::vector<double> stack;
  if (stack.size() < static_cast<size_t>(depth)) stack.resize(static_cast<size_t>(depth));
  return stack.data();
}

}  // namespace stepwise::equations
