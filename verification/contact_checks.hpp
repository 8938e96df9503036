// A box resting on or sliding down a slope: the parameters that put it there and what its run did. Shared
// by the contact tests and the report's contact study.
#pragma once

#include <stepwise/models/model.hpp>
#include <stepwise/solvers/integrator.hpp>

namespace stepwise {

// dropped-body parameters: the default box (half-extents 0.3, 0.2, 0.1 m) released at rest, its largest
// face touching a ground of slope s (rad, about y), with Coulomb friction mu
Params box_on_slope(double slope, double friction);

struct SlopeMotion {
  double creep = 0;     // largest move along the ground (down the slope or across it) after `settled_at` (m)
  double sink = 0;      // largest move into the ground from the start (m)
  double turn = 0;      // largest rotation after `settled_at` (rad)
  double speed = 0;     // speed down the slope at the end (m/s)
};

// from the trajectory of a run of box_on_slope(slope, ...)
SlopeMotion slope_motion(const RunResult& run, double slope, double settled_at);

}  // namespace stepwise
