// The report's study: advice on a user's equations: `stepwise advise` run on two shipped equation scenes, Van der
// Pol at mu = 1 and at mu = 1000 (stiff by its spectrum), at an error of 1e-6 each, within a budget.
#include "report/advise.hpp"
#include "report/cost_model.hpp"
#include "report/user_scene.hpp"

namespace stepwise {
namespace {

StudyOutput advice_section(const StudyContext& ctx) {
  // the quick report's budget is a minute in all: 3 s each; the full report's 15
  const double budget = ctx.quick ? 3 : 15, target = 1e-6;
  StudyOutput out;
  out.markdown = fmt::format(
      "`stepwise advise` asks a scene of the user's which method is cheapest for an error at t_end, and measures the answer (docs/usage.md): "
      "here on two scenes written as equations (docs/scenes.md, \"Your own equations\": parsed, differentiated and compiled when loaded), "
      "at {:.0e} within {:g} s each. The runs on the report's threads share the machine with nothing else, so their CPU times are those of "
      "a user's own `stepwise advise`.\n\n",
      target, budget);
  std::vector<Advice> advices;
  double unknowns = 0;
  for (const char* scene : {"van-der-pol", "van-der-pol-stiff"}) {
    RunOptions options;
    options.scene_file = scenes_directory() + "/" + scene + ".toml";
    const StudyScene s = user_study_scene(options);
    unknowns = scene_model(s)->size();
    advices.push_back(advise(s, target, budget, ctx.threads));
    out.markdown += advice_markdown(advices.back(), fmt::format("stepwise advise scenes/{}.toml --error {:g} --budget {:g}", scene, target, budget), "###");
    out.markdown += "\n";
    out.figures.push_back(advice_figure(advices.back()));
  }
  // what the stiff scene's advice says of the label "stiff", from its own numbers
  const Advice& stiff = advices.back();
  if (!stiff.candidates.empty() && stiff.candidates[0].cheapest) {
    const Method& picked = *find_method(stiff.candidates[0].method);
    const bool implicit = solves_newton_systems(picked) || picked.dense != DenseMatrices::none;
    out.markdown += implicit
        ? fmt::format("On {} the spectrum says stiff (stiffness {:.3g}) and the measured cheapest is an implicit method, `{}`.\n\n", stiff.scene,
                      stiff.stiffness, picked.name)
        : fmt::format("On {} the spectrum says stiff (stiffness {:.3g}: an explicit method is held near 2.8 / {:.3g} s a step), yet the measured "
                      "cheapest is the explicit `{}`: on {} unknowns an explicit step costs so little that its stability-bound steps undercut "
                      "the implicit methods' fewer, dearer ones at this error. The advice measures rather than follows the label (at mu = 1e6, "
                      "`--set mu=1e6`, the explicit methods lose by two orders of magnitude: docs/findings.md).\n\n",
                      stiff.scene, stiff.stiffness, stiff.fastest_decay, picked.name, unknowns);
  }
  // the finding: on the stiff scene, the advised method against the best of the other kind (implicit or explicit), in CPU
  // seconds as the candidates' table has them
  if (!stiff.candidates.empty() && stiff.candidates[0].cheapest) {
    const auto implicit = [](const Candidate& c) {
      const Method& m = *find_method(c.method);
      return solves_newton_systems(m) || m.dense != DenseMatrices::none;
    };
    const Candidate& best = stiff.candidates[0];
    const Candidate* other = nullptr;
    for (const Candidate& c : stiff.candidates)
      if (c.cheapest && implicit(c) != implicit(best) && (!other || c.cheapest->cpu_seconds < other->cheapest->cpu_seconds)) other = &c;
    if (other)
      out.findings.push_back(fmt::format("{} on {} (stiffness {:.3g}) the measured cheapest method for an error of {:.0e} is the {} `{}`, "
                                         "{:.3g} s of CPU, against {:.3g} s for the best {} one, `{}`.",
                                         implicit(best) ? "**A stiff system, measured**:" : "**\"Stiff\" need not mean implicit**:", stiff.scene,
                                         stiff.stiffness, target, implicit(best) ? "implicit" : "explicit", best.method, best.cheapest->cpu_seconds,
                                         other->cheapest->cpu_seconds, implicit(best) ? "explicit" : "implicit", other->method));
  }
  AdviceTables tables = advice_tables(advices);
  out.tables = {{"advice_sweep", std::move(tables.sweep)}, {"advice_summary", std::move(tables.summary)}, {"advice_candidates", std::move(tables.candidates)}};
  return out;
}

}  // namespace

Study advice_study() { return {"advice", "Advice on your own equations: the cheapest method, measured", advice_section}; }

}  // namespace stepwise
