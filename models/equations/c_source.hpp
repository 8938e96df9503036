// A scene's f and Jacobian as C (models/native_code.hpp compiles and caches it): the tapes' operations printed in
// their order, each value computed once across the tapes, in parts and units sized for the compiler.
#pragma once

#include "models/equations/tape.hpp"
#include "models/native_code.hpp"

#include <string>
#include <vector>

namespace stepwise::equations {

// the largest system whose compiled f a stepper calls inline (solvers/capabilities/inline_rhs.hpp)
constexpr size_t max_inline_size = 4;

// f and its Jacobian's nonzeros as C: `stepwise_rhs` and `stepwise_jacobian` (t, y, p, out), their parts
// gathered into units of about `unit_bytes`, each compiled apart and in parallel (JiTCODE's chunking)
NativeSource c_source(const std::vector<Tape>& rhs, const std::vector<Tape>& jacobian, size_t function_bytes, size_t unit_bytes);

// a size in words: "12 kB", "3.4 MB"
std::string bytes_text(size_t bytes);

}  // namespace stepwise::equations
