// Your own OdeSystem (the Lorenz system) through three stepwise methods, by name: the state at t = 1 and the
// work each took. Build: examples/cpp/CMakeLists.txt (find_package(stepwise) is all it needs).
#include <stepwise/stepwise.hpp>

#include <cstdio>
#include <vector>

struct Lorenz : stepwise::OdeSystem {
  double sigma = 10, rho = 28, beta = 8.0 / 3;
  int size() const override { return 3; }
  bool autonomous() const override { return true; }
  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    dydt << sigma * (y[1] - y[0]), y[0] * (rho - y[2]) - y[1], y[0] * y[1] - beta * y[2];
  }
};

int main() {
  const Lorenz lorenz;
  const Eigen::Vector3d y0(1, 1, 1);
  const std::vector<double> t_out{0.5, 1.0};
  for (const char* method : {"verner98", "cvode-adams", "odeint-dopri5"}) {
    const auto integrator = stepwise::make_integrator(method, stepwise::StepControl::adaptive(1e-10, 1e-12));
    const stepwise::RunResult r = integrator->integrate(lorenz, 0.0, y0, t_out);
    if (r.status != stepwise::Status::ok) return std::fprintf(stderr, "%s: %s\n", method, r.message.c_str()), 1;
    std::printf("%-14s y(1) = (%.9f, %.9f, %.9f)  %ld steps, %ld calls of f\n", method, r.y_stop[0], r.y_stop[1], r.y_stop[2],
                r.stats.steps, r.stats.rhs_evals);
  }
}
