// A method added through the public registration (solvers/method_table.hpp's add_method) with an option of its own is
// a method like the table's, from that one declaration: the command line offers its option (`run --help`), `methods
// --json` lists it with its range and default, a value out of range or a method that does not take it is refused
// (exit 2, one line naming the option, the value and the method), and a run uses it and echoes it in summary.json.
// What adding a method takes is its file, its test and the build list (docs/architecture.md); this test is all three
// at once for a toy: explicit Euler in `pieces` equal substeps a step.
#include "app/cli.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/method_table.hpp"
#include "solvers/run_support.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace stepwise {
namespace {
namespace fs = std::filesystem;

// y += (h / pieces) f(t, y), `pieces` times
class PiecewiseEuler final : public FixedStepper {
 public:
  PiecewiseEuler(const CountedSystem& system, int pieces) : system_(system), pieces_(pieces), f_(system.size()) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    const double piece = h / pieces_;
    y_next = y;
    for (int k = 0; k < pieces_; ++k) {
      system_.rhs(t + k * piece, y_next, f_);
      for (Eigen::Index i = 0; i < y_next.size(); ++i) y_next[i] += piece * f_[i];
    }
    return true;
  }

 private:
  const CountedSystem& system_;
  int pieces_;
  Eigen::VectorXd f_;
};

constexpr int most_pieces = 64;

void register_toy() {
  if (find_method("toy-euler")) return;
  add_method({
      .name = "toy-euler",
      .family = Family::euler,
      .source = Source::hand_written,
      .description = "explicit Euler in equal pieces of a step (a test's method)",
      .order = {1, 1, "1"},
      .options = {{.name = "pieces", .max = most_pieces, .fallback = 2, .help = "equal Euler substeps a step"}},
      .make =
          [](const Method& method, const StepControl& control) {
            return std::make_unique<FixedStepIntegrator>(method, control, [pieces = method.whole_setting(control, "pieces")](const CountedSystem& system) {
              return std::make_unique<PiecewiseEuler>(system, pieces);
            });
          },
  });
}

struct Typed {
  int status;
  std::string out, err;
};

// `stepwise ARGS...` as a user types it, in this process (the toy is in this process's table)
Typed stepwise(std::vector<std::string> args) {
  args.insert(args.begin(), "stepwise");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  const int status = command_line(static_cast<int>(argv.size()), argv.data());
  std::string out = testing::internal::GetCapturedStdout(), err = testing::internal::GetCapturedStderr();
  return {status, std::move(out), std::move(err)};
}

class ToyMethod : public ::testing::Test {
 protected:
  void SetUp() override {
    register_toy();
    dir_ = fs::temp_directory_path() / ("stepwise-toy-" + std::to_string(::getpid()) + "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string scene() const { return std::string(STEPWISE_SOURCE_DIR) + "/scenes/pendulum.toml"; }
  nlohmann::json summary(const std::string& run) const { return nlohmann::json::parse(std::ifstream(dir_ / run / "summary.json")); }
  fs::path dir_;
};

TEST_F(ToyMethod, ItsOptionIsOnTheCommandLine) {
  for (const char* command : {"run", "render"}) {
    const Typed help = stepwise({command, "--help"});
    EXPECT_EQ(help.status, 0) << command;
    const auto at = help.out.find("--pieces INT");
    ASSERT_NE(at, std::string::npos) << command << "'s help lacks --pieces:\n" << help.out;
    const std::string line = help.out.substr(at, help.out.find('\n', at) - at);
    EXPECT_NE(line.find("equal Euler substeps a step, default 2 (toy-euler)"), std::string::npos) << line;
    EXPECT_NE(line.find("1..64"), std::string::npos) << line;
  }
}

TEST_F(ToyMethod, MethodsJsonListsItsOption) {
  const Typed listed = stepwise({"methods", "--json"});
  ASSERT_EQ(listed.status, 0) << listed.err;
  const auto all = nlohmann::json::parse(listed.out);
  const auto toy = std::find_if(all.begin(), all.end(), [](const auto& m) { return m["name"] == "toy-euler"; });
  ASSERT_NE(toy, all.end());
  ASSERT_EQ((*toy)["options"].size(), 1u);
  const auto& pieces = (*toy)["options"][0];
  EXPECT_EQ(pieces["name"], "pieces");
  EXPECT_EQ(pieces["type"], "whole");
  EXPECT_EQ(pieces["minimum"], 1);
  EXPECT_EQ(pieces["maximum"], most_pieces);
  EXPECT_EQ(pieces["default"], 2);
  EXPECT_EQ(pieces["summary_key"], "pieces");
}

TEST_F(ToyMethod, ItsOptionOutOfRangeOrOnAnotherMethodIsRefused) {
  const struct {
    std::vector<std::string> args;
    std::string says;
  } cases[] = {
      {{"--method", "toy-euler", "--pieces", "65"}, "--pieces 65: must be a whole number in 1..64"},
      {{"--method", "toy-euler", "--pieces", "1.5"}, "--pieces 1.5: must be a whole number in 1..64"},
      {{"--method", "toy-euler", "--pieces", "many"}, "--pieces many: not a number (a whole number in 1..64)"},
      {{"--method", "rk4", "--pieces", "4"}, "--pieces: rk4 takes no --pieces (toy-euler does)"},
      {{"--method", "toy-euler", "--iterations", "4"}, "--iterations: toy-euler takes no --iterations"},
  };
  for (const auto& c : cases) {
    std::vector<std::string> args{"run", scene(), "--dt", "0.01", "--t-end", "0.1", "--out", (dir_ / "refused").string()};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const Typed r = stepwise(args);
    EXPECT_EQ(r.status, 2) << c.says;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "refused")) << c.says;
  }
}

// four pieces of a 0.01 s step are Euler's steps of 0.0025 s: the run took the option, and says so
TEST_F(ToyMethod, ARunUsesItsOptionAndEchoesIt) {
  const std::vector<std::string> common{"run", scene(), "--t-end", "1"};
  auto args = common;
  args.insert(args.end(), {"--method", "toy-euler", "--dt", "0.01", "--pieces", "4", "--out", (dir_ / "toy").string()});
  ASSERT_EQ(stepwise(args).status, 0);
  args = common;
  args.insert(args.end(), {"--method", "euler", "--dt", "0.0025", "--out", (dir_ / "euler").string()});
  ASSERT_EQ(stepwise(args).status, 0);
  args = common;
  args.insert(args.end(), {"--method", "toy-euler", "--dt", "0.01", "--out", (dir_ / "default").string()});
  ASSERT_EQ(stepwise(args).status, 0);
  const auto toy = summary("toy"), euler = summary("euler"), fallback = summary("default");
  EXPECT_EQ(toy["pieces"], 4);
  EXPECT_EQ(fallback["pieces"], 2);
  EXPECT_FALSE(euler.contains("pieces"));
  // the same steps in the same arithmetic, but for the order of f's terms the compiler may fuse: round-off per step
  const double steps = 400;
  for (const auto& [name, value] : euler["final_state"].items()) {
    const double x = value.get<double>();
    EXPECT_NEAR(toy["final_state"][name].get<double>(), x, tolerance::roundoff_per_step * steps * 0x1p-52 * std::max(1.0, std::abs(x))) << name;
    EXPECT_GT(std::abs(fallback["final_state"][name].get<double>() - x), 0.0) << name << ": two pieces a step ran as four";
  }
}

}  // namespace
}  // namespace stepwise
