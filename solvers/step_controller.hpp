// The error-per-step controller of the hand-written embedded pairs: Gustafsson's PI controller after an
// accepted step, the elementary controller after a rejected one. k is the order of the local error estimate
// plus one (err ~ h^k as h -> 0), err the estimate scaled so that 1 is the tolerance.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>

namespace stepwise {

class PiStepController {
 public:
  static constexpr double safety = 0.9, min_factor = 0.2, max_factor = 10;

  explicit constexpr PiStepController(double k) : k_(k), alpha_(0.7 / k), beta_(0.4 / k) {}

  // the next step over the accepted one: 0.9 err^(-0.7/k) err_prev^(0.4/k), kept in [0.2, 10]; err and
  // err_prev as one exponential with the previous logarithm kept (two pow() calls were 6% of a Verner step
  // on the pendulum)
  double accepted(double err) {
    const double log_err = std::log(std::max(err, 1e-10));
    const double factor = std::clamp(safety * std::exp(beta_ * log_err_prev_ - alpha_ * log_err), min_factor, max_factor);
    log_err_prev_ = std::max(log_err, std::log(1e-4));
    return factor;
  }

  // the retry over the rejected step: the step at which err ~ h^k predicts the tolerance, times the safety
  // factor (at least 0.2); a non-finite estimate (f blew up inside the step) cuts the step fivefold
  double rejected(double err) const { return std::isfinite(err) ? std::max(min_factor, safety * std::pow(err, -1 / k_)) : min_factor; }

  void reset() { log_err_prev_ = 0; }

  // the next trial step after an accepted step of dt; `clamped`: the step was cut short to land on t_limit, and the
  // trial step h it was cut from is kept where it is the larger
  double next_after_accepted(double err, double dt, double h, bool clamped) {
    const double next = dt * accepted(err);
    return clamped ? std::max(h, next) : next;
  }

  // h for the retry after a rejected step of dt at t; false where it falls to 1e-14 (1 + |t|) or below, with
  // `failure` naming the method and the step size underflow (empty where the estimate was not finite: the
  // adaptive loop then reports the run diverged)
  bool retry_after_rejected(double err, double dt, double t, double& h, std::string_view method, std::string& failure) const {
    h = dt * rejected(err);
    if (h > 1e-14 * std::max(1.0, std::abs(t))) return true;
    failure = std::isfinite(err) ? fmt::format("{}: step size underflow (h = {:.3g}) at t = {:.9g}", method, h, t) : std::string();
    return false;
  }

 private:
  double k_, alpha_, beta_;
  double log_err_prev_ = 0;  // the last accepted error's log
};

}  // namespace stepwise
