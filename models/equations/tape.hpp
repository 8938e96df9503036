// A scene's formulas as tapes: each formula in postfix, what the interpreter runs and the C is printed from (so
// both compute the same operations in the same order: the compiled and interpreted f agree to the bit); the
// functions a formula may call, with their values (fn) and their C (c).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace stepwise::equations {

// what a formula may call: GiNaC parses many more functions (zeta, gamma, ...); these are the ones evaluated, by
// the interpreter (fn) and in the generated C (c). Their derivatives are in the same set
struct Function1 {
  std::string_view name;
  double (*fn)(double);
  std::string_view c;
};
extern const std::array<Function1, 16> functions1;
constexpr std::string_view functions2 = "atan2";  // atan2(y, x)
extern const std::string function_list;

// names a variable or parameter may not take: the functions, the time, and GiNaC's constants
bool reserved(std::string_view name);

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
double integer_power(double x, int n);

// the formula's value at (t, y) with the parameters p, on `stack` (tape.depth values at least)
double run(const Tape& tape, double t, const double* y, const double* p, double* stack);

// the deepest the value stack of a tape goes
int depth_of(const Tape& tape);

// the scratch stack of the calling thread (a sweep's threads share one model)
double* scratch(int depth);

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

}  // namespace stepwise::equations
