// The seeds' three-level scheme (wave_step.hpp) as a stepper on y = (z, v), with where its levels are
// advanced left to a subclass: `wave-fd` on the CPU in double (solvers/methods/wave_fd.cpp), `gpu-wave`
// in a fragment shader in float32 (solvers/gpu/gpu_wave.cpp).
//
// The scheme carries z^{k-1} and z^k, the state carries z and v: the stepper keeps z^{k-1} itself between
// consecutive steps of one size, and reports v^{k+1} = (3 z^{k+1} - 4 z^k + z^{k-1}) / (2 dt), the
// second-order one-sided difference. At the start, and whenever the step is not the continuation of its
// last one (after an event, a shortened step, a re-step), it starts afresh as the seeds do, z^1 from the
// shape and the velocity by Taylor's expansion z^1 = z^0 + dt v^0 + dt^2/2 a^0 with
// a^0 = c^2 Lap z^0 - mu v^0, and v^1 by the trapezoid rule on dv/dt = a (velocity Verlet), in double.
#pragma once

#include <stepwise/solvers/fixed_step.hpp>
#include <stepwise/solvers/run_support.hpp>
#include <stepwise/solvers/wave_step.hpp>

namespace stepwise {

class ThreeLevelWaveStepper : public FixedStepper {
 public:
  explicit ThreeLevelWaveStepper(const CountedSystem& s);
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) final;
  void reset() final { history_ = false; }

 protected:
  // z_next = z^{k+1} on the interior from z_prev = z^{k-1} and z = z^k (n^2 each) with coefficients k;
  // `fresh`: these levels come from a restart, not from the last call (a stepper that keeps its own copy
  // of the levels must take them); false with `failure` said if it cannot
  virtual bool advance(const WaveCoefficients& k, const double* z_prev, const double* z, double* z_next, bool fresh, std::string& failure) = 0;
  const WaveGridView& grid() const { return grid_; }

 private:
  const CountedSystem& system_;
  WaveGridView grid_;
  int n_;                         // grid points per side
  Eigen::Index cells_;            // n^2
  Eigen::VectorXd z_prev_;        // z^{k-1} (n^2), valid while history_
  bool history_ = false;          // the last step's end is where the next one starts
  bool fresh_ = true;             // the levels were restarted since the last advance
  double h_ = 0, t_last_ = 0;     // the last step's size and end
  const double* last_ = nullptr;  // the buffer it wrote
  WaveCoefficients k_;            // for h_
};

}  // namespace stepwise
