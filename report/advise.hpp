// `stepwise advise SCENE.toml --error E [--budget S] --out DIR`: which method is cheapest for this scene at this
// accuracy, measured rather than guessed. A short work-precision sweep of every method that applies, each method
// refined until it first meets E (then between its last two settings, for the cheapest that does), under a
// budget of wall-clock seconds; the stiffness read off the exact Jacobian's spectrum along a reference run; and
// why each other method lost. The advisor is a budgeted study on one scene.
#pragma once

#include <stepwise/report/studies.hpp>
#include <stepwise/report/studies/study_scenes.hpp>
#include <stepwise/run/csv.hpp>
#include <stepwise/run/prepare.hpp>
#include <stepwise/solvers/stability.hpp>  // stiffness_threshold

#include <nlohmann/json_fwd.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace stepwise {

// one run of the sweep
struct AdvisePoint {
  std::string method;
  std::optional<double> dt;  // fixed step, or
  double rtol = 0, atol = 0;  // the tolerances of an adaptive run
  std::optional<double> error;  // at t_end against the exact solution or the reference; empty: diverged or failed
  double cpu_seconds = 0, rhs_evals = 0;
  long steps = 0;
  Status status = Status::ok;
  std::string message;
  static auto fields(auto& s) { return std::tie(s.method, s.dt, s.rtol, s.atol, s.error, s.cpu_seconds, s.rhs_evals, s.steps, s.status, s.message); }
  std::string setting() const;  // "dt 0.001" or "rtol 1e-06"
};

// a method's verdict: the cheapest to meet the error, the next, one that meets it at a higher cost, one that
// meets it only past the budget or not within its sweep, one that diverged, one whose runs failed
enum class Verdict { advised, runner_up, meets, too_costly, unstable, failed };
std::string_view to_string(Verdict verdict);  // "advised", "runner-up", "meets", "too costly", "unstable", "failed"

// one method's verdict
struct Candidate {
  std::string method;
  Verdict status = Verdict::failed;
  std::string reason;  // why it lost, in words (empty for the advised method)
  std::optional<AdvisePoint> cheapest;   // its cheapest point meeting E
  std::optional<double> predicted_stable_dt;  // from the spectrum and its stability function, where it has one
  std::optional<double> searched_stable_dt;   // an explicit fixed-step method's, found by bisection from the initial state
};

struct Advice {
  std::string scene;
  double target = 0;           // E
  double budget_seconds = 0;
  double elapsed_seconds = 0;  // the advice's wall clock, all of it
  std::string reference;       // what the errors are measured against
  std::optional<size_t> event_count;  // a scene with events of its own: how many the reference run found (their times count in the error)
  double reference_agreement = 0;  // the two reference runs' difference (0 against an exact solution)
  // the spectrum of the exact Jacobian along the reference run
  double fastest_decay = 0;    // max over the run of -Re(lambda) (1/s)
  double spectral_radius = 0;  // max over the run of |lambda| (1/s)
  double stiffness = 0;        // t_end x fastest_decay: the steps a stable explicit method cannot go below, within a factor
  bool stiff = false;
  std::vector<AdvisePoint> points;
  std::vector<Candidate> candidates;  // the advised method first, then the runner-up, then by cost
  std::optional<AdvisePoint> reproduced;  // the advised setting run again as `stepwise run` runs it
};

// InputError, the command's one-line message, unless E is a positive finite number and the budget 1 to 86400 s
void check_advice_request(double error, double budget_seconds);

// the advice for a scene; `threads` runs the sweep's methods side by side. The budget bounds the whole advice: its
// reference gets half of it (ReferenceOutOfTime past that), saying its progress through `progress` where one is given
Advice advise(const StudyScene& scene, double target, double budget_seconds, int threads,
              const std::function<void(const std::string& line)>& progress = {});

// the advice in Markdown under a heading of `heading` ("#", "###"): the answer first, the stiffness, the table of
// verdicts; `command` is the command line it came from
std::string advice_markdown(const Advice& advice, const std::string& command, const std::string& heading);

// advice.json's text: the contract's fields (method, dt or rtol and atol, error, cpu_seconds, stiff, runner_up,
// candidates) and the spectrum, reference and reproduction behind them; `scene_file` as the user gave it
nlohmann::json advice_json(const Advice& advice, const std::string& scene_file);
std::string advice_json_text(const Advice& advice, const std::string& scene_file);

// the sweeps' points (advice_sweep.csv) and one row per advice (advice_summary.csv: what plot.py marks)
struct AdviceTables {
  Table sweep, summary, candidates;  // candidates: each method's verdict (advice_candidates.csv)
};
AdviceTables advice_tables(const std::vector<Advice>& advices);
// the advice's figure (TABLES_SCENE.png): the sweep's error against CPU time per method, the error asked, the
// advised point, from the tables TABLES_sweep and TABLES_summary (advice_tables' sweep and summary)
Figure advice_figure(const Advice& advice, const std::string& tables = "advice");

// one method's sweep at every third of a decade of rtol (or of a halving of dt) from the coarsest until it meets
// the target, without the advice's budget (at most `seconds` of CPU): what the advice's pick is checked against
std::vector<AdvisePoint> full_sweep(const StudyScene& scene, const Method& method, double target, const Eigen::VectorXd* reference, double seconds);

// the command: checks the inputs (exit 2), then writes DIR/advice.md, advice.json, advice_sweep.csv and the
// figure; exit 0 when a method met E, 1 when none did
struct AdviseOptions {
  RunOptions run;  // the scene file and --set
  double error = 0;
  double budget = 30;
  int threads = 0;
  std::string out;
};
int advise_command(const AdviseOptions& options);

}  // namespace stepwise
