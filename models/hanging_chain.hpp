// A hanging chain of N masses and springs (the cloth's first check, with a known equilibrium): node 1 hangs
// from a pin at the origin by a spring, node k + 1 from node k, gravity along -y. Springs are Voigt's
// (models/springs.hpp: stiffness c, damping gamma along the spring), each node has mass m and optional
// linear drag. It starts straight down at rest length, at rest, and falls into its static equilibrium,
// which is known exactly: the spring i places from the bottom carries the i masses below it, so it is
// stretched by i m g / c, and node k (from the top) hangs at
//   y_k = -(k l + (m g / c) sum_{j=1..k} (N - j + 1)).
// State: x[i], y[i], z[i] then vx[i], vy[i], vz[i] for the N free nodes (top first); summary.json's
// final_state adds the bottom node's height y_bottom and the energy (kinetic + m g y + springs).
// f has an analytic sparse Jacobian (cvode-bdf solves with KLU).
#pragma once

#include <stepwise/models/model.hpp>

#include <vector>

namespace stepwise {

std::span<const ParamSpec> hanging_chain_params();
std::unique_ptr<Model> make_hanging_chain(const Params& params);

// the columns its trajectory writes (the state, y_bottom and the energy: summary_names), from the parameters alone;
// BadParameter for a node count the memory rule refuses
double hanging_chain_columns(const Params& params);

// the equilibrium heights y_1..y_N above
std::vector<double> chain_equilibrium(int nodes, double mass, double stiffness, double rest_length, double g);

}  // namespace stepwise
