#!/usr/bin/env python3
"""stepwise.solve_ivp against scipy.integrate.solve_ivp, at equal error.

usage: PYTHONPATH=build/release/python /usr/bin/python3 bench/python_vs_scipy.py [--quick] [--events-only]

Per problem (the pendulum at 170 degrees, Lorenz, Van der Pol mu = 1; Van der Pol mu = 1000 over one relaxation cycle, t = 2000, for the stiff
methods against Radau, BDF and LSODA), each method is swept over rtol (thirds of a decade, atol = rtol 1e-3) and
each solve timed (wall clock on this otherwise idle machine: the least over PASSES passes of the best of REPEATS
means, below) with its error at t_end against a reference (SciPy's DOP853, or Radau on the stiff problem, at
rtol 1e-13). Last, a ball bouncing with events, each side's impact times against the reference's. Each side's cost at an error
E is read off its own work-precision curve (log-log interpolation between the two sweep points around E, not
the nearest tolerance), its best method's; the ratio is SciPy's best over stepwise's best, for a Python fun and for
the same equations compiled (stepwise.Equations). `fun share` is the time the Python fun alone takes for the
calls stepwise's solve made (calls x the fun's own cost per call, timed in a loop), over the solve's time: what
a compiled stepper cannot remove."""
import argparse
import math
import sys
import time

import numpy as np
import scipy.integrate

import stepwise

parser = argparse.ArgumentParser()
parser.add_argument("--quick", action="store_true", help="fewer repeats and tolerances (a smoke run)")
parser.add_argument("--events-only", action="store_true", help="the bouncing ball's table alone")
args = parser.parse_args()
REPEATS = 1 if args.quick else 3
# each method's sweep is run PASSES times, the methods of both sides taken in turn in each pass, and each point's
# time is the least over the passes: this machine's speed drifts by up to 2x over seconds, so a side swept once
# may land in a slow phase the other side's sweep missed (its own repeats, back to back, would not tell)
PASSES = 1 if args.quick else 3
ERRORS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9]


def pendulum(t, y):
    return np.array([y[1], -9.81 * np.sin(y[0])])


def lorenz(t, y):
    return np.array([10.0 * (y[1] - y[0]), y[0] * (28.0 - y[2]) - y[1], y[0] * y[1] - 8.0 / 3.0 * y[2]])


def vdp(mu):
    def f(t, y):
        return np.array([y[1], mu * (1 - y[0] ** 2) * y[1] - y[0]])
    return f


def vdp_jac(mu):
    def j(t, y):
        return np.array([[0.0, 1.0], [-2 * mu * y[0] * y[1] - 1, mu * (1 - y[0] ** 2)]])
    return j


PROBLEMS = [
    # name, fun, jac, equations, t_end, y0, stepwise methods, SciPy methods, reference method
    ("pendulum 170 deg", pendulum, None, stepwise.Equations({"x": "v", "v": "-g*sin(x)"}, parameters={"g": 9.81}),
     10.0, [math.radians(170), 0.0], ["verner98", "tsitouras54", "gsl-rk8pd"], ["RK45", "DOP853", "LSODA"], "DOP853"),
    ("Lorenz", lorenz, None,
     stepwise.Equations({"x": "s*(y-x)", "y": "x*(r-z)-y", "z": "x*y-b*z"}, parameters={"s": 10.0, "r": 28.0, "b": 8.0 / 3.0}),
     2.0, [1.0, 1.0, 1.0], ["verner98", "tsitouras54", "gsl-rk8pd"], ["RK45", "DOP853", "LSODA"], "DOP853"),
    ("Van der Pol mu=1", vdp(1.0), None, stepwise.Equations({"x": "v", "v": "mu*(1-x^2)*v-x"}, parameters={"mu": 1.0}),
     10.0, [2.0, 0.0], ["verner98", "tsitouras54", "gsl-rk8pd"], ["RK45", "DOP853", "LSODA"], "DOP853"),
    ("Van der Pol mu=1000 (stiff)", vdp(1000.0), vdp_jac(1000.0), stepwise.Equations({"x": "v", "v": "mu*(1-x^2)*v-x"}, parameters={"mu": 1000.0}),
     2000.0, [2.0, 0.0], ["rodas5", "rodas4", "cvode-bdf", "gsl-bsimp"], ["Radau", "BDF", "LSODA"], "Radau"),
]


def timed(solve):
    """the best of REPEATS timings of a solve, each the mean over enough calls to last about 10 ms (timeit's
    autorange, the same for every side): a 20 us solve timed alone is mostly the clock's and a cold cache's noise"""
    start = time.perf_counter()
    sol = solve()
    calls = max(1, min(1000, int(0.01 / max(time.perf_counter() - start, 1e-9))))
    best = math.inf
    for _ in range(REPEATS):
        start = time.perf_counter()
        for _ in range(calls):
            sol = solve()
        best = min(best, (time.perf_counter() - start) / calls)
    return best, sol


def sweep(solve, reference, read=None):
    """[(error, seconds, nfev)] over rtol 1e-2 .. 1e-11 in thirds of a decade, stopping once an error is below
    the smallest asked. Only solve(rtol) is timed; read(its result), where given, makes what is measured of it
    (an object with success, y[:, -1] and nfev) outside the timing"""
    points = []
    for k in range(0, 28 if not args.quick else 28, 1 if not args.quick else 2):
        rtol = 10 ** (-2 - k / 3)
        seconds, sol = timed(lambda: solve(rtol))
        if read:
            sol = read(sol)
        if not sol.success:
            continue
        err = float(np.max(np.abs(sol.y[:, -1] - reference)))
        points.append((err, seconds, sol.nfev))
        if err < ERRORS[-1] / 3 or seconds > 5:
            break
    return points


def sweep_all(solves, reference, probe=None):
    """{method: sweep points} for {method: solve(rtol), or (solve, read) as sweep() takes them}, over PASSES
    passes (each taking every method in turn), each point's time the least of its passes' (the errors and calls
    are the same in every pass); and probe() (a time), where given, run in each pass too: the least of them"""
    curves = {}
    probed = math.inf
    for _ in range(PASSES):
        if probe:
            probed = min(probed, probe())
        for method, entry in solves.items():
            solve, read = entry if isinstance(entry, tuple) else (entry, None)
            points = sweep(solve, reference, read)
            if method in curves and len(curves[method]) == len(points):
                points = [(e, min(c, c0), n) for (e, c, n), (_, c0, _) in zip(points, curves[method])]
            curves[method] = points
    return (curves, probed) if probe else curves


def cost_at(points, target, column=1):
    """the cost (column 1: seconds; 2: calls of f) at error `target` on the curve (log-log interpolation between
    the first pair of successive points that brackets it), or None where the sweep never reached it"""
    for p1, p2 in zip(points, points[1:]):
        e1, c1, e2, c2 = p1[0], p1[column], p2[0], p2[column]
        if e1 >= target >= e2 and e1 > e2:
            w = (math.log(e1) - math.log(target)) / (math.log(e1) - math.log(e2))
            return math.exp(math.log(c1) + w * (math.log(c2) - math.log(c1)))
    if points and points[0][0] <= target:
        return points[0][column]
    return None


def best(curves, target):
    costs = {m: cost_at(p, target) for m, p in curves.items()}
    costs = {m: c for m, c in costs.items() if c is not None}
    return min(costs.items(), key=lambda mc: mc[1]) if costs else (None, None)


def compare(e, scipy_curves, python_curves, compiled_curves):
    """each side's best method and cost at error e, and the two ratios as printed; None (said) where SciPy's
    methods did not reach it"""
    sm, sc = best(scipy_curves, e)
    pm, pc = best(python_curves, e)
    cm, cc = best(compiled_curves, e)
    if sc is None:
        print(f"{e:7.0e} | SciPy's methods did not reach it")
        return None
    return sm, sc, pm, pc, cm, cc, f"{sc / pc:6.1f}" if pc else "     -", f"{sc / cc:7.0f}" if cc else "      -"


def per_call(fun, y0):
    """the Python fun's own cost a call: the least of five means over 4000 calls (run in each pass of the sweeps,
    as the solves' times are the least of their passes': timed once, in a slow phase, it would put the fun's
    share of a solve over 100%)"""
    y = np.array(y0, dtype=float)
    best = math.inf
    for _ in range(5):
        start = time.perf_counter()
        for _ in range(4000):
            fun(0.0, y)
        best = min(best, (time.perf_counter() - start) / 4000)
    return best


print(f"stepwise {stepwise.__version__}; SciPy {scipy.__version__}; NumPy {np.__version__}; repeats {REPEATS}, passes {PASSES}")
summary = []
for name, fun, jac, equations, t_end, y0, ours, theirs, ref_method in [] if args.events_only else PROBLEMS:
    ref = scipy.integrate.solve_ivp(fun, (0, t_end), y0, method=ref_method, rtol=1e-13, atol=1e-15, jac=jac).y[:, -1]
    curves = sweep_all({**{("scipy", m): lambda rtol, m=m: scipy.integrate.solve_ivp(fun, (0, t_end), y0, method=m, rtol=rtol, atol=rtol * 1e-3,
                                                                                   **({"jac": jac} if jac and m != "RK45" else {})) for m in theirs},
                        **{("python", m): lambda rtol, m=m: stepwise.solve_ivp(fun, (0, t_end), y0, method=m, rtol=rtol, atol=rtol * 1e-3, jac=jac) for m in ours},
                        **{("compiled", m): lambda rtol, m=m: stepwise.solve_ivp(equations, (0, t_end), y0, method=m, rtol=rtol, atol=rtol * 1e-3) for m in ours}},
                       ref, probe=lambda: per_call(fun, y0))
    curves, call = curves
    scipy_curves, python_curves, compiled_curves = ({m: p for (side, m), p in curves.items() if side == s} for s in ("scipy", "python", "compiled"))
    print(f"\n{name} (t_end {t_end}; the Python fun costs {call * 1e6:.2f} us a call)")
    print(f"{'error':>7} | {'SciPy best':>22} | {'stepwise, Python fun':>24} {'ratio':>6} {'fun share':>9} | {'stepwise, compiled':>24} {'ratio':>7}")
    for e in ERRORS:
        row = compare(e, scipy_curves, python_curves, compiled_curves)
        if row is None:
            continue
        sm, sc, pm, pc, cm, cc, pr, cr = row
        share = ""
        if pm:
            # the calls stepwise's best made near this error: interpolated like the cost
            share = f"{cost_at(python_curves[pm], e, column=2) * call / pc:9.0%}"
        print(f"{e:7.0e} | {sm:>10} {sc * 1e3:9.3f} ms | {pm or '-':>12} {(pc or 0) * 1e3:8.3f} ms {pr} {share:>9} | {cm or '-':>12} {(cc or 0) * 1e3:8.4f} ms {cr}")
        summary.append((name, e, sc / pc if pc else None, sc / cc if cc else None))


# ---- events: a ball with quadratic drag bouncing off the floor (restitution 0.8) to its fifth impact. SciPy has
# no state change at an event: its loop restarts solve_ivp at each impact with the rebound (a terminal event), and
# so does stepwise's with a Python fun and event; stepwise.Equations bounces inside one compiled solve (an
# [events] action). The error is the largest impact-time error against the same loop with DOP853 at rtol 1e-13.
G, DRAG, E, BOUNCES = 9.81, 0.1, 0.8, 5


def dragged_ball(t, y):
    return np.array([y[1], -G - DRAG * y[1] * abs(y[1])])


def floor_event(t, y):
    return y[0]


floor_event.terminal = True
floor_event.direction = -1


def bounce_loop(solve_ivp, method, rtol):
    t, y, impacts = 0.0, [1.0, 0.0], []
    while len(impacts) < BOUNCES:
        sol = solve_ivp(dragged_ball, (t, t + 10), y, method=method, rtol=rtol, atol=rtol * 1e-3, events=floor_event)
        if not sol.success or not len(sol.t_events[0]):
            return None
        t = float(sol.t_events[0][0])
        impacts.append(t)
        y = [0.0, -E * float(sol.y_events[0][0][1])]
    return impacts


ball_equations = stepwise.Equations({"y": "v", "v": "-g - c*v*abs(v)"}, parameters={"g": G, "c": DRAG, "e": E}, initial={"y": 1.0},
                                    events={"floor": {"when": "y", "direction": "falling", "action": {"v": "-e*v"}}})


class Impacts:
    """a sweep point's result, shaped as sweep() reads a solution: success, y[:, -1] the impact times, nfev"""

    def __init__(self, times, nfev=0):
        self.success = times is not None and len(times) >= BOUNCES
        self.y = np.array(times[:BOUNCES] if self.success else [np.nan] * BOUNCES)[:, None]
        self.nfev = nfev


reference_impacts = bounce_loop(scipy.integrate.solve_ivp, "DOP853", 1e-13)
ref = np.array(reference_impacts)
# the compiled run ends at the fifth impact's time plus a little: the impact times are the solve's own events
T_END = reference_impacts[-1] + 0.05


def compiled_bounces(method, rtol):
    return stepwise.solve_ivp(ball_equations, (0, T_END), [1.0, 0.0], method=method, rtol=rtol, atol=rtol * 1e-3, t_eval=[T_END])


def compiled_impacts(sol):
    return Impacts(list(sol.equation_events["floor"][0]), sol.nfev)


# each side's solve timed alone: the loops of restarts are SciPy's and the Python fun's solve; the impacts' array
# made of a result is not timed on any side
curves = sweep_all({**{("scipy", m): (lambda rtol, m=m: bounce_loop(scipy.integrate.solve_ivp, m, rtol), Impacts) for m in ["RK45", "DOP853", "LSODA"]},
                    **{("python", m): (lambda rtol, m=m: bounce_loop(stepwise.solve_ivp, m, rtol), Impacts) for m in ["verner98", "tsitouras54"]},
                    **{("compiled", m): (lambda rtol, m=m: compiled_bounces(m, rtol), compiled_impacts) for m in ["verner98", "tsitouras54"]}}, ref)
scipy_curves, python_curves, compiled_curves = ({m: p for (side, m), p in curves.items() if side == s} for s in ("scipy", "python", "compiled"))
print(f"\nbouncing ball with drag, {BOUNCES} impacts: the largest impact-time error")
print(f"{'error':>7} | {'SciPy best':>22} | {'stepwise, Python fun':>24} {'ratio':>6} | {'stepwise, compiled':>24} {'ratio':>7}")
event_ratios = []
for e in ERRORS:
    row = compare(e, scipy_curves, python_curves, compiled_curves)
    if row is None:
        continue
    sm, sc, pm, pc, cm, cc, pr, cr = row
    print(f"{e:7.0e} | {sm:>10} {sc * 1e3:9.3f} ms | {pm or '-':>12} {(pc or 0) * 1e3:8.3f} ms {pr} | {cm or '-':>12} {(cc or 0) * 1e3:8.4f} ms {cr}")
    event_ratios.append((sc / pc if pc else None, sc / cc if cc else None))
print(f"events, at equal impact-time error, SciPy's best / stepwise's best: Python fun "
      f"{min(r for r, _ in event_ratios if r):.1f}-{max(r for r, _ in event_ratios if r):.1f}x, compiled "
      f"{min(r for _, r in event_ratios if r):.0f}-{max(r for _, r in event_ratios if r):.0f}x")

if not summary:
    sys.exit(0)
python_ratios = [r for _, _, r, _ in summary if r]
compiled_ratios = [r for _, _, _, r in summary if r]
print(f"\nat equal error, SciPy's best / stepwise's best: Python fun {min(python_ratios):.1f}-{max(python_ratios):.1f}x, "
      f"compiled equations {min(compiled_ratios):.0f}-{max(compiled_ratios):.0f}x")
sys.exit(0)
