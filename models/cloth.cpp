#include "cloth.hpp"

#include "kernels/wind.hpp"

#include "solvers/capabilities/second_order.hpp"
#include "solvers/capabilities/mass_spring.hpp"
#include "solvers/capabilities/cloth_grid.hpp"
#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/capabilities/imex_split.hpp"

#include "membrane.hpp"
#include "particle_common.hpp"
#include "plane_collision.hpp"
#include "springs.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <numbers>

namespace stepwise {

namespace {

// the defaults are the seeds' flag (scenes/flag.toml): 32 x 32, four corners pinned, a gusting wind face-on
std::span<const ParamSpec> parameter_table() {
  static const ParamSpec table[] = {
      {"rows", 32, "", "grid nodes down the sheet (at least 2)", Bound::positive},
      {"columns", 32, "", "grid nodes across the sheet (at least 2)", Bound::positive},
      {"width", 1.0, "m", "sheet width (along x)", Bound::positive},
      {"height", 1.0, "m", "sheet height (down the sheet: -y when vertical, +z when horizontal)", Bound::positive},
      {"mass", 0.5, "kg", "mass of the whole sheet, shared equally by its nodes", Bound::positive},
      {"stiffness", 200.0, "N/m", "structural spring constant c", Bound::nonnegative},
      {"shear_stiffness", 100.0, "N/m", "shear (diagonal) spring constant", Bound::nonnegative},
      {"bend_stiffness", 20.0, "N/m", "bend (two apart) spring constant", Bound::nonnegative},
      {"structural", 1, "", "structural springs on (1) or off (0)", Bound::flag},
      {"shear", 1, "", "shear springs on (1) or off (0)", Bound::flag},
      {"bend", 1, "", "bend springs on (1) or off (0)", Bound::flag},
      {"damping", 0.02, "N s/m", "Voigt damping gamma along every spring", Bound::nonnegative},
      {"drag", 0.05, "1/s", "linear drag of each node per unit mass", Bound::nonnegative},
      {"g", 9.81, "m/s^2", "gravitational acceleration, along -y", Bound::nonnegative},
      {"wind_x", 0, "m/s", "wind velocity w0, x", Bound::finite},
      {"wind_y", 0, "m/s", "wind velocity w0, y", Bound::finite},
      {"wind_z", 3, "m/s", "wind velocity w0, z", Bound::finite},
      {"wind_coefficient", 0.5, "N s/m^3", "force per unit area per unit normal relative speed k_w", Bound::nonnegative},
      {"gust_amplitude", 0.5, "", "gust A: the wind is w0 (1 + A sin(2 pi f t))", Bound::finite},
      {"gust_frequency", 0.5, "Hz", "gust frequency f", Bound::nonnegative},
      {"pick_row", -1, "", "row of the picked node pulled by the pick force (-1: none)", Bound::finite},
      {"pick_column", -1, "", "column of the picked node", Bound::finite},
      {"pick_fx", 0, "N", "pick force, x", Bound::finite},
      {"pick_fy", 0, "N", "pick force, y", Bound::finite},
      {"pick_fz", 0, "N", "pick force, z", Bound::finite},
      {"pin_corners", 1, "", "pin the four corners (the seeds' flag)", Bound::flag},
      {"pin_top_corners", 0, "", "pin the two top (row 0) corners (a hanging sheet)", Bound::flag},
      {"pin_left_edge", 0, "", "pin the left (column 0) edge (a flag on a pole)", Bound::flag},
      {"pin_top_edge", 0, "", "pin the whole top (row 0) edge (a sheet held along a line, where plane elasticity is not singular)", Bound::flag},
      {"clamp_left_edge", 0, "", "pin the first two columns, so that the left edge can neither move nor turn (a clamped plate)", Bound::flag},
      {"pin_row", -1, "", "row of one more pinned node (-1: none)", Bound::finite},
      {"pin_column", -1, "", "column of that pinned node", Bound::finite},
      {"horizontal", 0, "", "sheet starts horizontal in the x-z plane (1) or vertical in x-y (0)", Bound::flag},
      {"elevation", 0, "m", "height y of the top row (vertical) or of the sheet (horizontal)", Bound::finite},
      {"sphere_radius", 0, "m", "radius of a fixed sphere the cloth collides with (0: none)", Bound::nonnegative},
      {"sphere_x", 0, "m", "sphere centre, x", Bound::finite},
      {"sphere_y", 0, "m", "sphere centre, y", Bound::finite},
      {"sphere_z", 0, "m", "sphere centre, z", Bound::finite},
      {"ground", 0, "", "collide with the ground plane y = ground_y (1) or not (0)", Bound::flag},
      {"ground_y", -2, "m", "height of the ground plane", Bound::finite},
      {"friction", 0.3, "", "Coulomb friction on the sphere and the ground", Bound::nonnegative},
      {"continuum", 0, "", "the sheet's elastic forces: springs (0), or the continuum (1): a St. Venant-Kirchhoff membrane and "
       "quadratic bending on the grid's triangles (models/membrane.hpp), with E, nu, thickness and density in place of the "
       "springs' constants, `mass` and `damping`", Bound::flag},
      {"E", 5e5, "Pa", "Young's modulus of the continuum sheet", Bound::positive},
      {"nu", 0.3, "", "Poisson's ratio of the continuum sheet, in (-1, 0.5)", Bound::finite},
      {"thickness", 5e-4, "m", "thickness of the continuum sheet", Bound::positive},
      {"density", 1000, "kg/m^3", "density of the continuum sheet; its node masses are lumped from its triangles", Bound::positive},
      {"rayleigh_beta", 0, "s", "the continuum's damping of its own: a viscous stress in the membrane, the elastic law times beta on "
       "the strain rate (-beta K v in the linear limit: Rayleigh's stiffness-proportional damping; `drag` is the mass-proportional "
       "part); gamma / stiffness matches a spring's Voigt damping", Bound::nonnegative},
  };
  return table;
}

// a whole number in [low, high], or -1 when `optional` allows none; BadParameter naming the key otherwise
int grid_index(const Params& p, const char* key, int low, int high, bool optional) {
  const double value = p.at(key);
  if (optional && value == -1) return -1;
  if (value != std::floor(value) || value < low || value > high)
    throw BadParameter(key, fmt::format("parameter '{}' = {} must be a whole number from {} to {}{} (the grid's size)", key, value, low,
                                        high, optional ? ", or -1 for none" : ""));
  return static_cast<int>(value);
}

Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

class Cloth final : public Model, public SparseJacobian, public Projection {
 public:
  Cloth(const Params& p, std::span<const GridNode> pins)
      : rows_(grid_size(p, "rows")),
        columns_(grid_size(p, "columns")),
        g_(p.at("g")),
        drag_(p.at("drag")),
        wind_(p.at("wind_x"), p.at("wind_y"), p.at("wind_z")),
        wind_k_(p.at("wind_coefficient")),
        gust_(p.at("gust_amplitude")),
        gust_frequency_(p.at("gust_frequency")),
        pick_force_(p.at("pick_fx"), p.at("pick_fy"), p.at("pick_fz")),
        sphere_centre_(p.at("sphere_x"), p.at("sphere_y"), p.at("sphere_z")),
        sphere_radius_(p.at("sphere_radius")),
        ground_(p.at("ground") == 1),
        ground_y_(p.at("ground_y")),
        friction_(p.at("friction")),
        continuum_(p.at("continuum") == 1),
        material_(p.at("E"), p.at("nu"), p.at("thickness")),
        beta_(p.at("rayleigh_beta")) {
    if (!(p.at("nu") > -1 && p.at("nu") < 0.5))
      throw BadParameter("nu", fmt::format("parameter 'nu' = {} must be in (-1, 0.5): 0.5 is an incompressible sheet and -1 one with no "
                                           "resistance to area change, where the plane-stress Lame parameters are infinite",
                                           p.at("nu")));
    // the sheet's whole run, its springs and the default implicit Euler's sparse Cholesky factor, by node:
    // 16 KiB, the peak resident size measured here at 256 x 256 (1.04 GiB) and 384 x 384 (2.35 GiB) nodes; the
    // continuum's 22 KiB (its elements, and bending stencils coupling nodes two apart: 1.43 GB at 256 x 256)
    particle_grid(p, "rows", "columns", (p.at("continuum") == 1 ? 22 : 16) * 1024, "nodes");
    const int nodes = rows_ * columns_;
    node_mass_ = p.at("mass") / nodes;
    const double dx = p.at("width") / (columns_ - 1), dz = p.at("height") / (rows_ - 1);
    place_nodes(p, dx, dz);
    number_free_nodes(p, pins);
    const int picked_node = pick_node(p);
    if (!continuum_) add_springs(p);
    for (int r = 0; r + 1 < rows_; ++r)
      for (int c = 0; c + 1 < columns_; ++c) {
        const int k = r * columns_ + c;
        triangles_.push_back({k, k + columns_, k + 1});
        triangles_.push_back({k + columns_, k + columns_ + 1, k + 1});
      }
    view_.nodes = free_;
    view_.mass.assign(free_, node_mass_);
    if (continuum_) set_up_continuum(dx, dz, p.at("density"));
    mass3_.resize(3 * free_);
    for (int i = 0; i < free_; ++i) mass3_.segment<3>(3 * i).setConstant(view_.mass[i]);
    grid_ = ClothGridView{rows_, columns_, rest_, free_index_, dx, dz,
                          {p.at("stiffness"), p.at("shear_stiffness"), p.at("bend_stiffness")},
                          {p.at("structural") == 1, p.at("shear") == 1, p.at("bend") == 1}, p.at("damping"), node_mass_, drag_, g_, wind_, wind_k_,
                          gust_, gust_frequency_, picked_node, pick_force_, sphere_radius_, sphere_centre_, ground_, ground_y_, friction_};
    set_up_jacobian_pattern();
    second_order_.positions = 3 * free_;
    second_order_.acceleration = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a) { acceleration(t, y, a); };
    view_.force_jacobians = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, bool definite, Eigen::SparseMatrix<double>& dfdx,
                                   Eigen::SparseMatrix<double>& dfdv) { force_jacobians(t, y, definite, dfdx, dfdv); };
    view_.potential = [this](const Eigen::Ref<const Eigen::VectorXd>& x) { return elastic_energy(x.data()); };
    view_.elastic_force = [this](const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) {
      // the springs at rest relative to each other: their Voigt damping is zero
      const Eigen::VectorXd at_rest = Eigen::VectorXd::Zero(3 * free_);
      add_elastic_forces(x.data(), at_rest.data(), f);
    };
    view_.elastic_jacobian = [this](const Eigen::Ref<const Eigen::VectorXd>& x, bool definite, Eigen::SparseMatrix<double>& dfdx) {
      pattern_->zero(dfdx);
      add_spring_force_jacobians(view_.springs, spring_slots_, x.data(), nullptr, definite, dfdx, nullptr);
      if (continuum_) add_continuum_force_jacobian(x.data(), definite, dfdx);
    };
    set_up_vertex_terms();
    view_.vertex_elastic = [this](int node, const Eigen::Ref<const Eigen::VectorXd>& x, bool definite, bool derivatives, VertexElastic& out) {
      vertex_elastic(node, x.data(), definite, derivatives, out);
    };
    set_up_split();
    if (!continuum_) read_springs_as_constraints();
  }

 private:
  // the grid's rest positions: hanging from its top row in the x-y plane, or lying flat in the x-z plane
  void place_nodes(const Params& p, double dx, double dz) {
    const bool horizontal = p.at("horizontal") == 1;
    for (int r = 0; r < rows_; ++r)
      for (int c = 0; c < columns_; ++c) {
        const double across = c * dx - p.at("width") / 2;
        rest_.push_back(horizontal ? Eigen::Vector3d(across, p.at("elevation"), r * dz - p.at("height") / 2)
                                   : Eigen::Vector3d(across, p.at("elevation") - r * dz, 0));
      }
  }

  // the pins (by parameter and by the scene's list), then the free nodes' numbering
  void number_free_nodes(const Params& p, std::span<const GridNode> pins) {
    const int nodes = rows_ * columns_;
    std::vector<bool> pinned(nodes, false);
    const auto pin = [&](int r, int c) { pinned[r * columns_ + c] = true; };
    if (p.at("pin_corners") == 1) {
      pin(0, 0), pin(0, columns_ - 1), pin(rows_ - 1, 0), pin(rows_ - 1, columns_ - 1);
    }
    if (p.at("pin_top_corners") == 1) pin(0, 0), pin(0, columns_ - 1);
    pole_ = p.at("pin_left_edge") == 1;
    if (pole_)
      for (int r = 0; r < rows_; ++r) pin(r, 0);
    if (p.at("pin_top_edge") == 1)
      for (int c = 0; c < columns_; ++c) pin(0, c);
    if (p.at("clamp_left_edge") == 1)
      for (int r = 0; r < rows_; ++r) pin(r, 0), pin(r, 1);
    const int pin_row = grid_index(p, "pin_row", 0, rows_ - 1, true), pin_column = grid_index(p, "pin_column", 0, columns_ - 1, true);
    if ((pin_row < 0) != (pin_column < 0))
      throw BadParameter(pin_row < 0 ? "pin_row" : "pin_column", "parameters 'pin_row' and 'pin_column' go together: give both or neither");
    if (pin_row >= 0) pin(pin_row, pin_column);
    for (const auto& [r, c] : pins) {
      if (r < 0 || r >= rows_ || c < 0 || c >= columns_)
        throw BadParameter("pins", fmt::format("node [{}, {}] is off the {} x {} grid (rows 0..{}, columns 0..{})", r, c, rows_, columns_,
                                               rows_ - 1, columns_ - 1));
      pin(r, c);
    }
    free_index_.assign(nodes, -1);
    for (int k = 0; k < nodes; ++k)
      if (!pinned[k]) {
        free_index_[k] = free_;
        grid_node_.push_back(k);
        ++free_;
      }
    if (free_ == 0) throw BadParameter("pin_corners", "every node of the cloth is pinned: nothing moves");
  }

  // the node the pick force pulls (its free index in picked_), as a grid node; -1 for none
  int pick_node(const Params& p) {
    const int pick_row = grid_index(p, "pick_row", 0, rows_ - 1, true), pick_column = grid_index(p, "pick_column", 0, columns_ - 1, true);
    if ((pick_row < 0) != (pick_column < 0))
      throw BadParameter(pick_row < 0 ? "pick_row" : "pick_column", "parameters 'pick_row' and 'pick_column' go together: give both or neither");
    picked_ = pick_row >= 0 ? free_index_[pick_row * columns_ + pick_column] : -1;
    return pick_row >= 0 ? pick_row * columns_ + pick_column : -1;
  }

  // the springs, family by family (offsets in rows and columns), each once
  void add_springs(const Params& p) {
    const double gamma = p.at("damping");
    const auto join = [&](int r, int c, int dr, int dc, double stiffness) {
      const int r2 = r + dr, c2 = c + dc;
      if (r2 < 0 || r2 >= rows_ || c2 < 0 || c2 >= columns_) return;
      const int a = r * columns_ + c, b = r2 * columns_ + c2;
      const double rest = (rest_[b] - rest_[a]).norm();
      const int fa = free_index_[a], fb = free_index_[b];
      if (fa < 0 && fb < 0) return;
      if (fa < 0) view_.springs.push_back(Spring{-1, fb, rest, stiffness, gamma, rest_[a]});
      else if (fb < 0) view_.springs.push_back(Spring{-1, fa, rest, stiffness, gamma, rest_[b]});
      else view_.springs.push_back(Spring{fa, fb, rest, stiffness, gamma});
    };
    for (int r = 0; r < rows_; ++r)
      for (int c = 0; c < columns_; ++c) {
        if (p.at("structural") == 1) join(r, c, 0, 1, p.at("stiffness")), join(r, c, 1, 0, p.at("stiffness"));
        if (p.at("shear") == 1) join(r, c, 1, 1, p.at("shear_stiffness")), join(r, c, 1, -1, p.at("shear_stiffness"));
        if (p.at("bend") == 1) join(r, c, 0, 2, p.at("bend_stiffness")), join(r, c, 2, 0, p.at("bend_stiffness"));
      }
  }

  // the Jacobians' block pattern (springs, bending stencils, and triangles where wind or the continuum couples
  // their nodes) and each term's slots in it
  void set_up_jacobian_pattern() {
    const bool triangles = wind_k_ > 0 || continuum_;
    const auto both_free = [&](int a, int b) { return free_index_[a] >= 0 && free_index_[b] >= 0; };
    auto pairs = spring_pairs(view_.springs);
    for (const auto& s : stencils_)
      for (size_t i = 0; i < s.node.size(); ++i)
        for (size_t j = i + 1; j < s.node.size(); ++j)
          if (both_free(s.node[i], s.node[j])) pairs.emplace_back(free_index_[s.node[i]], free_index_[s.node[j]]);
    if (triangles)
      for (const auto& tri : triangles_)
        for (int i = 0; i < 3; ++i)
          for (int j = i + 1; j < 3; ++j)
            if (both_free(tri[i], tri[j])) pairs.emplace_back(free_index_[tri[i]], free_index_[tri[j]]);
    pattern_ = std::make_unique<BlockPattern>(free_, pairs);
    spring_slots_ = spring_slots(view_.springs, *pattern_);
    for (int i = 0; i < free_; ++i) diagonal_slots_.push_back(pattern_->slot(i, i));
    if (triangles)
      for (const auto& tri : triangles_) {
        std::array<BlockPattern::Slot, 9> slots{};
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            if (both_free(tri[i], tri[j])) slots[3 * i + j] = pattern_->slot(free_index_[tri[i]], free_index_[tri[j]]);
        triangle_slots_.push_back(slots);
      }
    // the bending's force Jacobian, -D B between free nodes (B the stencils summed over the grid), is constant: its
    // values on the pattern, once
    if (stencils_.empty()) return;
    Eigen::SparseMatrix<double> bending;
    pattern_->zero(bending);
    for (Eigen::Index k = 0; k < bending_nodes_.outerSize(); ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(bending_nodes_, k); it; ++it)
        if (both_free(static_cast<int>(it.row()), static_cast<int>(it.col())))
          pattern_->add(bending, free_index_[it.row()], free_index_[it.col()], -material_.bending * it.value() * Eigen::Matrix3d::Identity());
    bending_jacobian_ = Eigen::Map<const Eigen::VectorXd>(bending.valuePtr(), bending.nonZeros());
  }

 public:
  Cloth(const Cloth&) = delete;  // its capabilities hold `this`
  Cloth& operator=(const Cloth&) = delete;

  std::string_view name() const override { return "cloth"; }
  // the sheet (pinned nodes where they were pinned), the sphere, the ground, and the pole along a pinned left edge
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    TriangleMesh sheet;
    sheet.vertices.resize(static_cast<Eigen::Index>(rest_.size()), 3);
    for (size_t k = 0; k < rest_.size(); ++k) sheet.vertices.row(static_cast<Eigen::Index>(k)) = corner(static_cast<int>(k), y.data()).transpose();
    sheet.faces.resize(static_cast<Eigen::Index>(triangles_.size()), 3);
    for (size_t f = 0; f < triangles_.size(); ++f)
      sheet.faces.row(static_cast<Eigen::Index>(f)) << triangles_[f][0], triangles_[f][1], triangles_[f][2];
    s.surfaces.push_back(std::move(sheet));
    if (sphere_radius_ > 0) s.balls.push_back({sphere_centre_, sphere_radius_, false});
    if (ground_) s.ground = make_plane(Eigen::Vector3d(0, ground_y_, 0), Eigen::Vector3d::UnitY());
    if (pole_) {
      s.lines.emplace_back();
      for (int r = 0; r < rows_; ++r) s.lines.back().push_back(rest_[static_cast<size_t>(r * columns_)]);
    }
    s.up = Eigen::Vector3d::UnitY();
    return s;
  }
  int size() const override { return 6 * free_; }
  bool autonomous() const override { return gust_ == 0 || wind_k_ == 0; }
  // the continuum sheet is no network of springs: the GPU pass, the position-based methods and the prefactored
  // local/global method, which step springs, do not apply to it
  // the projection onto the sphere and the ground where the sheet has them
  const void* capability(const std::type_info& type) const override {
    if (type == typeid(Projection)) return sphere_radius_ > 0 || ground_ ? &as_part<Projection>(*this) : nullptr;
    if (type == typeid(SparseJacobian)) return &as_part<SparseJacobian>(*this);
    if (continuum_) return offer(type, second_order_, view_, split_);
    return offer(type, second_order_, view_, network_, grid_, split_, constraints_);
  }
  std::vector<std::string> state_names() const override { return particle_state_names(free_); }
  Eigen::VectorXd initial_state() const override {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(size());
    for (int i = 0; i < free_; ++i) y.segment<3>(3 * i) = rest_[grid_node_[i]];
    return y;
  }

  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    dydt.head(3 * free_) = y.tail(3 * free_);
    acceleration(t, y, dydt.tail(3 * free_));
  }
  // which forces an acceleration or Jacobian includes: all of them, or one side of the IMEX split (the
  // springs and their damping, stiff; wind, the picked node's pull, drag and gravity, not)
  enum class Forces { all, stiff, nonstiff };

  void acceleration(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a, Forces forces = Forces::all) const {
    const double* x = y.data();
    const double* v = y.data() + 3 * free_;
    a.setZero();
    if (forces != Forces::nonstiff) add_elastic_forces(x, v, a);
    if (forces == Forces::stiff) {
      a.array() /= mass3_.array();
      return;
    }
    if (wind_k_ > 0) {
      const Eigen::Vector3d w = wind_at(t);
      for (const auto& tri : triangles_) {
        const Eigen::Vector3d share = wind_share(area_vector(tri, x), mean_velocity(tri, v), w, wind_k_);
        for (const int k : tri)
          if (free_index_[k] >= 0) a.segment<3>(3 * free_index_[k]) += share;
      }
    }
    if (picked_ >= 0) a.segment<3>(3 * picked_) += pick_force_;
    a.array() /= mass3_.array();
    a -= drag_ * y.tail(3 * free_);
    for (int i = 0; i < free_; ++i) a[3 * i + 1] -= g_;
  }

  // the force Jacobians of all forces or of the stiff ones (Forces::nonstiff is not asked for), on one pattern
  void force_jacobians(double t, const Eigen::Ref<const Eigen::VectorXd>& y, bool definite, Eigen::SparseMatrix<double>& dfdx,
                       Eigen::SparseMatrix<double>& dfdv, Forces forces = Forces::all) const {
    const double* x = y.data();
    const double* v = y.data() + 3 * free_;
    pattern_->zero(dfdx);
    pattern_->zero(dfdv);
    if (forces != Forces::stiff)
      for (int i = 0; i < free_; ++i) BlockPattern::add(dfdv, diagonal_slots_[i], -view_.mass[i] * drag_ * Eigen::Matrix3d::Identity());
    add_spring_force_jacobians(view_.springs, spring_slots_, x, v, definite, dfdx, &dfdv);
    if (continuum_) add_continuum_force_jacobian(x, definite, dfdx);
    if (continuum_ && beta_ > 0) add_continuum_damping_jacobians(x, v, definite, dfdx, dfdv);
    if (forces == Forces::stiff || wind_k_ == 0) return;
    const Eigen::Vector3d w = wind_at(t);
    for (size_t k = 0; k < triangles_.size(); ++k) {
      const auto& tri = triangles_[k];
      const Eigen::Vector3d n = area_vector(tri, x);
      const double area = n.norm();
      const Eigen::Matrix3d by_velocity = -wind_k_ / (9 * area) * n * n.transpose();  // corner force by one corner's velocity
      std::array<Eigen::Matrix3d, 3> by_position;  // the corner force (a third of F) by each corner's position
      if (!definite) {
        const Eigen::Vector3d u = w - mean_velocity(tri, v);
        const double flow = u.dot(n);
        const Eigen::Matrix3d dg = (n * u.transpose() + flow * Eigen::Matrix3d::Identity()) / area - flow * n * n.transpose() / (area * area * area);
        const Eigen::Vector3d e1 = corner(tri[1], x) - corner(tri[0], x), e2 = corner(tri[2], x) - corner(tri[0], x);
        const Eigen::Matrix3d d1 = -cross_matrix(e2) / 2, d2 = cross_matrix(e1) / 2;
        by_position = {wind_k_ / 3 * dg * (-d1 - d2), wind_k_ / 3 * dg * d1, wind_k_ / 3 * dg * d2};
      }
      for (int i = 0; i < 3; ++i) {
        if (free_index_[tri[i]] < 0) continue;
        for (int j = 0; j < 3; ++j) {
          if (free_index_[tri[j]] < 0) continue;
          BlockPattern::add(dfdv, triangle_slots_[k][3 * i + j], by_velocity);
          if (!definite) BlockPattern::add(dfdx, triangle_slots_[k][3 * i + j], by_position[j]);
        }
      }
    }
  }

  void sparse_jacobian(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& dfdy) const override {
    Eigen::SparseMatrix<double> dfdx, dfdv;
    force_jacobians(t, y, false, dfdx, dfdv);
    mass_spring_jacobian(dfdx, dfdv, view_.mass, dfdy);
  }

  // nodes inside the sphere or below the ground back onto its surface, their approach stopped
  void project(Eigen::Ref<Eigen::VectorXd> y) const override {
    const auto contact = [&](int i, const Eigen::Vector3d& surface, const Eigen::Vector3d& normal) {
      y.segment<3>(3 * i) = surface;
      auto v = y.segment<3>(3 * (free_ + i));
      if (v.dot(normal) < 0) v = collision_response(Plane{surface, normal}, v, 0, friction_);
    };
    for (int i = 0; i < free_; ++i) {
      const Eigen::Vector3d offset = y.segment<3>(3 * i) - sphere_centre_;
      const double distance = offset.norm();
      if (sphere_radius_ > 0 && distance < sphere_radius_ && distance > 0) {
        const Eigen::Vector3d normal = offset / distance;
        contact(i, sphere_centre_ + sphere_radius_ * normal, normal);
      }
      if (ground_ && y[3 * i + 1] < ground_y_) {
        Eigen::Vector3d surface = y.segment<3>(3 * i);
        surface.y() = ground_y_;
        contact(i, surface, Eigen::Vector3d::UnitY());
      }
    }
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    double e = kinetic_energy(y) + elastic_energy(y.data());
    for (int i = 0; i < free_; ++i) e += view_.mass[i] * g_ * y[3 * i + 1];
    if (picked_ >= 0) e -= pick_force_.dot(y.segment<3>(3 * picked_));
    return e;
  }

  std::vector<std::string> summary_names() const override {
    return {"energy", "kinetic_energy", "x_mean", "y_mean", "z_mean", "y_min", "max_stretch"};
  }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override {
    const Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>> x(y.data(), 3, free_);
    double stretch = 0;
    for (const Spring& s : view_.springs) {
      const Eigen::Vector3d from = s.a < 0 ? s.anchor : Eigen::Vector3d(x.col(s.a));
      stretch = std::max(stretch, (x.col(s.b) - from).norm() / s.rest - 1);
    }
    // the continuum's: each element's largest principal stretch, the root of F^T F's larger eigenvalue
    for (const MembraneElement& e : elements_) {
      const Eigen::Matrix<double, 3, 2> F = deformation_gradient(e, corners(e.node, y.data()));
      stretch = std::max(stretch, std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(F.transpose() * F).eigenvalues().maxCoeff()) - 1);
    }
    Eigen::VectorXd out(7);
    out << *energy(y), kinetic_energy(y), x.row(0).mean(), x.row(1).mean(), x.row(2).mean(),
        x.row(1).minCoeff(), stretch;
    return out;
  }

 private:
  // IMEX: x' = v and the springs' forces implicit, the rest explicit
  void set_up_split() {
    split_.stiff = continuum_ ? "the membrane and bending forces" : "the springs and their damping";
    split_.implicit_part = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
      f.head(3 * free_) = y.tail(3 * free_);
      acceleration(t, y, f.tail(3 * free_), Forces::stiff);
    };
    split_.explicit_part = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
      f.head(3 * free_).setZero();
      acceleration(t, y, f.tail(3 * free_), Forces::nonstiff);
    };
    split_.implicit_jacobian = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& dfdy) {
      Eigen::SparseMatrix<double> dfdx, dfdv;
      force_jacobians(t, y, false, dfdx, dfdv, Forces::stiff);
      mass_spring_jacobian(dfdx, dfdv, view_.mass, dfdy);
    };
  }

  // the continuum: the grid's triangles as membrane elements in the sheet's own (across, down) coordinates,
  // the plate's bending stencils, and the node masses lumped from the triangles (a third of each's)
  void set_up_continuum(double dx, double dz, double density) {
    const auto material_point = [&](int k) { return Eigen::Vector2d((k % columns_) * dx, (k / columns_) * dz); };
    std::fill(view_.mass.begin(), view_.mass.end(), 0.0);
    for (const auto& tri : triangles_) {
      elements_.push_back(make_membrane_element(tri, material_point(tri[0]), material_point(tri[1]), material_point(tri[2])));
      for (const int k : tri)
        if (free_index_[k] >= 0) view_.mass[free_index_[k]] += density * material_.thickness * elements_.back().area / 3;
    }
    stencils_ = plate_bending_stencils(rows_, columns_, dx, dz, material_.poisson);
    // the stencils summed over the grid's nodes: the whole bending energy is D / 2 sum_kl B_kl x_k . x_l
    std::vector<Eigen::Triplet<double>> entries;
    for (const BendingStencil& s : stencils_)
      for (size_t i = 0; i < s.node.size(); ++i)
        for (size_t j = 0; j < s.node.size(); ++j) entries.emplace_back(s.node[i], s.node[j], s.Q(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
    bending_nodes_.resize(rows_ * columns_, rows_ * columns_);
    bending_nodes_.setFromTriplets(entries.begin(), entries.end());
  }

  Corners3 corners(const std::array<int, 3>& node, const double* x) const { return {corner(node[0], x), corner(node[1], x), corner(node[2], x)}; }
  Corners3 corner_velocities(const std::array<int, 3>& node, const double* v) const {
    return {corner_velocity(node[0], v), corner_velocity(node[1], v), corner_velocity(node[2], v)};
  }
  std::vector<Eigen::Vector3d> corners(const std::vector<int>& node, const double* x) const {
    std::vector<Eigen::Vector3d> c;
    for (const int k : node) c.push_back(corner(k, x));
    return c;
  }

  // the springs' forces, or the continuum's (membrane and bending), added to f (N, by free node)
  void add_elastic_forces(const double* x, const double* v, Eigen::Ref<Eigen::VectorXd> f) const {
    if (!continuum_) {
      add_spring_forces(view_.springs, x, v, f.data());
      return;
    }
    const auto add = [&](int k, const Eigen::Vector3d& force) {
      if (free_index_[k] >= 0) f.segment<3>(3 * free_index_[k]) += force;
    };
    for (const MembraneElement& e : elements_) {
      Vector9d fe = membrane_force(material_, e, corners(e.node, x));
      if (beta_ > 0) fe += membrane_damping_force(material_, e, corners(e.node, x), corner_velocities(e.node, v), beta_);
      for (int i = 0; i < 3; ++i) add(e.node[i], fe.segment<3>(3 * i));
    }
    // the bending force -D (Q x) of every stencil at once: -D X B (X the grid's positions as columns; B symmetric)
    const Eigen::Matrix3Xd bent = grid_positions(x) * bending_nodes_;
    for (int k = 0; k < rows_ * columns_; ++k) add(k, -material_.bending * bent.col(k));
  }

  // every grid node's position (a pinned one's where it is pinned), as the columns of a 3 x nodes matrix
  Eigen::Matrix3Xd grid_positions(const double* x) const {
    Eigen::Matrix3Xd at(3, rows_ * columns_);
    for (int k = 0; k < rows_ * columns_; ++k) at.col(k) = corner(k, x);
    return at;
  }

  // an element's 9 x 9 Jacobian added on the pattern, its free corners' blocks
  void add_element(size_t k, const Matrix9d& J, Eigen::SparseMatrix<double>& to) const {
    const MembraneElement& e = elements_[k];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (free_index_[e.node[i]] >= 0 && free_index_[e.node[j]] >= 0) BlockPattern::add(to, triangle_slots_[k][3 * i + j], J.block<3, 3>(3 * i, 3 * j));
  }

  // the continuum's df/dx added on the pattern (definite: each element's semidefinite approximation, membrane.hpp)
  void add_continuum_force_jacobian(const double* x, bool definite, Eigen::SparseMatrix<double>& dfdx) const {
    for (size_t k = 0; k < elements_.size(); ++k)
      add_element(k, membrane_force_jacobian(material_, elements_[k], corners(elements_[k].node, x), definite), dfdx);
    Eigen::Map<Eigen::VectorXd>(dfdx.valuePtr(), dfdx.nonZeros()) += bending_jacobian_;
  }

  // the continuum's damping: df/dv (negative semidefinite) and, exact, df/dx (the viscous stress turning with F). The
  // membrane's alone: the quadratic bending's constant Hessian times v would damp a curved sheet's rigid spin
  void add_continuum_damping_jacobians(const double* x, const double* v, bool definite, Eigen::SparseMatrix<double>& dfdx,
                                       Eigen::SparseMatrix<double>& dfdv) const {
    for (size_t k = 0; k < elements_.size(); ++k) {
      const MembraneElement& e = elements_[k];
      add_element(k, membrane_damping_velocity_jacobian(material_, e, corners(e.node, x), beta_), dfdv);
      if (!definite) add_element(k, membrane_damping_position_jacobian(material_, e, corners(e.node, x), corner_velocities(e.node, v), beta_), dfdx);
    }
  }

  // each free node's elastic terms: its springs, or its elements and bending stencils with its place in each
  void set_up_vertex_terms() {
    node_springs_ = springs_by_node(view_.springs, free_);
    node_elements_.resize(static_cast<size_t>(free_));
    node_stencils_.resize(static_cast<size_t>(free_));
    for (size_t k = 0; k < elements_.size(); ++k)
      for (int j = 0; j < 3; ++j)
        if (const int i = free_index_[elements_[k].node[j]]; i >= 0) node_elements_[static_cast<size_t>(i)].emplace_back(static_cast<int>(k), j);
    for (size_t k = 0; k < stencils_.size(); ++k)
      for (size_t j = 0; j < stencils_[k].node.size(); ++j)
        if (const int i = free_index_[stencils_[k].node[j]]; i >= 0) node_stencils_[static_cast<size_t>(i)].emplace_back(static_cast<int>(k), static_cast<int>(j));
  }

  // the elastic terms touching free node i (MassSpringView::vertex_elastic)
  void vertex_elastic(int i, const double* x, bool definite, bool derivatives, VertexElastic& out) const {
    const auto node = static_cast<size_t>(i);
    add_springs_at_node(view_.springs, node_springs_[node], i, x, definite, derivatives, out);
    for (const auto& [k, j] : node_elements_[node]) {
      const MembraneElement& e = elements_[static_cast<size_t>(k)];
      const Corners3 c = corners(e.node, x);
      out.energy += membrane_energy(material_, e, c);
      if (!derivatives) continue;
      Eigen::Vector3d f;
      Eigen::Matrix3d K;
      membrane_corner(material_, e, c, j, definite, f, K);
      out.force += f;
      out.jacobian += K;
    }
    for (const auto& [k, j] : node_stencils_[node]) {
      const BendingStencil& s = stencils_[static_cast<size_t>(k)];
      const auto c = corners(s.node, x);
      out.energy += bending_energy(material_.bending, s, c);
      if (!derivatives) continue;
      out.force += bending_force_on(material_.bending, s, c, static_cast<size_t>(j));
      out.jacobian -= material_.bending * s.Q(j, j) * Eigen::Matrix3d::Identity();
    }
  }

  double kinetic_energy(const Eigen::VectorXd& y) const { return y.tail(3 * free_).cwiseAbs2().dot(mass3_) / 2; }
  double elastic_energy(const double* x) const {
    if (!continuum_) return spring_energy(view_.springs, x);
    double e = 0;
    for (const MembraneElement& m : elements_) e += membrane_energy(material_, m, corners(m.node, x));
    if (stencils_.empty()) return e;
    const Eigen::Matrix3Xd at = grid_positions(x);
    return e + material_.bending / 2 * at.cwiseProduct(at * bending_nodes_).sum();
  }

  // the springs read as compliant distance constraints (alpha = 1 / stiffness: the same material), which the
  // position-based methods, RATTLE and IDA step; the other forces (wind, the pick, drag, gravity) are their
  // external acceleration, and the springs' Voigt damping is left out (XPBD damps by itself). A stiffness
  // taken to infinity (--set stiffness=1e12) is the inextensible cloth
  void read_springs_as_constraints() {
    constraints_.dimension = 3;
    constraints_.inverse_mass.assign(static_cast<size_t>(free_), 1 / node_mass_);
    for (const Spring& s : view_.springs) {
      if (!(s.stiffness > 0)) continue;
      if (s.a < 0) constraints_.constraints.push_back({s.b, -1, s.anchor, s.rest, 1 / s.stiffness});
      else constraints_.constraints.push_back({s.a, s.b, Eigen::Vector3d::Zero(), s.rest, 1 / s.stiffness});
    }
    constraints_.external = [this](double t, const double* x, const double* v, double* a) {
      Eigen::VectorXd y(6 * free_);
      y << Eigen::Map<const Eigen::VectorXd>(x, 3 * free_), Eigen::Map<const Eigen::VectorXd>(v, 3 * free_);
      acceleration(t, y, Eigen::Map<Eigen::VectorXd>(a, 3 * free_), Forces::nonstiff);
    };
  }

  // at most 1024 a side: a million nodes, whose sparse factor already takes gigabytes
  static int grid_size(const Params& p, const char* key) { return grid_index(p, key, 2, 1024, false); }
  Eigen::Vector3d wind_at(double t) const { return wind_ * (1 + gust_ * std::sin(2 * std::numbers::pi * gust_frequency_ * t)); }
  Eigen::Vector3d corner(int k, const double* x) const {
    const int i = free_index_[k];
    return i < 0 ? rest_[k] : Eigen::Vector3d(Eigen::Map<const Eigen::Vector3d>(x + 3 * i));
  }
  Eigen::Vector3d area_vector(const std::array<int, 3>& tri, const double* x) const {
    return stepwise::area_vector(corner(tri[0], x), corner(tri[1], x), corner(tri[2], x));
  }
  // a pinned corner is at rest
  Eigen::Vector3d corner_velocity(int k, const double* v) const {
    const int i = free_index_[k];
    return i < 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(Eigen::Map<const Eigen::Vector3d>(v + 3 * i));
  }
  Eigen::Vector3d mean_velocity(const std::array<int, 3>& tri, const double* v) const {
    return stepwise::mean_velocity(corner_velocity(tri[0], v), corner_velocity(tri[1], v), corner_velocity(tri[2], v));
  }

  int rows_, columns_;
  double g_, drag_;
  Eigen::Vector3d wind_;
  double wind_k_, gust_, gust_frequency_;
  Eigen::Vector3d pick_force_, sphere_centre_;
  double sphere_radius_;
  bool ground_;
  bool pole_ = false;  // the left edge pinned to a pole
  double ground_y_, friction_;
  double node_mass_ = 0;  // the spring sheet's (the continuum's masses are lumped: view_.mass)
  bool continuum_;
  MembraneMaterial material_;
  double beta_;  // the continuum's Rayleigh beta (s): its viscous stress's retardation time
  std::vector<MembraneElement> elements_;  // the continuum's, one a triangle (triangles_'s order)
  std::vector<BendingStencil> stencils_;   // the continuum's bending, one a node and one a cell
  Eigen::SparseMatrix<double> bending_nodes_;  // their Q summed over the grid's nodes (rows x columns of them)
  // each free node's elastic terms (vbd's view): springs by index; elements and stencils by (index, the node's place)
  std::vector<std::vector<int>> node_springs_;
  std::vector<std::vector<std::pair<int, int>>> node_elements_, node_stencils_;
  Eigen::VectorXd mass3_;                  // each free node's mass, once a coordinate
  std::vector<Eigen::Vector3d> rest_;  // every grid node's starting place (a pinned node stays there)
  std::vector<int> free_index_;         // grid node -> state node, -1 if pinned
  std::vector<int> grid_node_;          // state node -> grid node
  int free_ = 0;
  int picked_ = -1;
  std::vector<std::array<int, 3>> triangles_;  // grid nodes
  SecondOrderView second_order_;  // y = (x, v), with the acceleration below
  MassSpringView view_;
  SpringNetworkView network_{&view_};  // the spring sheet's elastic forces are its springs alone
  ClothGridView grid_;
  ImexSplit split_;
  DistanceConstraints constraints_;  // the springs as compliant constraints
  std::unique_ptr<BlockPattern> pattern_;
  std::vector<std::array<BlockPattern::Slot, 4>> spring_slots_;
  std::vector<BlockPattern::Slot> diagonal_slots_;
  std::vector<std::array<BlockPattern::Slot, 9>> triangle_slots_;  // (corner i, corner j) of each triangle
  Eigen::VectorXd bending_jacobian_;  // the bending stencils' df/dx, constant: its values on the pattern
};

}  // namespace

std::span<const ParamSpec> cloth_params() { return parameter_table(); }
std::unique_ptr<Model> make_cloth(const Params& params, std::span<const GridNode> pins) { return std::make_unique<Cloth>(params, pins); }

}  // namespace stepwise
