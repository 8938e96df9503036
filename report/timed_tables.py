"""What measured time decides in the report's CSVs: the one list that scripts/compare-reports (two reports of one
code) and verification/tests/mpi_ranks.py (a report on ranks against one process) both read.

- TIMING: columns that are CPU or wall times, or rates and ratios of them (by name);
- CHOSEN_BY_TIME: tables whose rows are chosen by measured time (the cheapest method at a target, a Pareto front,
  a verdict against a CPU budget, the step a budget buys, the scaling model fitted to timed cells, the step limits
  an advice's budget had time to search);
- KEPT_FACTOR_FILES and KEPT_FACTOR_METHODS: tables, and rows of methods, whose results move by the solver's
  round-off because a factor is kept across steps while measured time says it pays (implicit Euler on the cloth,
  fast mass-spring; backward Euler's Newton starts from the linearised step, and the cloth solvers' rows are
  measured against that Newton's runs, as are the constraints study's compliant rod's); KEPT_FACTOR_COUNTS: their counts of work, which the reuse changes;
- kept_factor_tolerance(): how far such a result may move, verification/tolerances.hpp's kept_factor_reproducibility;
  kept_factor_agree(): two cells of such a row alike, an offset in pixels (PIXEL_OFFSETS) to kept_factor_pixel_offset.
"""
import functools
import os
import re

TIMING = re.compile(r"(cpu|seconds|_ms|_ns|ms_per|per_second|per_simulated|speed|halo_share|over_best|over_budget|at_equal_cpu)")
CHOSEN_BY_TIME = {
    "advice_candidates.csv", "advice_summary.csv", "advice_sweep.csv", "recommendations.csv", "work_precision_pareto.csv",
    "cloth_realtime_verdicts.csv", "constraints_cheapest.csv", "constraints_substeps.csv", "side_by_side.csv",
    "side_by_side_frames.csv", "scaling_crossover.csv", "scaling_model.csv", "scaling_cell.csv",
    "continuum_cloth_equal_cpu.csv", "pde_scene_candidates.csv", "pde_scene_summary.csv", "pde_scene_sweep.csv", "pde_scene_limits.csv",
}
KEPT_FACTOR_FILES = {"cloth_families.csv", "cloth_momentum.csv", "cloth_realtime.csv", "continuum_cloth_newton.csv", "cloth_solvers.csv",
                     "constraints_compliant_rod.csv"}
KEPT_FACTOR_METHODS = {"implicit-euler", "implicit-euler-newton", "fast-mass-spring"}
KEPT_FACTOR_COUNTS = {"rhs_evals", "jac_evals", "linear_solves", "factorizations", "newton_iterations", "newton_iterations_mean",
                      "line_search_halvings_mean"}


def kept_factor_row(name, header, row):
    """whether a row's results are reproducible only to the kept factor's round-off"""
    method = header.index("method") if "method" in header else None
    return name in KEPT_FACTOR_FILES or (method is not None and row[method] in KEPT_FACTOR_METHODS)


@functools.lru_cache(maxsize=None)
def tolerance(name, root=os.path.dirname(os.path.dirname(os.path.abspath(__file__)))):
    """verification/tolerances.hpp's constant `name` (read once: a comparison asks it for every cell)"""
    text = open(os.path.join(root, "verification", "tolerances.hpp")).read()
    return float(re.search(name + r"\s*=\s*([0-9.eE+-]+)", text).group(1))


def kept_factor_tolerance(root=os.path.dirname(os.path.dirname(os.path.abspath(__file__)))):
    return tolerance("kept_factor_reproducibility", root)


# the kept-factor tables' offsets in pixels: a difference of two runs' positions, whose round-off is the positions'
PIXEL_OFFSETS = {"pixels_off", "pixels_off_true_motion", "pixels_vs_converged"}


def kept_factor_agree(column, a, b, root=os.path.dirname(os.path.dirname(os.path.abspath(__file__)))):
    """two cells of a kept-factor row alike: an offset in pixels within kept_factor_pixel_offset (or the residual of
    itself), any other number within kept_factor_reproducibility (numbers_agree)"""
    rel = kept_factor_tolerance(root)
    if column not in PIXEL_OFFSETS:
        return numbers_agree(a, b, rel)
    try:
        x, y = float(a), float(b)
    except ValueError:
        return a == b
    return x == y or (x != x and y != y) or abs(x - y) <= max(tolerance("kept_factor_pixel_offset", root), rel * max(abs(x), abs(y)))


def numbers_agree(a, b, rel):
    """two cells alike to `rel`: relative to the value, absolute below 1 (a round-off quantity, a momentum error of
    1e-15, differs by round-off); text cells alike exactly"""
    try:
        x, y = float(a), float(b)
    except ValueError:
        return a == b
    if x == y or (x != x and y != y):
        return True
    return abs(x - y) <= rel * max(abs(x), abs(y), 1.0)
