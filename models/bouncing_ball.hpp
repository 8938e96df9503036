// A ball dropped on the ground plane (seeds: collision of a particle with a plane, signed distance
// d(p) = (p - p0) . n, response n . v2 = -eps n . v1).
//
//   y'' = -g above the plane; at y = 0 falling: vy+ = -eps vy-   (eps = restitution in [0, 1])
//
// state (y [m], vy [m/s]); parameters height h0 [m], restitution eps, g [m/s^2], rest_speed [m/s].
// Exact, with v0 = sqrt(2 g h0) the first impact speed:
//   impact times  t1 = sqrt(2 h0 / g),  t_{n+1} = t_n + 2 eps^n v0 / g
//   apex heights  eps^(2n) h0 after the n-th impact
//   without a rest threshold the impacts accumulate at t_inf = t1 (1 + eps) / (1 - eps): infinitely many
//   bounces in finite time (a Zeno point). So a rebound slower than rest_speed ends in resting contact
//   instead: the ball stays at y = 0, vy = 0, where the plane's normal force cancels gravity.
// Energy per unit mass E = vy^2 / 2 + g y.
#pragma once

#include <stepwise/models/model.hpp>

#include <vector>

namespace stepwise {

std::span<const ParamSpec> bouncing_ball_params();
std::unique_ptr<Model> make_bouncing_ball(const Params& params);

struct Bounce {
  double t;     // impact time (s)
  double apex;  // height of the following apex (m); 0 for the impact that ends in rest
  bool rest;    // this impact ends in resting contact
};

// the closed-form impacts of the bouncing ball for these parameters, at most `count` of them
std::vector<Bounce> bouncing_ball_impacts(const Params& params, int count);

}  // namespace stepwise
