// Rigid bodies in contact: detection (box-ground depths, box-box face and crossed-edge manifolds with the
// separating axis' normal, the bounding-volume culls), impulses (kinetic energy never rises for eps <= 1
// over random impacts, an elastic frictionless impact keeps it, momentum kept in body-body impacts without
// ground), resting contact held for 10 s on flat ground and on a slope inside the friction cone, sliding
// at Coulomb's acceleration outside it, and bit-identical runs of the collapsing stack.
#include "models/contact.hpp"
#include "models/model.hpp"
#include "solvers/contact_solve.hpp"
#include "solvers/integrator.hpp"
#include "solvers/method_table.hpp"
#include "verification/contact_checks.hpp"
#include "run/measure.hpp"
#include "verification/order_fit.hpp"
#include "verification/tolerances.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

namespace stepwise {
namespace {

constexpr double geometry = tolerance::contact_geometry_roundoff;

// 13-entry states of bodies at poses (x, q) with velocities (v, body w)
Eigen::VectorXd states(std::initializer_list<std::tuple<Eigen::Vector3d, Eigen::Quaterniond, Eigen::Vector3d, Eigen::Vector3d>> bodies) {
  Eigen::VectorXd y(13 * static_cast<Eigen::Index>(bodies.size()));
  Eigen::Index o = 0;
  for (const auto& [x, q, v, w] : bodies) {
    y.segment<13>(o) << x, v, q.w(), q.x(), q.y(), q.z(), w;
    o += 13;
  }
  return y;
}

const Eigen::Quaterniond level = Eigen::Quaterniond::Identity();
const Eigen::Vector3d still = Eigen::Vector3d::Zero();
const Plane ground = make_plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());

TEST(ContactDetection, ABoxOnTheGroundTouchesAtItsCornersAsDeepAsTheyAre) {
  const Eigen::Vector3d h(0.3, 0.2, 0.1);
  const std::vector<ContactBody> box{make_contact_body(box_mesh(h), 500)};
  // flat, 1 mm in: the four bottom corners
  auto contacts = find_contacts(box, &ground, states({{Eigen::Vector3d(0, 0, h.z() - 1e-3), level, still, still}}));
  ASSERT_EQ(contacts.size(), 4u);
  for (const Contact& c : contacts) {
    EXPECT_NEAR(c.depth, 1e-3, geometry);
    EXPECT_EQ(c.b, -1);
    EXPECT_EQ(c.normal, Eigen::Vector3d::UnitZ());
    EXPECT_NEAR(std::abs(c.point.x()), h.x(), geometry);
  }
  // on a corner: turned so that one vertex is lowest, the rest well above
  const Eigen::Quaterniond tilt = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX())) *
                                  Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()));
  double lowest = 0;
  for (Eigen::Index v = 0; v < 8; ++v) lowest = std::min(lowest, (tilt * box[0].mesh.vertices.row(v).transpose()).z());
  contacts = find_contacts(box, &ground, states({{Eigen::Vector3d(0, 0, -lowest - 2e-3), tilt, still, still}}));
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_NEAR(contacts[0].depth, 2e-3, geometry);
}

TEST(ContactDetection, StackedBoxesShareTheFaceNormalAndOverlap) {
  const Eigen::Vector3d h(0.2, 0.2, 0.2);
  const std::vector<ContactBody> boxes(2, make_contact_body(box_mesh(h), 300));
  // the upper box 1 mm into the lower, shifted so that its corners lie over the lower's top face
  long tests = 0;
  const auto contacts = find_contacts(boxes, nullptr, states({{Eigen::Vector3d(0, 0, 0.2), level, still, still},
                                                              {Eigen::Vector3d(0.05, 0.03, 0.6 - 1e-3), level, still, still}}), &tests);
  ASSERT_FALSE(contacts.empty());
  EXPECT_GT(tests, 0);
  for (const Contact& c : contacts) {
    EXPECT_EQ(c.a, 1) << "the upper box is pushed ...";
    EXPECT_EQ(c.b, 0);
    EXPECT_LT((c.normal - Eigen::Vector3d::UnitZ()).norm(), geometry) << "... up, along the lower's top face normal";
    EXPECT_NEAR(c.depth, 1e-3, geometry);
    EXPECT_NEAR(c.point.z(), 0.4 - 1e-3 / 2, 1e-3 / 2 + geometry) << "in the overlap";
  }
}

TEST(ContactDetection, CrossedEdgesMeetAlongTheirCommonNormal) {
  // two boxes turned 45 degrees about x and about y: the lower's top edge runs along x, the upper's bottom
  // edge along y; they cross at one point, with no vertex of either inside the other
  const Eigen::Vector3d h(0.2, 0.2, 0.2);
  const std::vector<ContactBody> boxes(2, make_contact_body(box_mesh(h), 300));
  const double reach = 0.2 * std::sqrt(2.0), overlap = 2e-3;
  const Eigen::Quaterniond about_x(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX()));
  const Eigen::Quaterniond about_y(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY()));
  const auto contacts = find_contacts(boxes, nullptr, states({{Eigen::Vector3d::Zero(), about_x, still, still},
                                                              {Eigen::Vector3d(0, 0, 2 * reach - overlap), about_y, still, still}}));
  ASSERT_FALSE(contacts.empty());
  for (const Contact& c : contacts) {
    EXPECT_LT((c.normal - Eigen::Vector3d::UnitZ()).norm(), geometry) << "x cross y";
    EXPECT_NEAR(c.depth, overlap, geometry);
    // the middle of an edge's part inside the other lies in the lens where they overlap: within the
    // overlap's depth of the crossing point below, and along the edge within the lens's half-width, which
    // for edges crossing at right angles through 45-degree wedges is the overlap again
    EXPECT_LT((c.point - Eigen::Vector3d(0, 0, reach - overlap / 2)).norm(), 2 * overlap) << "at the crossing";
  }
}

TEST(ContactDetection, BodiesApartCostNoTriangleTest) {
  const std::vector<ContactBody> boxes(2, make_contact_body(box_mesh(Eigen::Vector3d(0.2, 0.2, 0.2)), 300));
  long tests = 0;
  // bounding spheres (radius 0.35 m) apart: culled before the hierarchy
  EXPECT_TRUE(find_contacts(boxes, nullptr, states({{still, level, still, still}, {Eigen::Vector3d(0.8, 0, 0), level, still, still}}), &tests).empty());
  EXPECT_EQ(tests, 0);
  // spheres and boxes overlapping, bodies 2.6 cm apart: the second turned 45 degrees about z faces the
  // first's corner across the diagonal (separation 0.36 sqrt 2 - 0.2 sqrt 2 - 0.2): the triangle tests say no
  const Eigen::Quaterniond turned(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE(find_contacts(boxes, nullptr, states({{still, level, still, still}, {Eigen::Vector3d(0.36, 0.36, 0), turned, still, still}}), &tests).empty());
  EXPECT_GT(tests, 0);
  // 0.33 along each axis: 0.7 cm into each other
  EXPECT_FALSE(find_contacts(boxes, nullptr, states({{still, level, still, still}, {Eigen::Vector3d(0.33, 0.33, 0), turned, still, still}})).empty());
}

// random impacts of a box on the ground and of two boxes: random poses, 1-3 mm of overlap, random
// velocities and spins, eps and mu anywhere in [0, 1] and [0, 1.5]
struct Impact {
  std::vector<ContactBody> bodies;
  Eigen::VectorXd y;
  std::vector<Contact> contacts;
  ContactMaterial material;
};

Impact random_impact(std::mt19937_64& rng, bool two_bodies) {
  std::uniform_real_distribution<double> u(-1, 1), unit(0, 1);
  const auto random_quaternion = [&] { return Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized()); };
  const auto random_vector = [&](double scale) -> Eigen::Vector3d { return Eigen::Vector3d(u(rng), u(rng), u(rng)) * scale; };
  Impact impact;
  impact.material.restitution = unit(rng);
  impact.material.friction = 1.5 * unit(rng);
  impact.material.push = 0;
  const Eigen::Vector3d h(0.1 + 0.3 * unit(rng), 0.1 + 0.3 * unit(rng), 0.1 + 0.3 * unit(rng));
  impact.bodies.push_back(make_contact_body(box_mesh(h), 100 + 900 * unit(rng)));
  const Eigen::Quaterniond q = random_quaternion();
  if (!two_bodies) {
    double lowest = 0;
    for (Eigen::Index v = 0; v < 8; ++v) lowest = std::min(lowest, (q * impact.bodies[0].mesh.vertices.row(v).transpose()).z());
    impact.y = states({{Eigen::Vector3d(0, 0, -lowest - 1e-3 * (1 + 2 * unit(rng))), q, random_vector(3) - Eigen::Vector3d(0, 0, 3), random_vector(5)}});
    impact.contacts = find_contacts(impact.bodies, &ground, impact.y);
    return impact;
  }
  impact.bodies.push_back(make_contact_body(box_mesh(Eigen::Vector3d(0.1 + 0.3 * unit(rng), 0.1 + 0.3 * unit(rng), 0.1 + 0.3 * unit(rng))),
                                            100 + 900 * unit(rng)));
  // the second box approaches along a random direction until the two overlap
  const Eigen::Vector3d direction = random_vector(1).normalized();
  const Eigen::Quaterniond q2 = random_quaternion();
  for (double d = 2; d > 0; d -= 1e-3) {
    impact.y = states({{still, q, random_vector(1), random_vector(3)}, {d * direction, q2, -3 * direction + random_vector(1), random_vector(3)}});
    impact.contacts = find_contacts(impact.bodies, nullptr, impact.y);
    if (!impact.contacts.empty()) break;
  }
  return impact;
}

TEST(ContactImpulses, KineticEnergyNeverRisesAtAnImpact) {
  std::mt19937_64 rng(20261121);
  int impacts = 0, guarded = 0;
  double largest_rise = -1;
  for (int trial = 0; trial < 400; ++trial) {
    Impact impact = random_impact(rng, trial % 2 == 1);
    if (impact.contacts.empty()) continue;
    ++impacts;
    const double before = kinetic_energy(impact.bodies, impact.y);
    ContactMemory memory;
    const ContactOutcome outcome = resolve(body_masses(impact.bodies), impact.contacts, impact.material, impact.y, memory);
    guarded += outcome.energy_guard;
    const double after = kinetic_energy(impact.bodies, impact.y);
    largest_rise = std::max(largest_rise, (after - before) / before);
    EXPECT_LE(after, before * (1 + tolerance::impulse_energy_roundoff)) << "trial " << trial << " eps " << impact.material.restitution
                                                                         << " mu " << impact.material.friction;
  }
  EXPECT_GT(impacts, 300);
  std::cout << impacts << " impacts; the frictionless fallback took " << guarded << "; largest change " << largest_rise << " of T\n";
}

TEST(ContactImpulses, AnElasticFrictionlessImpactKeepsTheKineticEnergy) {
  // eps = 1, mu = 0, one contact: the normal velocity reverses and nothing else changes, so T is kept
  const std::vector<ContactBody> box{make_contact_body(box_mesh(Eigen::Vector3d(0.3, 0.2, 0.1)), 500)};
  const Eigen::Quaterniond tilt = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX())) *
                                  Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()));
  double lowest = 0;
  for (Eigen::Index v = 0; v < 8; ++v) lowest = std::min(lowest, (tilt * box[0].mesh.vertices.row(v).transpose()).z());
  Eigen::VectorXd y = states({{Eigen::Vector3d(0, 0, -lowest - 1e-3), tilt, Eigen::Vector3d(0.5, 0.2, -3), Eigen::Vector3d(1, -2, 0.5)}});
  const auto contacts = find_contacts(box, &ground, y);
  ASSERT_EQ(contacts.size(), 1u);
  ContactMaterial elastic;
  elastic.restitution = 1;
  elastic.friction = 0;
  const double before = kinetic_energy(box, y);
  ContactMemory memory;
  resolve(body_masses(box), contacts, elastic, y, memory);
  EXPECT_NEAR(kinetic_energy(box, y) / before, 1, tolerance::impulse_energy_roundoff);
}

TEST(ContactImpulses, MomentumIsKeptInABodyBodyImpactWithoutGround) {
  // the wall without ground or gravity, hit by the projectile: impulses come in +j/-j pairs at one point
  for (const double push : {0.0, 0.2}) {
    const auto model = make_model("box-stack", {{"ground", 0}, {"g", 0}, {"push", push}, {"rows", 3}, {"columns", 2}, {"projectile_height", 0.5}});
    const Measured m = run_and_measure(*model, "sequential-impulses", StepControl::fixed(1e-3), 1.0, 0.5);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    const auto names = model->summary_names();
    const auto at = [&](const Eigen::VectorXd& s, const std::string& key) { return s[std::find(names.begin(), names.end(), key) - names.begin()]; };
    const Eigen::VectorXd first = model->summary(model->initial_state()), last = model->summary(m.result.y_stop);
    ASSERT_GT(m.result.events.size(), 0u) << "the projectile hits the wall";
    const double p0 = at(first, "px"), L0 = at(first, "Ly");
    for (const char* key : {"px", "py", "pz"}) EXPECT_NEAR(at(last, key), at(first, key), tolerance::impulse_momentum_roundoff * p0) << key << " push " << push;
    const double dL = std::hypot(at(last, "Lx") - at(first, "Lx"), at(last, "Ly") - L0, at(last, "Lz") - at(first, "Lz"));
    if (push == 0) {
      EXPECT_LT(dL, tolerance::impulse_momentum_roundoff * std::abs(L0));
    }
    std::cout << "push " << push << ": |dL| / |L| = " << dL / std::abs(L0) << " (a push moves positions: L about the origin by m d x dv)\n";
  }
}

TEST(RestingContact, ABoxOnTheGroundStaysPutForTenSeconds) {
  for (const double slope : {0.0, std::atan(0.25)}) {  // flat, and a slope inside the friction cone (mu = 0.5)
    const auto model = make_model("dropped-body", box_on_slope(slope, 0.5));
    const double dt = 1e-3, t_end = 10, g = 9.81;
    const Measured m = run_and_measure(*model, "sequential-impulses", StepControl::fixed(dt), t_end, 0.01);
    ASSERT_EQ(m.result.status, Status::ok);
    EXPECT_TRUE(m.result.events.empty()) << "no impact: the first approach is one step of gravity";
    const SlopeMotion motion = slope_motion(m.result, slope, 0.01);
    EXPECT_LE(motion.creep, tolerance::resting_creep(t_end)) << "slope " << slope;
    EXPECT_LE(motion.sink, tolerance::resting_settle(g, dt)) << "slope " << slope;
    EXPECT_LE(motion.turn * 0.1, tolerance::resting_creep(t_end)) << "a corner 0.1 m off the axis moves no more than the centre may";
    std::cout << "slope " << slope << ": creep " << motion.creep << " m, settled " << motion.sink << " m, turned " << motion.turn << " rad over "
              << t_end << " s\n";
  }
}

TEST(RestingContact, ABoxOnASlopeSteeperThanItsFrictionAngleSlidesAtCoulombsAcceleration) {
  const double slope = std::atan(0.75), mu = 0.5;
  const auto model = make_model("dropped-body", box_on_slope(slope, mu));
  const Measured m = run_and_measure(*model, "sequential-impulses", StepControl::fixed(1e-3), 1.0, 0.1);
  ASSERT_EQ(m.result.status, Status::ok);
  const double a = 9.81 * (std::sin(slope) - mu * std::cos(slope));
  const Eigen::Vector3d along(std::cos(slope), 0, -std::sin(slope));
  for (size_t k = 1; k < m.result.trajectory.t.size(); ++k) {
    const Eigen::VectorXd& y = m.result.trajectory.y[k];
    // the first step falls freely, and the second's normal impulse, twice a step's, takes back with its
    // friction what the first gained along the slope: from then on v = a t exactly
    const double t = m.result.trajectory.t[k];
    EXPECT_NEAR(y.segment<3>(3).dot(along), a * t, tolerance::sliding_roundoff * a * t) << t;
    EXPECT_LT(y.segment<3>(10).norm(), tolerance::sliding_roundoff) << "no spin";
  }
}

TEST(SequentialImpulses, WithoutContactsItIsSymplecticEulerOfItsDocumentedOrder) {
  // a spinning box thrown up with no ground: no contact, so a step is symplectic Euler on the translation,
  // v_n = v0 - g n h, z_n = z0 + h (v_1 + ... + v_n) = z(t) - g h t / 2 exactly: an error linear in h, the
  // documented order 1, over five halvings of the step
  const auto model = make_model("dropped-body", {{"ground", 0}, {"vz0", 3.0}});
  const Method& method = *find_method("sequential-impulses");
  const double t_end = 0.5, g = 9.81, z0 = 1.5, vz0 = 3.0;
  std::vector<double> steps, errors;
  for (double h = 0.01; steps.size() < 6; h /= 2) {
    const Measured m = run_and_measure(*model, method.name, StepControl::fixed(h), t_end, t_end);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    steps.push_back(h);
    errors.push_back(std::abs(m.result.y_stop[2] - (z0 + vz0 * t_end - g * t_end * t_end / 2)));
  }
  const double order = loglog_slope(steps, errors);
  std::cout << "sequential-impulses in free flight: |z - z_exact| at " << t_end << " s from " << errors.front() << " to " << errors.back()
            << " (g h t / 2: " << g * steps.front() * t_end / 2 << " to " << g * steps.back() * t_end / 2 << "), order " << order << '\n';
  EXPECT_NEAR(order, method.order.max, tolerance::order_band);
}

TEST(StackCollapse, RunsAreBitIdenticalFromTheSameInputs) {
  const auto model = make_model("box-stack");
  const auto once = [&] { return run_and_measure(*model, "sequential-impulses", StepControl::fixed(1e-3), 0.4, 0.01).result; };
  const RunResult a = once(), b = once();
  ASSERT_EQ(a.status, Status::ok);
  ASSERT_GT(a.events.size(), 0u) << "the projectile reaches the wall by 0.4 s";
  ASSERT_EQ(a.trajectory.y.size(), b.trajectory.y.size());
  for (size_t k = 0; k < a.trajectory.y.size(); ++k) EXPECT_EQ(a.trajectory.y[k], b.trajectory.y[k]) << a.trajectory.t[k];
  EXPECT_EQ(a.events.size(), b.events.size());
}

}  // namespace
}  // namespace stepwise
