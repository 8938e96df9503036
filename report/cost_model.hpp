// A run's expected CPU time, before it runs: what a sweep shares its points by (among threads and MPI ranks,
// costliest first) and estimates its time left from (report/sweep.hpp). Within a factor of a few per point,
// which the sums over a sweep average out, and corrected as the sweep goes by the seconds its points took.
#pragma once

#include <stepwise/solvers/method.hpp>

namespace stepwise {

// whether the method solves linear systems a step (dense matrices, a mass-spring system's, a spring network's prefactored one, an IMEX split's)
bool solves_newton_systems(const Method& method);

// nanoseconds of one run of `method` with `control` over t_end on a state of n entries: steps (t_end / dt,
// or for an order-p method at rtol about 10 rtol^(-1/(p+1)) per time scale) times a step's cost (a fixed part,
// and ~10 ns per entry and stage, the stages ~ the order; five times that for an implicit method's Newton
// iterations; ~15 ns more for SUNDIALS' vector operations; ~10 us more for a GPU pass's round trip through OpenGL)
double expected_run_ns(const Method& method, const StepControl& control, double t_end, double time_scale, double n);

// how much slower this machine runs the cost model's work than the one its seconds per unit were measured on
// (Progress takes 0.4 ns a unit for a group with no point done): a fixed piece of such work, rk4 on the
// pendulum over 10 000 steps through the method table, timed here (the mean of 60 runs, ~20 ms in all, so that
// a machine busy with other work shows as slower too) over its time there. 1 on that machine; ~2 with two busy
// loops beside it on two cores
double machine_slowness();

// nanoseconds of a contact method's (sequential impulses') collision work over `steps` steps among `bodies`
// bodies: every pair tested and resolved each step, ~3.4 us a pair (stack-collapse: 16 bodies, 0.87 ms a step)
double expected_contact_ns(double steps, double bodies);

// nanoseconds to draw and write one frame of a picture (render/): a fixed part (the read-back and the PNG,
// ~12 ms at 640 x 360: the full report's cheapest scenes took ~0.8 s for their 60 frames) and the scene's
// primitives, measured per kind on llvmpipe (the report's pictures table: 100 000 balls 430 ms a frame, a 128^2
// water surface with its caustic 18 ms, a cloth or a body a few ms)
double expected_frame_ns(double balls, double water_points, double other_primitives);

}  // namespace stepwise
