// rodas4 and rodas5: Rosenbrock methods of our own on Hairer & Wanner's RODAS scheme (Solving ODEs II, IV.7):
// RODAS4's coefficients (their rodas.f), order 4(3) in six stages, and Di Marzo's RODAS5, order 5(4) in eight;
// both L-stable and stiffly accurate. A
// Rosenbrock method linearises each implicit stage once instead of iterating Newton to convergence: one Jacobian,
// one factorisation of W = I - gamma h J and six solves a step, with the stages in Hairer's transformed variables
//
//   W k_i = gamma h ( f(t + c_i h, y0 + sum_j a_ij k_j) + sum_j (C_ij / h) k_j + d_i h df/dt ),   i = 1..s
//   y1 = y0 + sum_j a_sj k_j + k_s,   error estimate k_s
//
// W is factorised by dense LU for a small system, by UMFPACK's sparse LU on the system's fixed pattern for a large
// one with a sparse Jacobian (solvers/sparse_newton_matrix.cpp). df/dt of a non-autonomous system is a five-point central difference in t.
#include "solvers/adaptive_step.hpp"
#include "solvers/fd_jacobian.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/newton_matrix.hpp"
#include "solvers/run_support.hpp"
#include "solvers/step_controller.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <type_traits>

namespace stepwise {
namespace {

// a stiffly accurate Rosenbrock tableau in Hairer's transformed variables: a[i][j] the stage arguments (the last
// row, with its 1, gives y1), C[i][j] the stage couplings, c and d per stage
template <int S, int D>
struct RosenbrockTableau {
  static constexpr int stages = S;
  static constexpr int dense_terms = D;
  double gamma;
  std::array<std::array<double, S - 1>, S> a, C;
  std::array<double, S> c, d;
  // dense output (Steinebach's continuous extension, as OrdinaryDiffEq.jl gives these coefficients): with
  // q_r = sum_i H[r][i] k_i, y(t0 + theta h) = (1 - theta) y0 + theta (y1 + (1 - theta)(q_1 + theta (q_2 + theta q_3 ...)))
  std::array<std::array<double, S>, D> H;
};

// RODAS4 (Hairer & Wanner, rodas.f)
constexpr RosenbrockTableau<6, 2> rodas4{
    0.25,
    {{{0, 0, 0, 0, 0},
      {1.544, 0, 0, 0, 0},
      {0.9466785280815826, 0.2557011698983284, 0, 0, 0},
      {3.314825187068521, 2.896124015972201, 0.9986419139977817, 0, 0},
      {1.221224509226641, 6.019134481288629, 12.53708332932087, -0.687886036105895, 0},
      {1.221224509226641, 6.019134481288629, 12.53708332932087, -0.687886036105895, 1}}},
    {{{0, 0, 0, 0, 0},
      {-5.6688, 0, 0, 0, 0},
      {-2.430093356833875, -0.2063599157091915, 0, 0, 0},
      {-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0, 0},
      {7.496443313967647, -10.24680431464352, -33.99990352819905, 11.7089089320616, 0},
      {8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136, -6.058818238834054}}},
    {0, 0.386, 0.21, 0.63, 1, 1},
    {0.25, -0.1043, 0.1035, -0.0362, 0, 0},
    {{{10.12623508344586, -7.487995877610167, -34.80091861555747, -7.992771707568823, 1.025137723295662, 0},
      {-0.6762803392801253, 6.087714651680015, 16.43084320892478, 24.76722511418386, -6.594389125716872, 0}}}};

// RODAS5 (Di Marzo 1993, as Hairer's group distributes it): order 5(4), 8 stages
constexpr RosenbrockTableau<8, 3> rodas5{
    0.19,
    {{{0, 0, 0, 0, 0, 0, 0},
      {2.0, 0, 0, 0, 0, 0, 0},
      {3.040894194418781, 1.041747909077569, 0, 0, 0, 0, 0},
      {2.576417536461461, 1.62208306077664, -0.9089668560264532, 0, 0, 0, 0},
      {2.760842080225597, 1.446624659844071, -0.3036980084553738, 0.2877498600325443, 0, 0, 0},
      {-14.09640773051259, 6.925207756232704, -41.47510893210728, 2.343771018586405, 24.13215229196062, 0, 0},
      {-14.09640773051259, 6.925207756232704, -41.47510893210728, 2.343771018586405, 24.13215229196062, 1, 0},
      {-14.09640773051259, 6.925207756232704, -41.47510893210728, 2.343771018586405, 24.13215229196062, 1, 1}}},
    {{{0, 0, 0, 0, 0, 0, 0},
      {-10.31323885133993, 0, 0, 0, 0, 0, 0},
      {-21.04823117650003, -7.234992135176716, 0, 0, 0, 0, 0},
      {32.22751541853323, -4.943732386540191, 19.44922031041879, 0, 0, 0, 0},
      {-20.69865579590063, -8.816374604402768, 1.260436877740897, -0.7495647613787146, 0, 0, 0},
      {-46.22004352711257, -17.49534862857472, -289.6389582892057, 93.60855400400906, 318.3822534212147, 0, 0},
      {34.20013733472935, -14.1553540271769, 57.823356409884, 25.83362985412365, 1.408950972071624, -6.551835421242162, 0},
      {42.57076742291101, -13.80770672017997, 93.98938432427124, 18.77919633714503, -31.5835918722337, -6.685968952921985, -5.810979938412932}}},
    {0, 0.38, 0.3878509998321533, 0.483971893787384, 0.457047700881958, 1, 1, 1},
    {0.19, -0.1823079225333714636, -0.319231832186874912, 0.3449828624725343, -0.377417564392089818, 0, 0, 0},
    {{{27.354592673333357, -6.925207756232857, 26.40037733258859, 0.5635230501052979, -4.699151156849391, -1.6008677469422725, -1.5306074446748028,
       -1.3929872940716344},
      {44.19024239501722, 1.3677947663381929e-13, 202.93261852171622, -35.5669339789154, -181.91095152160645, 3.4116351403665033, 2.5793540257308067,
       2.2435122582734066},
      {-44.0988150021747, -5.755396159656812e-13, -181.26175034586677, 56.99302194811676, 183.21182741427398, -7.480257918273637, -5.792426076169686,
       -5.32503859794143}}}};

// the stages on y' = z y with h = 1: R(z) = y1
template <const auto& T>
std::complex<double> stability(std::complex<double> z) {
  constexpr int S = std::remove_cvref_t<decltype(T)>::stages;
  std::array<std::complex<double>, S> k{};
  std::complex<double> arg = 1.0;
  for (int i = 0; i < S; ++i) {
    arg = 1.0;
    std::complex<double> coupling = 0.0;
    for (int j = 0; j < i; ++j) {
      arg += T.a[static_cast<size_t>(i)][static_cast<size_t>(j)] * k[static_cast<size_t>(j)];
      coupling += T.C[static_cast<size_t>(i)][static_cast<size_t>(j)] * k[static_cast<size_t>(j)];
    }
    k[static_cast<size_t>(i)] = T.gamma * (z * arg + coupling) / (1.0 - T.gamma * z);
  }
  return arg + k[S - 1];
}

// W = I - gamma h J for a system of N = 2..4 unknowns in fixed-size Eigen types: the LU and its solves unrolled
// (a dynamic-size LU's solve, two triangular passes through Eigen's general kernels, was most of what remained of
// a step on Van der Pol after the stages were fused)
template <int N>
class SmallNewtonMatrix final : public NewtonMatrix {
 public:
  explicit SmallNewtonMatrix(const CountedSystem& s) : system_(s) {}
  bool factor(double t, const Eigen::VectorXd& y, double h) override {
    jacobian_or_fd(system_, t, y, jac_);
    ++system_.stats().jac_evals;
    ++system_.stats().factorizations;
    lu_.compute(Eigen::Matrix<double, N, N>::Identity() - h * jac_);
    const auto pivots = lu_.matrixLU().diagonal();
    return pivots.allFinite() && (pivots.array() != 0).all();
  }
  void solve(const Eigen::VectorXd& r, Eigen::VectorXd& out) override {
    ++system_.stats().linear_solves;
    out = lu_.solve(Eigen::Matrix<double, N, 1>(r));
  }

 private:
  const CountedSystem& system_;
  Eigen::Matrix<double, N, N> jac_;
  Eigen::PartialPivLU<Eigen::Matrix<double, N, N>> lu_;
};

std::unique_ptr<NewtonMatrix> newton_matrix_for(const CountedSystem& s);

// sparse LU on a large system's pattern, fixed-size LU on 2 to 4 unknowns, else dense LU
std::unique_ptr<NewtonMatrix> newton_matrix_for(const CountedSystem& s) {
  if (s.as<SparseJacobian>() && s.size() >= sparse_newton_from) return make_sparse_newton_matrix(s);
  if (s.size() == 2) return std::make_unique<SmallNewtonMatrix<2>>(s);
  if (s.size() == 3) return std::make_unique<SmallNewtonMatrix<3>>(s);
  if (s.size() == 4) return std::make_unique<SmallNewtonMatrix<4>>(s);
  return make_dense_newton_matrix(s);
}

template <const auto& T>
class RosenbrockStages {
  static constexpr int stages = std::remove_cvref_t<decltype(T)>::stages;

 public:
  RosenbrockStages(const CountedSystem& s, std::string name)
      : system_(s),
        matrix_(newton_matrix_for(s)),
        k_(s.size(), stages), arg_(s.size()), f_(s.size()), r_(s.size()), dfdt_(s.size()), solved_(s.size()), name_(std::move(name)) {}

  // one step of h from (t, y) into y1; the error estimate is the last stage. False (with the call that failed)
  // where W is singular
  const std::string& name() const { return name_; }
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y1, std::string& failure) {
    if (!matrix_->factor(t, y, T.gamma * h)) {
      failure = fmt::format("{}: W = I - gamma h J singular at t = {:.9g} (h = {:.3g})", name_, t, h);
      return false;
    }
    const bool timed = !system_.autonomous();
    if (timed) {
      // df/dt by the five-point central difference: truncation (dt^4/30) f^(5), round-off ~ eps |f| / dt, both
      // ~1e-13 relative at dt = eps^(1/5) (a forward difference's 1e-8 capped rodas5's order at 4.4 on y' = y cos t,
      // the order conditions with d_i asking df/dt to the method's accuracy); four calls of f a step
      const double dt = 7.4e-4 * std::max(1.0, std::abs(t));  // eps^(1/5)
      dfdt_.setZero();
      for (const auto& [offset, weight] : {std::pair{2.0, -1.0}, {1.0, 8.0}, {-1.0, -8.0}, {-2.0, 1.0}}) {
        system_.rhs(t + offset * dt, y, f_);
        dfdt_ += weight * f_;
      }
      dfdt_ /= 12 * dt;
    }
    // the stage's argument and couplings entry by entry, over the earlier stages in one pass: on a small system
    // a vector operation per pair of stages (Eigen's loop set-up each time) was most of a step's cost (rodas5 on
    // Van der Pol: 0.65 us a step, 28 pairs)
    const Eigen::Index n = y.size();
    const double* k = k_.data();  // column j: stage j
    for (int i = 0; i < stages; ++i) {
      const auto& a_i = T.a[static_cast<size_t>(i)];
      const auto& C_i = T.C[static_cast<size_t>(i)];
      for (Eigen::Index e = 0; e < n; ++e) {
        double arg = y[e], coupling = 0;
        for (int j = 0; j < i; ++j) {
          const double kj = k[j * n + e];
          arg += a_i[static_cast<size_t>(j)] * kj;
          coupling += C_i[static_cast<size_t>(j)] * kj;
        }
        arg_[e] = arg;
        r_[e] = coupling / h;
      }
      system_.rhs(t + T.c[static_cast<size_t>(i)] * h, arg_, f_);
      const double dh = timed ? T.d[static_cast<size_t>(i)] * h : 0, gh = T.gamma * h;
      for (Eigen::Index e = 0; e < n; ++e) r_[e] = gh * (f_[e] + r_[e] + (dh != 0 ? dh * dfdt_[e] : 0.0));
      matrix_->solve(r_, solved_);
      k_.col(i) = solved_;
    }
    y1 = arg_ + k_.col(stages - 1);
    return true;
  }
  // the embedded solution's difference from y1, entry by entry
  auto estimate() const { return k_.col(stages - 1); }
  // y at t0 + theta h inside the last step from y0 to y1 (the continuous extension of the stages)
  void interpolate(double theta, const Eigen::VectorXd& y0, const Eigen::VectorXd& y1, Eigen::VectorXd& out) const {
    constexpr int D = std::remove_cvref_t<decltype(T)>::dense_terms;
    out.setZero(y0.size());
    for (int r = D - 1; r >= 0; --r) {
      // Horner: q_r + theta (q_{r+1} + ...)
      if (r < D - 1) out *= theta;
      for (int i = 0; i < stages; ++i)
        if (const double hri = T.H[static_cast<size_t>(r)][static_cast<size_t>(i)]; hri != 0) out += hri * k_.col(i);
    }
    out = (1 - theta) * y0 + theta * (y1 + (1 - theta) * out);
  }

 private:
  const CountedSystem& system_;
  std::unique_ptr<NewtonMatrix> matrix_;
  Eigen::MatrixXd k_;  // the stages, one a column
  Eigen::VectorXd arg_, f_, r_, dfdt_, solved_;
  std::string name_;
};

template <const auto& T>
class RosenbrockFixed final : public FixedStepper {
 public:
  RosenbrockFixed(const CountedSystem& s, std::string name) : stages_(s, std::move(name)) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    if (!stages_.step(t, h, y, y_next, failure)) return false;
    norm_ = y_next.lpNorm<Eigen::Infinity>();
    return true;
  }

 private:
  RosenbrockStages<T> stages_;
};

template <const auto& T>
class RosenbrockAdaptive final : public AdaptiveStepper {
 public:
  RosenbrockAdaptive(const CountedSystem& s, const StepControl& control, std::string name, int order)
      : stages_(s, std::move(name)), rtol_(control.rtol), atol_(control.atol), y1_(s.size()), controller_(order) {}

  bool step(double& t, double t_limit, double& h, Eigen::VectorXd& y, long& rejected, std::string& failure) override {
    for (;;) {
      const bool clamped = t + h >= t_limit;
      const double dt = clamped ? t_limit - t : h;
      if (!stages_.step(t, dt, y, y1_, failure)) return false;
      // the estimate against atol + rtol max(|y0|, |y1|), in the max norm (as the embedded pairs)
      const auto e = stages_.estimate();
      double err = 0;
      for (Eigen::Index i = 0; i < y.size(); ++i) err = std::max(err, std::abs(e[i]) / (atol_ + rtol_ * std::max(std::abs(y[i]), std::abs(y1_[i]))));
      if (!y1_.allFinite()) err = std::numeric_limits<double>::infinity();
      if (err <= 1) {
        last_t_ = t;
        last_h_ = dt;
        t = clamped ? t_limit : t + dt;
        y.swap(y1_);  // y1_ keeps the step's start, for dense output
        end_ = y;
        h = controller_.next_after_accepted(err, dt, h, clamped);
        return true;
      }
      ++rejected;
      if (!controller_.retry_after_rejected(err, dt, t, h, stages_.name(), failure)) return false;
    }
  }
  // within the last accepted step from its start: the interpolant (a step taken anew would overwrite the stages
  // the interpolant reads, and the outputs inside the step that an event's location re-stepped would be read off a
  // step of another length)
  bool restep(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_out) override {
    if (t == last_t_ && h <= last_h_ && y == y1_) {
      stages_.interpolate(h / last_h_, y1_, end_, y_out);
      return true;
    }
    std::string failure;
    return stages_.step(t, h, y, y_out, failure);
  }
  void reset() override { controller_.reset(); }
  bool dense() const override { return true; }
  // inside the last accepted step, from its start and end
  void interpolate(double t, Eigen::VectorXd& out) override { stages_.interpolate((t - last_t_) / last_h_, y1_, end_, out); }

 private:
  RosenbrockStages<T> stages_;
  double rtol_, atol_;
  Eigen::VectorXd y1_, end_;  // after a step: its start (y1_) and its end, for the interpolant
  PiStepController controller_;  // the estimate's order plus one: err ~ h^order
  double last_t_ = 0, last_h_ = 0;
};

template <const auto& T>
MakeIntegrator rosenbrock_integrator() {
  return [](const Method& method, const StepControl& control) -> std::unique_ptr<Integrator> {
    const std::string name(method.name);
    if (control.dt)
      return std::make_unique<FixedStepIntegrator>(method, control, [name](const CountedSystem& s) { return std::make_unique<RosenbrockFixed<T>>(s, name); });
    return std::make_unique<AdaptiveStepIntegrator>(method, control, [name, order = method.order.max](const CountedSystem& s, const StepControl& c) {
      return std::make_unique<RosenbrockAdaptive<T>>(s, c, name, order);
    });
  };
}

}  // namespace

void register_rosenbrock_methods(MethodTable& table) {
  table.add({.name = "rodas4",
             .family = Family::rosenbrock,
             .source = Source::hand_written,
             .description = "Rodas4 (Hairer & Wanner): L-stable Rosenbrock 4(3), 6 stages, one Jacobian and LU a step (dense, or sparse LU on a "
                            "sparse Jacobian), PI control",
             .order = {4, 4, "4"},
             .stepping = Stepping::fixed_or_adaptive,
             .dense = DenseMatrices::unless_sparse_jacobian,
             .make = rosenbrock_integrator<rodas4>(),
             .stability = {.R = stability<rodas4>}});
  table.add({.name = "rodas5",
             .family = Family::rosenbrock,
             .source = Source::hand_written,
             .description = "Rodas5 (Di Marzo 1993): L-stable Rosenbrock 5(4), 8 stages, one Jacobian and LU a step (dense, or sparse LU on a "
                            "sparse Jacobian), PI control",
             .order = {5, 5, "5"},
             .stepping = Stepping::fixed_or_adaptive,
             .dense = DenseMatrices::unless_sparse_jacobian,
             .make = rosenbrock_integrator<rodas5>(),
             .stability = {.R = stability<rodas5>}});
}

}  // namespace stepwise
