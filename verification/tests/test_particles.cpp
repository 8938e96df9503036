// The particle-plane collision of the seeds and particles bouncing in a box: the three cases, the crossing
// on the segment, the response, the box invariant at any dt, energy that only decays, reproducible runs.
#include "models/model.hpp"
#include "models/particle_mesh.hpp"
#include "models/plane_collision.hpp"
#include "solvers/method_table.hpp"
#include "run/measure.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>

namespace stepwise {
namespace {

TEST(PlaneCollision, TheThreeCasesAndTheCrossingOnTheSegment) {
  const Plane plane = make_plane(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, 2));  // z = 1, normal +z (normalised)
  EXPECT_DOUBLE_EQ(plane.normal.norm(), 1.0);
  EXPECT_EQ(side_of(plane, Eigen::Vector3d(5, -3, 1)), Side::on);
  EXPECT_EQ(side_of(plane, Eigen::Vector3d(0, 0, 1.5)), Side::positive);
  EXPECT_EQ(side_of(plane, Eigen::Vector3d(0, 0, 0.5)), Side::negative);
  EXPECT_DOUBLE_EQ(signed_distance(plane, Eigen::Vector3d(7, 7, 3)), 2.0);
  // from z = 3 to z = 0 the segment meets z = 1 two thirds of the way
  const auto s = segment_crossing(plane, Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(3, 0, 0));
  ASSERT_TRUE(s.has_value());
  EXPECT_DOUBLE_EQ(*s, 2.0 / 3.0);
  EXPECT_FALSE(segment_crossing(plane, Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(0, 0, 2)).has_value());
  EXPECT_THROW(make_plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()), std::invalid_argument);
}

TEST(PlaneCollision, ResponseReversesTheNormalByRestitutionAndNeverAddsEnergy) {
  const Plane plane = make_plane(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 2, 2));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-5, 5), unit(0, 1);
  for (int k = 0; k < 1000; ++k) {
    const Eigen::Vector3d v(u(rng), u(rng), u(rng));
    const double eps = unit(rng), mu = unit(rng);
    const Eigen::Vector3d n = plane.normal;
    const Eigen::Vector3d free = collision_response(plane, v, eps, 0);
    EXPECT_NEAR(free.dot(n), -eps * v.dot(n), tolerance::kernel_roundoff);
    EXPECT_LT((free - free.dot(n) * n - (v - v.dot(n) * n)).norm(), tolerance::kernel_roundoff) << "tangential kept without friction";
    const Eigen::Vector3d rough = collision_response(plane, v, eps, mu);
    const Eigen::Vector3d vt = v - v.dot(n) * n, rt = rough - rough.dot(n) * n;
    // Coulomb: the tangential speed falls by mu (1 + eps) |v.n|, clamped at zero, direction kept
    EXPECT_NEAR(rt.norm(), std::max(0.0, vt.norm() - mu * (1 + eps) * std::abs(v.dot(n))), tolerance::kernel_roundoff);
    EXPECT_GE(rt.dot(vt), -tolerance::kernel_roundoff);
    EXPECT_LE(rough.squaredNorm(), v.squaredNorm() + tolerance::kernel_roundoff);
  }
}

Params box(double count, double restitution, double seed = 1) {
  return {{"count", count}, {"restitution", restitution}, {"seed", seed}};
}

RunResult run_box(const Params& params, std::string_view method, StepControl control, double t_end, double output_dt) {
  const auto model = make_model("particles-in-box", params);
  std::vector<double> t_out;
  for (double t = output_dt; t < t_end * (1 + 1e-12); t += output_dt) t_out.push_back(t);
  return make_integrator(method, control)->integrate(*model, 0, model->initial_state(), t_out);
}

TEST(ParticlesInBox, NoParticleEverEndsAStepOutsideTheBox) {
  // sampled at every step, for fine and coarse steps: dt = 0.05 s moves a 2 m/s particle a tenth of the box
  for (const double dt : {1e-3, 0.05}) {
    for (const char* method : {"rk4", "symplectic-euler", "euler"}) {
      const RunResult r = run_box(box(50, 0.9), method, StepControl::fixed(dt), 4.0, dt);
      ASSERT_EQ(r.status, Status::ok) << method << ": " << r.message;
      double worst = 0;
      for (const auto& y : r.trajectory.y)
        for (int k = 0; k < 150; ++k) worst = std::max({worst, -y[k], y[k] - 1.0});
      std::cout << method << " dt " << dt << ": " << r.events.size() << " impacts, deepest excursion " << worst << " m\n";
      // a particle moved onto a wall lies on it up to the rounding of p - d n
      EXPECT_LE(worst, 4 * std::numeric_limits<double>::epsilon()) << method << " dt " << dt;
    }
  }
}

TEST(ParticlesInBox, EnergyNeverGrowsAndElasticWallsKeepIt) {
  // rk4 integrates the parabolas exactly and re-stepping puts each impact at its root: with eps = 1 the
  // energy holds to round-off; with eps < 1 it only falls, as each impact removes (1 - eps^2)(n.v)^2/2
  for (const double eps : {1.0, 0.7}) {
    StepControl control = StepControl::fixed(1e-3);
    control.event_location = EventLocation::restep;
    const auto model = make_model("particles-in-box", box(20, eps));
    const RunResult r = run_box(box(20, eps), "rk4", control, 3.0, 0.01);
    ASSERT_EQ(r.status, Status::ok) << r.message;
    const double e0 = *model->energy(model->initial_state());
    double previous = e0, worst_rise = 0;
    for (const auto& y : r.trajectory.y) {
      const double e = *model->energy(y);
      worst_rise = std::max(worst_rise, (e - previous) / e0);
      previous = e;
    }
    std::cout << "eps " << eps << ": " << r.events.size() << " events, energy " << e0 << " -> " << previous
              << ", largest rise between samples " << worst_rise << '\n';
    EXPECT_LT(worst_rise, tolerance::kernel_roundoff);
    if (eps == 1.0) {
      EXPECT_NEAR(previous, e0, tolerance::event_energy_roundoff * e0);
    } else {
      // every particle meets the floor several times in 3 s, each impact taking 1 - eps^2 = 51% of its
      // vertical energy, which holds most of the total: more than half of it goes
      EXPECT_LT(previous, 0.5 * e0);
    }
  }
}

TEST(ParticlesInBox, EachImpactTakesTheShareOfEnergyRestitutionImplies) {
  // each impact multiplies the energy of the motion normal to its wall by eps^2: the x energy vx^2/2 at the
  // x walls, the vertical energy vz^2/2 + g z at the floor. rk4 is exact on the parabolas and re-stepping
  // puts each impact at its root, so per axis E_final = E_initial eps^(2 n) with n that axis's impacts.
  // The box is tall enough that the ceiling is never reached, and the run ends before the floor's Zeno point.
  const double eps = 0.7, g = 9.81;
  for (const double seed : {1.0, 2.0, 3.0}) {
    const Params params{{"count", 1}, {"size", 2.0}, {"restitution", eps}, {"speed", 1.0}, {"seed", seed}, {"rest_speed", 1e-9}};
    const auto model = make_model("particles-in-box", params);
    StepControl control = StepControl::fixed(1e-3);
    control.event_location = EventLocation::restep;
    const Eigen::VectorXd y0 = model->initial_state();
    const RunResult r = make_integrator("rk4", control)->integrate(*model, 0, y0, std::vector{2.0});
    ASSERT_EQ(r.status, Status::ok) << r.message;
    std::array<int, 6> hits{};
    for (const auto& e : r.events) ++hits[e.event % 6];
    ASSERT_EQ(hits[5], 0) << "the ceiling was reached";
    ASSERT_GT(hits[4], 2) << "a few floor impacts";
    const Eigen::VectorXd& y = r.trajectory.y.back();
    const std::array<double, 3> initial{0.5 * y0[3] * y0[3], 0.5 * y0[4] * y0[4], 0.5 * y0[5] * y0[5] + g * y0[2]};
    const std::array<double, 3> final{0.5 * y[3] * y[3], 0.5 * y[4] * y[4], 0.5 * y[5] * y[5] + g * y[2]};
    for (int axis = 0; axis < 3; ++axis) {
      const int n = hits[2 * axis] + hits[2 * axis + 1];
      const double predicted = initial[axis] * std::pow(eps, 2.0 * n);
      EXPECT_NEAR(final[axis], predicted, tolerance::per_impact_energy * initial[axis]) << "seed " << seed << " axis " << axis << " after " << n << " impacts";
    }
    std::cout << "seed " << seed << ": impacts x " << hits[0] + hits[1] << ", y " << hits[2] + hits[3] << ", floor " << hits[4]
              << "; vertical energy " << initial[2] << " -> " << final[2] << " J/kg\n";
  }
}

TEST(ParticlesInBox, TheSameSeedGivesABitIdenticalTrajectory) {
  const RunResult a = run_box(box(30, 0.8, 42), "rk4", StepControl::fixed(2e-3), 2.0, 0.1);
  const RunResult b = run_box(box(30, 0.8, 42), "rk4", StepControl::fixed(2e-3), 2.0, 0.1);
  const RunResult c = run_box(box(30, 0.8, 43), "rk4", StepControl::fixed(2e-3), 2.0, 0.1);
  ASSERT_EQ(a.trajectory.y.size(), b.trajectory.y.size());
  for (size_t k = 0; k < a.trajectory.y.size(); ++k) ASSERT_EQ(a.trajectory.y[k], b.trajectory.y[k]) << "sample " << k;
  ASSERT_EQ(a.events.size(), b.events.size());
  EXPECT_NE(a.trajectory.y.back(), c.trajectory.y.back());
}

TEST(ParticlesInBox, BadCountsAndRestitutionsNameTheirKey) {
  for (const auto& [key, value] : std::vector<std::pair<std::string, double>>{
           {"count", -5}, {"count", 2.5}, {"count", 1e12}, {"restitution", 1.5}, {"restitution", -0.1}, {"friction", -1}}) {
    try {
      make_model("particles-in-box", {{key, value}});
      ADD_FAILURE() << key << " = " << value << " accepted";
    } catch (const BadParameter& e) {
      EXPECT_EQ(e.key, key);
    }
  }
}

// the deepest any particle lies behind the ground (normal n, offset c) or inside the octahedron, over samples
double deepest_penetration(const std::vector<Eigen::VectorXd>& samples, int count, const Eigen::Vector3d& n, double c) {
  const TriangleMesh mesh = default_obstacle();
  double worst = 0;
  for (const auto& y : samples)
    for (int i = 0; i < count; ++i) {
      const Eigen::Vector3d p = y.segment<3>(3 * i);
      double inside = -std::numeric_limits<double>::infinity();
      for (int f = 0; f < mesh.faces.rows(); ++f) {
        const Triangle t = triangle(mesh, f);
        inside = std::max(inside, area_normal(t).normalized().dot(p - t.a));
      }
      worst = std::max({worst, -(n.normalized().dot(p) - c), -inside});
    }
  return worst;
}

Params rain(double count) { return {{"count", count}, {"plane_ny", 0.3}, {"rest_speed", 0.05}}; }

TEST(ParticleMesh, NoParticleEndsAStepBehindTheGroundOrInsideTheMeshAndEnergyOnlyFalls) {
  const auto model = make_model("particle-mesh", rain(30));
  const double e0 = *model->energy(model->initial_state());
  for (const char* method : {"rk4", "symplectic-euler", "gsl-rkf45", "cvode-bdf"}) {
    const Method& info = *find_method(method);
    StepControl control = info.fixed_step() ? StepControl::fixed(1e-3) : StepControl::adaptive(1e-9, 1e-12);
    control.event_location = EventLocation::restep;
    const Measured m = run_and_measure(*model, method, control, 3.0, info.fixed_step() ? 1e-3 : 0.01);
    ASSERT_EQ(m.result.status, Status::ok) << method << ": " << m.result.message;
    std::map<std::string, int> kinds;
    for (const auto& e : m.result.events) ++kinds[e.kind];
    const double worst = deepest_penetration(m.result.trajectory.y, 30, Eigen::Vector3d(0, 0.3, 1), 0);
    double rise = 0, previous = e0;
    for (const auto& y : m.result.trajectory.y) {
      rise = std::max(rise, *model->energy(y) - previous);
      previous = *model->energy(y);
    }
    std::cout << method << ": " << kinds["impact"] << " impacts, " << kinds["rest"] << " rests, deepest " << worst
              << " m, largest energy rise " << rise / e0 << " of E0\n";
    EXPECT_GT(kinds["rest"], 0) << method;
    // a particle comes to rest on a face once, and again only after sliding off it: no chattering contact
    EXPECT_LE(kinds["rest"], 2 * 30) << method;
    // on a face up to the rounding of p - d n; a resting particle keeps within the contact tolerance (1e-9 m)
    EXPECT_LE(worst, tolerance::contact_band) << method;
    // flight and sliding are parabolas, but a particle sliding off a face's edge meets a jump in its
    // acceleration that no step resolves exactly; impacts themselves only take energy away
    EXPECT_LE(rise, tolerance::edge_crossing_energy * e0) << method;
    EXPECT_LT(previous, e0) << method;
  }
}

TEST(ParticleMesh, AZeroGroundNormalAndBadMeshesAreRefusedByKey) {
  try {
    make_model("particle-mesh", {{"plane_nx", 0}, {"plane_ny", 0}, {"plane_nz", 0}});
    ADD_FAILURE() << "zero normal accepted";
  } catch (const BadParameter& e) {
    EXPECT_EQ(e.key, "plane_nx");
  }
  const ModelInfo& info = *find_model("particle-mesh");
  const Params params = resolve_params(info, {});
  TriangleMesh open = default_obstacle();
  open.faces.conservativeResize(7, 3);
  TriangleMesh inward = default_obstacle();
  inward.faces.col(1).swap(inward.faces.col(2));
  TriangleMesh dent = default_obstacle();
  dent.vertices(1, 2) = 0.3;  // the top vertex pushed below the equator: not convex
  TriangleMesh out_of_range = default_obstacle();
  out_of_range.faces(2, 1) = 17;
  TriangleMesh not_finite = default_obstacle();
  not_finite.vertices(3, 0) = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [name, mesh] : std::vector<std::pair<std::string, TriangleMesh>>{
           {"open", open}, {"inward", inward}, {"dent", dent}, {"out of range", out_of_range}, {"not finite", not_finite}}) {
    try {
      info.make_with_mesh(params, mesh);
      ADD_FAILURE() << name << " mesh accepted";
    } catch (const BadParameter& e) {
      EXPECT_EQ(e.key, "mesh") << name;
    }
  }
  EXPECT_NO_THROW(info.make_with_mesh(params, default_obstacle()));
}

}  // namespace
}  // namespace stepwise
