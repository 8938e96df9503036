#include "height_field.hpp"

#include "solvers/capabilities/second_order.hpp"
#include "solvers/capabilities/imex_split.hpp"
#include "solvers/capabilities/wave_grid.hpp"

#include "particle_common.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace stepwise {

double laplacian_eigenvalue(int intervals, double spacing, int m, int n) {
  const double sm = std::sin(m * std::numbers::pi / (2 * intervals)), sn = std::sin(n * std::numbers::pi / (2 * intervals));
  return 4 / (spacing * spacing) * (sm * sm + sn * sn);
}

double wave_mode_at(int points, int m, int n, int i, int j) {
  const int intervals = points - 1;
  // the boundary exactly zero (sin(m pi) is 1e-16, not 0)
  if (i == 0 || j == 0 || i == intervals || j == intervals) return 0;
  return std::sin(m * std::numbers::pi * i / intervals) * std::sin(n * std::numbers::pi * j / intervals);
}

Eigen::VectorXd wave_mode(int points, int m, int n) {
  Eigen::VectorXd s(static_cast<Eigen::Index>(points) * points);
  for (int i = 0; i < points; ++i)
    for (int j = 0; j < points; ++j) s[i * points + j] = wave_mode_at(points, m, n, i, j);
  return s;
}

void check_water_grid(const Params& p, int points, double spacing, bool drop) {
  if (points < 3) throw BadParameter("size", fmt::format("parameter 'size' must be at least 3 grid points per side, got {}", points));
  const double side = (points - 1) * spacing;
  if (drop)
    for (const char* key : {"drop_x", "drop_y"})
      if (!(p.at(key) > 0 && p.at(key) < side))
        throw BadParameter(key, fmt::format("parameter '{}' = {} m puts the drop outside the grid (0, {} m)", key, p.at(key), side));
}

void add_raised_cosine(int points, double spacing, double x, double y, double radius, double height, double* z, const GridBlock& block) {
  // the grid's interior within the block
  for (int i = std::max(1, block.row0); i < std::min(points - 1, block.row0 + block.rows); ++i)
    for (int j = std::max(1, block.col0); j < std::min(points - 1, block.col0 + block.cols); ++j) {
      const double r = std::hypot(i * spacing - x, j * spacing - y);
      if (r < radius) z[static_cast<std::ptrdiff_t>(i - block.row0) * block.cols + (j - block.col0)] += height * (1 + std::cos(std::numbers::pi * r / radius)) / 2;
    }
}

void add_raised_cosine(int points, double spacing, double x, double y, double radius, double height, double* z) {
  add_raised_cosine(points, spacing, x, y, radius, height, z, GridBlock{0, points, 0, points});
}

std::pair<double, double> mode_amplitude(double w2, double mu, double a0, double t) {
  const double decay = a0 * std::exp(-mu * t / 2);
  const double discriminant = mu * mu / 4 - w2;
  if (discriminant < 0) {
    const double w = std::sqrt(-discriminant);
    return {decay * (std::cos(w * t) + mu / (2 * w) * std::sin(w * t)), -decay * w2 / w * std::sin(w * t)};
  }
  if (discriminant > 0) {
    const double q = std::sqrt(discriminant);
    return {decay * (std::cosh(q * t) + mu / (2 * q) * std::sinh(q * t)), -decay * w2 / q * std::sinh(q * t)};
  }
  return {decay * (1 + mu * t / 2), -decay * w2 * t};
}

namespace {

// the keys every wave scene keeps (the contract's, checked from outside), then the scene's own
std::vector<ParamSpec> with_wave_params(std::initializer_list<ParamSpec> own) {
  std::vector<ParamSpec> specs{
      {"size", 64, "", "grid points per side, boundary included (z = 0 there); at least 3", Bound::positive},
      {"spacing", 0.02, "m", "grid spacing d", Bound::positive},
      {"c", 1.0, "m/s", "wave speed", Bound::positive},
      {"mu", 0.5, "1/s", "viscous damping", Bound::nonnegative}};
  specs.insert(specs.end(), own);
  return specs;
}

// per grid point: z and v in up to 32 copies (CVODE Adams keeps about 25 vectors)
constexpr double height_field_bytes_per_point = 32 * 2 * 8;

struct Drop {
  double t = 0;          // when it falls (s)
  double x = 0, y = 0;   // centre (m)
};

class HeightField final : public Model, public SparseJacobian, public EventSource {
 public:
  enum class Scene { drop, standing, pool };

  HeightField(Scene scene, const Params& p)
      : scene_(scene),
        n_(particle_count(p, "size", p.at("size") * height_field_bytes_per_point, "grid points per side")),
        cells_(static_cast<Eigen::Index>(n_) * n_),
        grid_{n_, p.at("spacing"), p.at("c"), p.at("mu")} {
    check_water_grid(p, n_, grid_.spacing, scene == Scene::drop);
    const double side = (n_ - 1) * grid_.spacing;
    if (scene == Scene::drop) drops_.push_back({0, p.at("drop_x"), p.at("drop_y")});
    if (scene != Scene::standing) {
      radius_ = p.at("drop_radius");
      height_ = p.at("drop_height");
    }
    if (scene == Scene::standing) {
      for (const char* key : {"mode_m", "mode_n"}) {
        const double k = p.at(key);
        if (k != std::floor(k) || k < 1 || k > n_ - 2)
          throw BadParameter(key, fmt::format("parameter '{}' must be a whole number from 1 to size - 2 = {}, got {}", key, n_ - 2, k));
      }
      m_ = static_cast<int>(p.at("mode_m"));
      mode_n_ = static_cast<int>(p.at("mode_n"));
      amplitude_ = p.at("amplitude");
    }
    if (scene == Scene::pool) {
      // each drop is an event of its own, kept and watched for the whole run
      const int count = particle_count(p, "drops", sizeof(Drop) + sizeof(Event) + 64, "drops");
      std::mt19937_64 rng(particle_seed(p));
      const double span = count * p.at("interval");
      for (int k = 0; k < count; ++k) {
        Drop d;
        d.t = k == 0 ? 0.0 : span * uniform01(rng);
        d.x = side * (0.1 + 0.8 * uniform01(rng));
        d.y = side * (0.1 + 0.8 * uniform01(rng));
        drops_.push_back(d);
      }
      std::sort(drops_.begin(), drops_.end(), [](const Drop& a, const Drop& b) { return a.t < b.t; });
      events_ = block_events(GridBlock{0, n_, 0, n_});
    }
    blocks_.initial_state = [this](const GridBlock& block) { return initial_state(block); };
    blocks_.events = [this](const GridBlock& block) { return block_events(block); };
    second_order_.positions = static_cast<int>(cells_);
    second_order_.acceleration = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a) { acceleration(t, y, a); };
    // IMEX: z' = v and the Laplacian implicit (linear, constant), the damping explicit
    split_.stiff = "z' = v and the Laplacian";
    split_.linear = true;
    split_.implicit_part = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
      f.head(cells_) = y.tail(cells_);
      acceleration(t, y, f.tail(cells_), true, false);
    };
    split_.explicit_part = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
      f.head(cells_).setZero();
      acceleration(t, y, f.tail(cells_), false, true);
    };
    split_.implicit_jacobian = [this](double, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::SparseMatrix<double>& dfdy) { jacobian_of(0.0, dfdy); };
  }
  HeightField(const HeightField&) = delete;  // its capabilities hold `this`
  HeightField& operator=(const HeightField&) = delete;

  std::string_view name() const override {
    return scene_ == Scene::drop ? "water-drop" : scene_ == Scene::standing ? "standing-wave" : "pool";
  }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.water = Shapes::Water{n_, grid_.spacing, y.head(cells_)};
    return s;
  }
  int size() const override { return static_cast<int>(2 * cells_); }
  bool autonomous() const override { return true; }
  const void* capability(const std::type_info& type) const override { return offer(type, second_order_, grid_, split_, blocks_, as_part<SparseJacobian>(*this), as_part<EventSource>(*this)); }
  std::span<const Event> events() const override { return events_; }

  std::vector<std::string> state_names() const override {
    std::vector<std::string> names;
    for (const char* q : {"z", "v"})
      for (int i = 0; i < n_; ++i)
        for (int j = 0; j < n_; ++j) names.push_back(fmt::format("{}[{},{}]", q, i, j));
    return names;
  }

  Eigen::VectorXd initial_state() const override { return initial_state(GridBlock{0, n_, 0, n_}); }

  // (z, v) on one block of the grid: at rest, the standing wave's mode or the drops that fall at t = 0
  Eigen::VectorXd initial_state(const GridBlock& block) const {
    const Eigen::Index cells = static_cast<Eigen::Index>(block.rows) * block.cols;
    Eigen::VectorXd y = Eigen::VectorXd::Zero(2 * cells);
    if (scene_ == Scene::standing)
      for (int i = 0; i < block.rows; ++i)
        for (int j = 0; j < block.cols; ++j) y[i * block.cols + j] = amplitude_ * wave_mode_at(n_, m_, mode_n_, block.row0 + i, block.col0 + j);
    for (const Drop& d : drops_)
      if (d.t == 0) add_drop(d, y, block);
    return y;
  }

  // a pool's drops, each at its time an event on g = t - t_k (either direction: it fires once, going up),
  // adding its shape to a state of this block
  std::vector<Event> block_events(const GridBlock& block) const {
    std::vector<Event> events;
    if (scene_ == Scene::pool)
      for (const Drop& d : drops_)
        events.push_back(Event{"drop", 0, [t = d.t](double time, const Eigen::VectorXd&) { return time - t; },
                               [this, d, block](double, Eigen::VectorXd& y) {
                                 add_drop(d, y, block);
                                 return std::string("drop");
                               }});
    return events;
  }

  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    // the boundary's v is 0 and its acceleration 0, so it holds still
    dydt.head(cells_) = y.tail(cells_);
    acceleration(t, y, dydt.tail(cells_));
  }

  // c^2 Lap z - mu v on the interior, 0 on the boundary; the IMEX split's parts are the two terms (mu = 0
  // drops the damping, c = 0 the Laplacian: the stiff part and the rest, which add up to f exactly)
  void acceleration(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a, bool laplacian = true, bool damping = true) const {
    const double* z = y.data();
    const double* v = z + cells_;
    const double c2 = laplacian ? grid_.c * grid_.c / (grid_.spacing * grid_.spacing) : 0.0;
    const double mu = damping ? grid_.mu : 0.0;
    a.setZero();
    for (int i = 1; i < n_ - 1; ++i)
      for (int j = i * n_ + 1; j < (i + 1) * n_ - 1; ++j)
        a[j] = wave_acceleration(c2, mu, neighbour_sum(z, j, n_), z[j], v[j]);
  }

  // dz'/dv = I; dv'/dz = c^2 Lap (boundary neighbours included) and dv'/dv = -mu I on the interior rows
  void sparse_jacobian(double, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::SparseMatrix<double>& dfdy) const override {
    jacobian_of(grid_.mu, dfdy);
  }
  // the same with damping mu (0: the IMEX split's stiff part)
  void jacobian_of(double mu, Eigen::SparseMatrix<double>& dfdy) const {
    const double c2 = grid_.c * grid_.c / (grid_.spacing * grid_.spacing);
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(7 * static_cast<size_t>(cells_));
    for (Eigen::Index j = 0; j < cells_; ++j) entries.emplace_back(j, cells_ + j, 1.0);
    for (int i = 1; i < n_ - 1; ++i)
      for (int j = i * n_ + 1; j < (i + 1) * n_ - 1; ++j) {
        const Eigen::Index row = cells_ + j;
        entries.emplace_back(row, j, -4 * c2);
        for (const int nb : {j - n_, j + n_, j - 1, j + 1}) entries.emplace_back(row, nb, c2);
        entries.emplace_back(row, cells_ + j, -mu);
      }
    dfdy.resize(size(), size());
    dfdy.setFromTriplets(entries.begin(), entries.end());
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    const double* z = y.data();
    const double* v = z + cells_;
    const double d2 = grid_.spacing * grid_.spacing;
    double kinetic = 0, potential = 0;
    for (int i = 0; i < n_; ++i)
      for (int j = 0; j < n_; ++j) {
        const Eigen::Index k = static_cast<Eigen::Index>(i) * n_ + j;
        kinetic += v[k] * v[k];
        if (j + 1 < n_) potential += (z[k + 1] - z[k]) * (z[k + 1] - z[k]);
        if (i + 1 < n_) potential += (z[k + n_] - z[k]) * (z[k + n_] - z[k]);
      }
    return d2 * kinetic / 2 + grid_.c * grid_.c * potential / 2;
  }

  std::vector<std::string> summary_names() const override { return {"energy", "max_abs_z", "max_abs_v"}; }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override {
    Eigen::VectorXd s(3);
    s << *energy(y), y.head(cells_).cwiseAbs().maxCoeff(), y.tail(cells_).cwiseAbs().maxCoeff();
    return s;
  }

  // the standing wave's mode of the semi-discrete system: a'' + mu a' + c^2 lambda_mn a = 0
  bool has_exact() const override { return scene_ == Scene::standing; }
  Eigen::VectorXd exact(double t) const override {
    if (scene_ != Scene::standing) return Model::exact(t);
    const double w2 = grid_.c * grid_.c * laplacian_eigenvalue(n_ - 1, grid_.spacing, m_, mode_n_);
    const auto [a, rate] = mode_amplitude(w2, grid_.mu, amplitude_, t);
    Eigen::VectorXd y(size());
    const Eigen::VectorXd s = wave_mode(n_, m_, mode_n_);
    y.head(cells_) = a * s;
    y.tail(cells_) = rate * s;
    return y;
  }

 private:
  void add_drop(const Drop& d, Eigen::VectorXd& y, const GridBlock& block) const {
    add_raised_cosine(n_, grid_.spacing, d.x, d.y, radius_, height_, y.data(), block);
  }

  Scene scene_;
  int n_;                       // grid points per side
  Eigen::Index cells_;          // n^2
  WaveGridView grid_;
  SecondOrderView second_order_;  // y = (z, v), with the acceleration below
  ImexSplit split_;
  WaveBlocksView blocks_;         // the model on one block of the grid (a rank's, under MPI)
  std::vector<Drop> drops_;     // the drop (water-drop) or the drops in time order (pool)
  double radius_ = 0, height_ = 0;
  int m_ = 0, mode_n_ = 0;      // standing wave's mode
  double amplitude_ = 0;
  std::vector<Event> events_;   // one per pool drop
};

}  // namespace

std::span<const ParamSpec> water_drop_params() {
  static const auto specs = with_wave_params({
      {"drop_x", 0.4, "m", "drop centre, x (inside the grid)"},
      {"drop_y", 0.5, "m", "drop centre, y (inside the grid)"},
      {"drop_radius", 0.1, "m", "drop radius R", Bound::positive},
      {"drop_height", -0.02, "m", "height h of the raised cosine at the centre (negative: a dent)"}});
  return specs;
}

std::span<const ParamSpec> standing_wave_params() {
  static const auto specs = with_wave_params({
      {"mode_m", 2, "", "mode number along x, 1 <= m <= size - 2", Bound::positive},
      {"mode_n", 3, "", "mode number along y, 1 <= n <= size - 2", Bound::positive},
      {"amplitude", 0.01, "m", "initial amplitude (at rest)"}});
  return specs;
}

std::span<const ParamSpec> pool_params() {
  static const auto specs = with_wave_params({
      {"drops", 8, "", "number of drops", Bound::positive},
      {"seed", 1, "", "random seed of the drops' places and times", Bound::nonnegative},
      {"interval", 0.5, "s", "the first drop falls at t = 0, the others at seeded uniform times in [0, drops * interval)", Bound::positive},
      {"drop_radius", 0.08, "m", "drop radius R", Bound::positive},
      {"drop_height", -0.01, "m", "height h of each drop's raised cosine (negative: a dent)"}});
  return specs;
}
std::unique_ptr<Model> make_water_drop(const Params& p) { return std::make_unique<HeightField>(HeightField::Scene::drop, p); }
std::unique_ptr<Model> make_standing_wave(const Params& p) { return std::make_unique<HeightField>(HeightField::Scene::standing, p); }
std::unique_ptr<Model> make_pool(const Params& p) { return std::make_unique<HeightField>(HeightField::Scene::pool, p); }

}  // namespace stepwise
