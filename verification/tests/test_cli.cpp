// The command-line contract (docs/cli.md, docs/outputs.md), pinned against the built binary: names and shapes of
// methods --json, trajectory.csv and summary.json, exit statuses, and one-line errors naming file, line and key.
#include "solvers/method_table.hpp"
#include "verification/tolerances.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace stepwise {
namespace {
namespace fs = std::filesystem;

struct Output {
  int status;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("stepwise-cli-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  Output run(const std::string& args) const {
    const std::string cmd = fmt::format("cd '{}' && '{}' {} >'{}' 2>'{}'", STEPWISE_SOURCE_DIR, STEPWISE_BIN, args, (dir_ / "stdout").string(), (dir_ / "stderr").string());
    const int raw = std::system(cmd.c_str());
    return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(dir_ / "stdout"), slurp(dir_ / "stderr")};
  }
  // a run past a method's stability limit: warned (the warning starting with `warning`), run, exit 1, and
  // its summary written with status diverged at the time it happened
  void expect_warned_and_diverged(const std::string& args, const std::string& warning) const {
    const fs::path out = dir_ / "past";
    const Output o = run(fmt::format("{} --out '{}'", args, out.string()));
    EXPECT_EQ(o.status, 1) << args << o.err;
    EXPECT_NE(o.err.find(warning), std::string::npos) << o.err;
    const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
    EXPECT_EQ(summary["status"], "diverged") << args;
    EXPECT_NE(summary["message"].get<std::string>().find("diverged at t = "), std::string::npos) << summary["message"];
  }
  fs::path scene(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  fs::path dir_;
};

// `stepwise study --list` and the list in docs/usage.md are one list
TEST_F(Cli, TheStudiesListIsTheDocs) {
  const Output o = run("study --list");
  ASSERT_EQ(o.status, 0) << o.err;
  std::string listed;
  std::istringstream lines(o.out);
  for (std::string line; std::getline(lines, line);) {
    const auto gap = line.find("  ");
    ASSERT_NE(gap, std::string::npos) << line;
    listed += fmt::format("- `{}`: {}\n", line.substr(0, gap), line.substr(gap + 2));
  }
  const std::string usage = slurp(fs::path(STEPWISE_SOURCE_DIR) / "docs" / "usage.md");
  const std::string open = "<!-- stepwise study --list -->\n", close = "<!-- end of the list -->";
  const auto from = usage.find(open), to = usage.find(close);
  ASSERT_TRUE(from != std::string::npos && to != std::string::npos) << "docs/usage.md has no studies list";
  EXPECT_EQ(usage.substr(from + open.size(), to - from - open.size()), listed);
  EXPECT_EQ(run("study --out x").status, 2);
}

// outputs are written through temporary files (mkstemp: 0600) and keep the permissions the umask gives a file
// written the usual way: 0644 under umask 022, 0600 under 077
TEST_F(Cli, OutputsGetTheUmasksPermissionsNotTheTemporaryFiles) {
  for (const auto& [umask, mode] : {std::pair{"022", fs::perms(0644)}, std::pair{"077", fs::perms(0600)}}) {
    const fs::path out = dir_ / fmt::format("umask{}", umask);
    const std::string cmd = fmt::format("cd '{}' && umask {} && '{}' run scenes/pendulum.toml --t-end 0.1 --out '{}' >/dev/null 2>&1",
                                        STEPWISE_SOURCE_DIR, umask, STEPWISE_BIN, out.string());
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    for (const char* file : {"summary.json", "trajectory.csv"})
      EXPECT_EQ(fs::status(out / file).permissions() & fs::perms::all, mode) << file << " under umask " << umask;
  }
}

TEST_F(Cli, MethodsJsonListsEveryMethodOfTheTable) {
  const Output o = run("methods --json");
  ASSERT_EQ(o.status, 0) << o.err;
  const auto j = nlohmann::json::parse(o.out);
  ASSERT_EQ(j.size(), methods().size());
  for (size_t i = 0; i < methods().size(); ++i) EXPECT_EQ(j[i]["name"], std::string(methods()[i].name));
}

TEST_F(Cli, RunWritesTheContractsFilesAndFields) {
  for (const std::string step : {"--method rk4 --dt 1e-3", "--method cvode-bdf --rtol 1e-8", "--method gsl-rk8pd --rtol 1e-8"}) {
    const fs::path out = dir_ / "run";
    const Output o = run(fmt::format("run scenes/pendulum.toml {} --out '{}'", step, out.string()));
    ASSERT_EQ(o.status, 0) << step << ": " << o.err;
    const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
    for (const char* key : {"scene", "method", "status", "message", "t_end", "steps", "rhs_evals", "jac_evals",
                            "cpu_seconds", "final_state", "error", "events"})
      EXPECT_TRUE(s.contains(key)) << key;
    EXPECT_EQ(s["status"], "ok");
    EXPECT_TRUE(s["message"].is_null());
    EXPECT_TRUE(s["steps"].is_number_integer());
    EXPECT_TRUE(s["events"].is_array());
    EXPECT_LT(s["error"].get<double>(), 1e-5) << step;
    EXPECT_EQ(s["final_state"].size(), 2u);
    std::istringstream csv(slurp(out / "trajectory.csv"));
    std::string header;
    std::getline(csv, header);
    EXPECT_EQ(header.rfind("t,theta,omega", 0), 0u) << header;
    long rows = 0;
    for (std::string line; std::getline(csv, line);) ++rows;
    EXPECT_EQ(rows, 1001) << "t = 0 and every t_end/1000";
  }
}

TEST_F(Cli, BadInputExitsTwoWithOneLineNamingTheKeyAndWritesNothing) {
  const fs::path out = dir_ / "bad";
  const fs::path bad_toml = scene("broken.toml", "model = \"pendulum\"\n[parameters]\ng = = 3\n");
  const fs::path bad_model = scene("nomodel.toml", "model = \"pendulumm\"\n");
  const fs::path bad_key = scene("badkey.toml", "model = \"pendulum\"\n[parameters]\n\nlenght = 2.0\n");
  const fs::path bad_length = scene("length.toml", "model = \"pendulum\"\n[parameters]\nlength = -1.0\n[run]\ndt = 0.01\n");
  const fs::path big_dt = scene("bigdt.toml", "model = \"pendulum\"\n[run]\nt_end = 1.0\ndt = 2.0\n");
  const fs::path nan_value = scene("nan.toml", "model = \"pendulum\"\n[parameters]\ng = nan\n[run]\ndt = 0.01\n");
  // meshes: an index out of range, a non-finite vertex, an open mesh, and a mesh given to a model without one
  const std::string verts = "vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]\n";
  // pins: a node off the grid, a row that is not [row, column], and pins for a model without a grid
  const fs::path off_grid = scene("offgrid.toml", "model = \"cloth\"\n[run]\nmethod = \"implicit-euler\"\ndt = 0.01\n[pins]\nnodes = [[0, 0],\n [0, 40]]\n");
  const fs::path bad_pin = scene("badpin.toml", "model = \"cloth\"\n[pins]\nnodes = [[0, 0],\n [7]]\n");
  const fs::path no_pins_model = scene("pendpins.toml", "model = \"pendulum\"\n[run]\ndt = 0.01\n[pins]\nnodes = [[0, 0]]\n");
  const fs::path bad_index = scene("index.toml", "model = \"particle-mesh\"\n[mesh]\n" + verts + "triangles = [[0, 2, 1],\n [0, 1, 3],\n [0, 3, 9],\n [1, 2, 3]]\n");
  const fs::path bad_vertex = scene("vertex.toml", "model = \"particle-mesh\"\n[mesh]\nvertices = [[0, 0, 0],\n [1, nan, 0], [0, 1, 0], [0, 0, 1]]\ntriangles = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]\n");
  const fs::path open_mesh = scene("open.toml", "model = \"particle-mesh\"\n\n[mesh]\n" + verts + "triangles = [[0, 2, 1], [0, 1, 3], [0, 3, 2]]\n");
  // a dropped body's mesh must bound a convex solid: a dent (the apex pushed inside) is refused
  const fs::path dented = scene("dented.toml", "model = \"dropped-body\"\n[run]\nmethod = \"sequential-impulses\"\ndt = 1e-3\n[mesh]\n"
                                "vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.1, 0.1, -0.1], [0, 0, -1]]\n"
                                "triangles = [[0, 1, 3], [1, 2, 3], [2, 0, 3], [0, 4, 1], [1, 4, 2], [2, 4, 0]]\n");
  // one face turned the other way: the mesh is not consistently oriented, its mass properties undefined
  const fs::path misoriented = scene("misoriented.toml", "model = \"dropped-body\"\n[run]\nmethod = \"sequential-impulses\"\ndt = 1e-3\n[mesh]\n" + verts +
                                     "triangles = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 3, 2]]\n");
  const fs::path no_mesh_model = scene("pendmesh.toml", "model = \"pendulum\"\n[run]\ndt = 0.01\n[mesh]\n" + verts + "triangles = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]\n");
  const std::vector<std::pair<std::string, std::string>> cases{
      {fmt::format("run '{}' --out '{}'", bad_toml.string(), out.string()), "broken.toml:3:"},
      {fmt::format("run '{}' --out '{}'", bad_model.string(), out.string()), "nomodel.toml:1: model"},
      {fmt::format("run '{}' --out '{}'", bad_key.string(), out.string()), "badkey.toml:4: parameters.lenght"},
      {fmt::format("run '{}' --out '{}'", bad_length.string(), out.string()), "length.toml:3: parameters.length"},
      {fmt::format("run '{}' --out '{}'", big_dt.string(), out.string()), "bigdt.toml:4: run.dt"},
      {fmt::format("run '{}' --out '{}'", nan_value.string(), out.string()), "nan.toml:3: parameters.g"},
      {fmt::format("run scenes/pendulum.toml --method no-such-method --out '{}'", out.string()), "--method"},
      {fmt::format("run scenes/pendulum.toml --set no_such_key=1 --out '{}'", out.string()), "--set no_such_key"},
      {fmt::format("run scenes/pendulum.toml --set g=nan --out '{}'", out.string()), "--set g"},
      {fmt::format("run scenes/pendulum.toml --set length=0 --out '{}'", out.string()), "--set length"},
      {fmt::format("run scenes/pendulum.toml --dt -1 --out '{}'", out.string()), "--dt"},
      {fmt::format("run scenes/bouncing-ball.toml --set restitution=1.5 --out '{}'", out.string()), "--set restitution"},
      {fmt::format("run scenes/bouncing-ball.toml --event-location cubic --out '{}'", out.string()), "--event-location"},
      {fmt::format("run scenes/pendulum.toml --dt 0 --out '{}'", out.string()), "--dt"},
      {fmt::format("run scenes/pendulum.toml --t-end -3 --out '{}'", out.string()), "--t-end"},
      {fmt::format("run scenes/pendulum.toml --method cvode-bdf --rtol 0 --out '{}'", out.string()), "--rtol"},
      {fmt::format("run scenes/pendulum.toml --method rk4 --rtol 1e-6 --out '{}'", out.string()), "rk4"},
      {fmt::format("run scenes/flow-particle.toml --method symplectic-euler --out '{}'", out.string()), "symplectic-euler"},
      {"run scenes/pendulum.toml --out /proc/no-such-dir", "--out"},
      {fmt::format("run scenes/no-such-scene.toml --out '{}'", out.string()), "no-such-scene.toml"},
      {fmt::format("run '{}' --out '{}'", bad_index.string(), out.string()), "index.toml:6: mesh.triangles[2]: vertex index 9 out of range"},
      {fmt::format("run '{}' --out '{}'", bad_vertex.string(), out.string()), "vertex.toml:4: mesh.vertices[1]: not a finite number"},
      {fmt::format("run '{}' --out '{}'", open_mesh.string(), out.string()), "open.toml:3: mesh: a closed mesh needs at least 4 triangles"},
      {fmt::format("run '{}' --out '{}'", no_mesh_model.string(), out.string()), "pendmesh.toml:4: mesh: model pendulum takes no mesh"},
      {fmt::format("run '{}' --out '{}'", off_grid.string(), out.string()), "offgrid.toml:6: pins: node [0, 40] is off the 32 x 32 grid"},
      {fmt::format("run '{}' --out '{}'", bad_pin.string(), out.string()), "badpin.toml:4: pins.nodes[1]: expected 2 grid indices"},
      {fmt::format("run '{}' --out '{}'", no_pins_model.string(), out.string()), "pendpins.toml:5: pins: model pendulum takes no pins"},
      {fmt::format("run scenes/particle-mesh.toml --set plane_nx=0 --set plane_ny=0 --set plane_nz=0 --out '{}'", out.string()), "--set plane_nx: parameters plane_nx, plane_ny, plane_nz: the ground plane's normal is zero"},
      {fmt::format("run scenes/particle-system.toml --set count=1e12 --out '{}'", out.string()), "--set count"},
      {fmt::format("run scenes/particle-system.toml --set count=-5 --out '{}'", out.string()), "--set count"},
      {fmt::format("run scenes/particle-system.toml --method implicit-euler --out '{}'", out.string()), "--method: implicit-euler keeps dense"},
      // ARKODE: an unknown table, an IMEX method on a model without a split, a DIRK method's dense matrices
      {fmt::format("run scenes/pendulum.toml --method arkode-erk-nosuch --out '{}'", out.string()), "--method: unknown method 'arkode-erk-nosuch'"},
      {fmt::format("run scenes/pendulum.toml --method arkode-imex-ark548 --out '{}'", out.string()), "--method: arkode-imex-ark548 needs a model that declares a stiff/non-stiff split"},
      {fmt::format("run scenes/particle-system.toml --set count=20000 --method arkode-dirk-kvaerno43 --rtol 1e-6 --out '{}'", out.string()),
       "--method: arkode-dirk-kvaerno43 keeps dense"},
      {fmt::format("run scenes/water-drop.toml --set size=2 --out '{}'", out.string()), "--set size: parameter 'size' must be at least 3"},
      {fmt::format("run scenes/water-drop.toml --set c=0 --out '{}'", out.string()), "--set c"},
      {fmt::format("run scenes/water-drop.toml --set spacing=-0.1 --out '{}'", out.string()), "--set spacing"},
      {fmt::format("run scenes/water-drop.toml --set mu=-1 --out '{}'", out.string()), "--set mu"},
      {fmt::format("run scenes/water-drop.toml --set drop_x=5 --out '{}'", out.string()), "--set drop_x: parameter 'drop_x' = 5 m puts the drop outside the grid"},
      {fmt::format("run scenes/water-drop.toml --dt 0 --out '{}'", out.string()), "--dt"},
      {fmt::format("run scenes/pendulum.toml --method wave-fd --dt 1e-3 --out '{}'", out.string()), "--method: wave-fd needs a wave equation on a grid"},
      {fmt::format("run scenes/spinning-body.toml --set I3=5 --out '{}'", out.string()), "--set I3: principal moment I3 = 5 exceeds the sum of the other two"},
      {fmt::format("run scenes/spinning-body.toml --set I1=0 --out '{}'", out.string()), "--set I1"},
      {fmt::format("run scenes/spinning-body.toml --set qw0=0 --out '{}'", out.string()), "--set qw0: initial orientation quaternion (qw0, qx0, qy0, qz0) is zero"},
      {fmt::format("run scenes/spinning-body.toml --set angular_drag=0.1 --out '{}'", out.string()), "run.method: rigid-splitting needs a torque-free rigid body"},
      {fmt::format("run '{}' --out '{}'", dented.string(), out.string()), "dented.toml:5: mesh: mesh is not convex"},
      {fmt::format("run '{}' --out '{}'", misoriented.string(), out.string()), "misoriented.toml:5: mesh:"},
      {fmt::format("run scenes/tumbling-box.toml --method rk4 --out '{}'", out.string()), "--method: rk4 has no contact response"},
      {fmt::format("run scenes/spinning-body.toml --method sequential-impulses --out '{}'", out.string()), "--method: sequential-impulses needs rigid bodies in contact"},
      {fmt::format("run scenes/tumbling-box.toml --set density=0 --out '{}'", out.string()), "--set density"},
      {fmt::format("run scenes/tumbling-box.toml --set qw0=0 --set qx0=0 --out '{}'", out.string()), "--set qw0: initial orientation quaternion"},
      {fmt::format("run scenes/tumbling-box.toml --set ground_slope=2 --out '{}'", out.string()), "--set ground_slope"},
      {fmt::format("run scenes/stack-collapse.toml --set ground=0.5 --out '{}'", out.string()), "--set ground: parameter 'ground' must be 0 or 1"},
      {fmt::format("run scenes/stack-collapse.toml --set rows=2.5 --out '{}'", out.string()), "--set rows"},
      {fmt::format("run scenes/hanging-chain.toml --set nodes=0 --out '{}'", out.string()), "--set nodes"},
      {fmt::format("run scenes/hanging-chain.toml --set stiffness=-1 --out '{}'", out.string()), "--set stiffness"},
      {fmt::format("run scenes/hanging-chain.toml --set rest_length=nan --out '{}'", out.string()), "--set rest_length"},
      {fmt::format("run scenes/flag.toml --set rows=1 --out '{}'", out.string()), "--set rows: parameter 'rows' = 1 must be a whole number from 2"},
      {fmt::format("run scenes/flag.toml --set columns=2.5 --out '{}'", out.string()), "--set columns"},
      {fmt::format("run scenes/flag.toml --set pin_row=32 --set pin_column=0 --out '{}'", out.string()), "--set pin_row: parameter 'pin_row' = 32"},
      {fmt::format("run scenes/flag.toml --set pin_row=3 --out '{}'", out.string()), "pin_column"},
      {fmt::format("run scenes/flag.toml --set stiffness=-1 --out '{}'", out.string()), "--set stiffness"},
      {fmt::format("run scenes/flag.toml --set mass=0 --out '{}'", out.string()), "--set mass"},
      {fmt::format("run scenes/flag.toml --set damping=inf --out '{}'", out.string()), "--set damping"},
      {fmt::format("run scenes/hanging-cloth.toml --set pick_row=0 --set pick_column=99 --out '{}'", out.string()), "--set pick_column"},
      {fmt::format("run scenes/pendulum.toml --method fast-mass-spring --dt 0.01 --out '{}'", out.string()), "--method: fast-mass-spring needs a mass-spring system"},
  };
  for (const auto& [args, expected] : cases) {
    const Output o = run(args);
    EXPECT_EQ(o.status, 2) << args << "\n" << o.err;
    EXPECT_NE(o.err.find(expected), std::string::npos) << args << " said: " << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << args << " said: " << o.err;
    EXPECT_FALSE(fs::exists(out / "summary.json")) << args;
  }
}

TEST_F(Cli, ARigidBodyTakesItsMassAndMomentsFromASceneMesh) {
  // a box of half-extents (0.5, 1, 1.5) at density 2: m = 12 kg, I = m/3 (hy^2 + hz^2, ...) = (13, 10, 5)
  // about the mesh's x, y, z: principal moments 5, 10, 13, so w0 = (0.01, 1, 0) in the principal frame
  // has energy (5 * 0.01^2 + 10 * 1^2) / 2
  const std::string box = "[mesh]\nvertices = [[-0.5, -1, -1.5], [0.5, -1, -1.5], [0.5, 1, -1.5], [-0.5, 1, -1.5], "
                          "[-0.5, -1, 1.5], [0.5, -1, 1.5], [0.5, 1, 1.5], [-0.5, 1, 1.5]]\n";
  const std::string faces = "triangles = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], "
                            "[2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]]\n";
  const std::string inside_out = "triangles = [[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6], [0, 5, 1], [0, 4, 5], [1, 6, 2], [1, 5, 6], "
                                 "[2, 7, 3], [2, 6, 7], [3, 4, 0], [3, 7, 4]]\n";
  const std::string head = "model = \"rigid-body\"\n[parameters]\ndensity = 2.0\nwx0 = 0.01\nwy0 = 1.0\nwz0 = 0.0\n[run]\nmethod = \"rk4\"\ndt = 0.01\nt_end = 1.0\n";
  const fs::path out = dir_ / "meshbody";
  const Output o = run(fmt::format("run '{}' --out '{}'", scene("meshbody.toml", head + box + faces).string(), out.string()));
  ASSERT_EQ(o.status, 0) << o.err;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_NEAR(s["energy_initial"].get<double>() / ((5 * 1e-4 + 10) / 2), 1, tolerance::mass_properties_roundoff);
  // mass given as well, and the mesh inside out: refused, named
  const Output both = run(fmt::format("run '{}' --set mass=3 --out '{}'", scene("both.toml", head + box + faces).string(), (dir_ / "both").string()));
  EXPECT_EQ(both.status, 2);
  EXPECT_NE(both.err.find("--set mass: parameter 'mass' follows from the [mesh]"), std::string::npos) << both.err;
  const Output flipped = run(fmt::format("run '{}' --out '{}'", scene("flipped.toml", head + box + inside_out).string(), (dir_ / "flipped").string()));
  EXPECT_EQ(flipped.status, 2);
  EXPECT_NE(flipped.err.find("flipped.toml:11: mesh: mesh is inside out"), std::string::npos) << flipped.err;
}

TEST_F(Cli, TheSpinningBodyKeepsItsContractNames) {
  // parameters I1..I3, wx0..wz0; trajectory columns wx, wy, wz, energy; final_state energy and world Lx, Ly, Lz
  const fs::path out = dir_ / "spin";
  const Output o = run(fmt::format("run scenes/spinning-body.toml --set I1=1 --set I2=2 --set I3=3 --set wx0=0.05 --set wy0=1 --set wz0=0 --out '{}'", out.string()));
  ASSERT_EQ(o.status, 0) << o.err;
  const std::string csv = slurp(out / "trajectory.csv");
  const std::string header = csv.substr(0, csv.find('\n'));
  for (const char* column : {"wx", "wy", "wz", "energy"}) EXPECT_NE(("," + header + ",").find(fmt::format(",{},", column)), std::string::npos) << header;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  for (const char* key : {"energy", "Lx", "Ly", "Lz"}) EXPECT_TRUE(s["final_state"].contains(key)) << key;
  // torque-free: L = I w0 at the start (identity orientation), kept to round-off by the splitting
  const double roundoff = tolerance::roundoff_per_step * std::numeric_limits<double>::epsilon() * s["steps"].get<double>() * 2.0;
  EXPECT_NEAR(s["final_state"]["Lx"].get<double>(), 0.05, roundoff);
  EXPECT_NEAR(s["final_state"]["Ly"].get<double>(), 2.0, roundoff);
  EXPECT_NEAR(s["final_state"]["Lz"].get<double>(), 0.0, roundoff);
  EXPECT_EQ(s["projections"], s["steps"]);
}

TEST_F(Cli, TheTumblingBoxLandsBouncesAndSettlesOnAFace) {
  const fs::path out = dir_ / "tumble";
  const Output o = run(fmt::format("run scenes/tumbling-box.toml --out '{}'", out.string()));
  ASSERT_EQ(o.status, 0) << o.err;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  for (const char* key : {"energy", "kinetic", "px", "py", "pz", "Lx", "Ly", "Lz", "qw", "wz"}) EXPECT_TRUE(s["final_state"].contains(key)) << key;
  ASSERT_GT(s["events"].size(), 2u) << "it bounces";
  EXPECT_EQ(s["events"][0]["kind"], "impact");
  EXPECT_EQ(s["events"][0]["event"], "contacts");
  // first touch: the centre falls freely from 1.5 m until the lowest point, between hz = 0.1 m and the
  // half-diagonal below the centre whatever the spin has turned, meets the ground (within a step)
  const double z0 = 1.5, g = 9.81, diagonal = std::sqrt(0.3 * 0.3 + 0.2 * 0.2 + 0.1 * 0.1), dt = 1e-3;
  EXPECT_GE(s["events"][0]["t"].get<double>(), std::sqrt(2 * (z0 - diagonal) / g));
  EXPECT_LE(s["events"][0]["t"].get<double>(), std::sqrt(2 * (z0 - 0.1) / g) + dt);
  // at rest on its largest face (hz = 0.1 m below the centre), less the settling of one step of gravity
  EXPECT_NEAR(s["final_state"]["z"].get<double>(), 0.1, tolerance::resting_settle(9.81, 1e-3));
  EXPECT_LT(s["final_state"]["kinetic"].get<double>(), tolerance::resting_kinetic(0.6 * 0.4 * 0.2 * 500)) << "m = 24 kg";
}

TEST_F(Cli, TheHangingChainKeepsItsContractNamesAndSettles) {
  // parameters nodes, mass, stiffness, rest_length, damping, g; final_state y_bottom
  const fs::path out = dir_ / "chain";
  const Output o = run(fmt::format("run scenes/hanging-chain.toml --set nodes=5 --set mass=0.2 --set stiffness=50 --set rest_length=0.2 "
                                   "--set damping=2 --set g=9.81 --out '{}'", out.string()));
  ASSERT_EQ(o.status, 0) << o.err;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  // the spring i places from the bottom carries i m g: y_bottom = -(N l + m g N (N + 1) / (2 c))
  const double exact = -(5 * 0.2 + 0.2 * 9.81 * 15 / 50);
  EXPECT_NEAR(s["final_state"]["y_bottom"].get<double>(), exact,
              tolerance::chain_settled(100, 0.2 * 9.81 * 15 / 50, 5, 0.2, 50, 2) + 1e-12);
}

TEST_F(Cli, TheBouncingBallWritesItsImpactsAndRestIntoTheSummary) {
  const fs::path out = dir_ / "ball";
  const Output o = run(fmt::format("run scenes/bouncing-ball.toml --method cvode-bdf --rtol 1e-10 --out '{}'", out.string()));
  ASSERT_EQ(o.status, 0) << o.err;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  ASSERT_GT(s["events"].size(), 2u);
  EXPECT_EQ(s["events"][0]["kind"], "impact");
  EXPECT_NEAR(s["events"][0]["t"].get<double>(), std::sqrt(2 * 1.0 / 9.81), 1e-8);
  EXPECT_EQ(s["events"].back()["kind"], "rest");
  EXPECT_EQ(s["final_state"]["y"], 0.0);
}

TEST_F(Cli, AParticleSystemWritesItsSummaryRatherThanEveryParticle) {
  const fs::path out = dir_ / "particles";
  const Output o = run(fmt::format("run scenes/particle-system.toml --set count=2000 --t-end 0.2 --out '{}'", out.string()));
  ASSERT_EQ(o.status, 0) << o.err;
  const std::string csv = slurp(out / "trajectory.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "t,energy,kinetic,centroid_x,centroid_y,centroid_z,rms_radius,max_speed,contacts");
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["final_state"].size(), 8u);
  EXPECT_GT(s["final_state"]["contacts"].get<double>(), 0);
  EXPECT_TRUE(s["error"].is_null()) << "no exact solution with repulsion";
  // without repulsion every particle has an exact solution, and rk4 at dt = 5e-3 is within 2e-10 of it
  const Output exact = run(fmt::format("run scenes/particle-system.toml --set count=2000 --set repulsion=0 --method rk4 --t-end 0.2 --out '{}'", out.string()));
  ASSERT_EQ(exact.status, 0) << exact.err;
  EXPECT_LT(nlohmann::json::parse(slurp(out / "summary.json"))["error"].get<double>(), tolerance::rk4_oscillator_error);
}

TEST_F(Cli, ADivergedRunExitsOneWithItsSummaryWritten) {
  const fs::path out = dir_ / "diverged";
  const Output o = run(fmt::format("run scenes/projectile.toml --set drag=100 --method euler --dt 0.05 --out '{}'", out.string()));
  EXPECT_EQ(o.status, 1) << o.err;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["status"], "diverged");
  EXPECT_TRUE(s["error"].is_null());
  EXPECT_LT(s["t_stop"].get<double>(), s["t_end"].get<double>());
  EXPECT_NE(s["message"].get<std::string>().find("diverged at t ="), std::string::npos);
  for (const auto& [name, value] : s["final_state"].items()) EXPECT_TRUE(value.is_number()) << name;
}

TEST_F(Cli, AWaveStepPastTheStabilityLimitIsWarnedRunAndReportedDiverged) {
  // water-drop's grid: d = 0.02 m, c = 1 m/s, N = 63: limit d / (sqrt(2) c cos(pi/126)) = 0.0141465 s
  expect_warned_and_diverged("run scenes/water-drop.toml --dt 0.015", "--dt: warning: dt = 0.015 s is past wave-fd's stability limit 0.0141465 s");
  // and below it: ok, energy and max_abs_z in final_state as the contract names them
  const fs::path ok = dir_ / "below";
  ASSERT_EQ(run(fmt::format("run scenes/water-drop.toml --dt 0.014 --out '{}'", ok.string())).status, 0);
  const auto fine = nlohmann::json::parse(slurp(ok / "summary.json"));
  EXPECT_EQ(fine["status"], "ok");
  for (const char* key : {"energy", "max_abs_z"}) EXPECT_TRUE(fine["final_state"].contains(key)) << key;
}

TEST_F(Cli, AnExplicitClothStepPastItsStiffestModesLimitIsWarnedRunAndReportedDiverged) {
  expect_warned_and_diverged("run scenes/flag.toml --method symplectic-euler --dt 0.002 --t-end 1",
                             "--dt: warning: dt = 0.002 s is past symplectic-euler's stability limit");
  // the cloth scenes run as written, and the flag's summary carries what the flag's users look at
  for (const char* scene : {"flag", "flag-on-pole", "hanging-cloth", "cloth-on-sphere"}) {
    const fs::path ok = dir_ / scene;
    const Output r = run(fmt::format("run scenes/{}.toml --t-end 0.2 --out '{}'", scene, ok.string()));
    ASSERT_EQ(r.status, 0) << scene << r.err;
    const auto fine = nlohmann::json::parse(slurp(ok / "summary.json"));
    EXPECT_EQ(fine["status"], "ok") << scene;
    for (const char* key : {"energy", "y_min", "max_stretch"}) EXPECT_TRUE(fine["final_state"].contains(key)) << scene << key;
  }
}

TEST_F(Cli, ARerunReplacesOutputsWholeAndLeavesNoTemporaryFiles) {
  const fs::path out = dir_ / "again";
  ASSERT_EQ(run(fmt::format("run scenes/pendulum.toml --out '{}'", out.string())).status, 0);
  ASSERT_EQ(run(fmt::format("run scenes/pendulum.toml --method euler --out '{}'", out.string())).status, 0);
  EXPECT_EQ(nlohmann::json::parse(slurp(out / "summary.json"))["method"], "euler");
  long files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(out)) ++files;
  EXPECT_EQ(files, 2);
}

TEST_F(Cli, ReportRefusesToReplaceADirectoryThatIsNotAReport) {
  // the report swaps its directory in whole; `--out report` in the source tree must not delete the sources
  const fs::path precious = dir_ / "precious";
  fs::create_directories(precious);
  std::ofstream(precious / "source.cpp") << "int main() {}\n";
  const Output o = run(fmt::format("report --quick --out '{}'", precious.string()));
  EXPECT_EQ(o.status, 2) << o.err;
  EXPECT_NE(o.err.find("not a stepwise report"), std::string::npos) << o.err;
  EXPECT_TRUE(fs::exists(precious / "source.cpp"));
}

}  // namespace
}  // namespace stepwise
