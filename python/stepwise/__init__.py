"""stepwise from Python: the method table, scene files run as the command line runs them, the advice and
the studies on a scene, and ``solve_ivp`` with SciPy's signature and result, on a Python ``fun`` or on
equations compiled once (``Equations``) with no Python in the loop.

    import stepwise
    sol = stepwise.solve_ivp(lambda t, y: [y[1], -9.81 * np.sin(y[0])], (0, 10), [2.9, 0.0],
                             method="verner98", rtol=1e-8, atol=1e-10, t_eval=np.linspace(0, 10, 101))

Use Debian's /usr/bin/python3 (its dist-packages hold numpy); docs/library.md says how to install it.
"""

import json
import warnings

import numpy as np

from . import _stepwise
from ._stepwise import Equations

__all__ = ["Equations", "OdeResult", "RunResult", "advise", "methods", "run", "solve_ivp", "study"]
__version__ = _stepwise.version()


def methods():
    """The method table, as ``stepwise methods`` prints it: a list of dicts (name, family, source,
    description, order, order_min, order_max, stepping, needs)."""
    return _stepwise.methods()


class RunResult:
    """A scene's run: ``t`` (N,), ``y`` (n, N) of the columns ``names`` (the state's, or a large model's
    summary), ``energy`` (N,) where the model has one, and ``summary`` (summary.json's fields, a dict)."""

    def __init__(self, columns, values, summary):
        self.columns = list(columns)
        self.t = values[0]
        names = self.columns[1:]
        self.energy = None
        if names and names[-1] == "energy":
            self.energy = values[-1]
            names = names[:-1]
            values = values[:-1]
        self.names = names
        self.y = values[1:]
        self.summary = summary

    def __repr__(self):
        return f"RunResult({self.summary['scene']}, {self.summary['method']}: {self.summary['status']}, {len(self.t)} samples)"


def _sets(set):
    if set is None:
        return {}
    if not isinstance(set, dict):
        raise TypeError(f"set must be a dict of name: number, not {type(set).__name__}")
    return {str(k): float(v) for k, v in set.items()}


def run(scene, method=None, dt=None, rtol=None, atol=None, t_end=None, output_dt=None, set=None, max_steps=None):
    """Run a scene file (a path, or a shipped scene by name: "pendulum") as ``stepwise run`` runs it, with
    the same overrides; the numbers equal trajectory.csv's and summary.json's to the bit."""
    out = _stepwise.run(str(scene), method, dt, rtol, atol, t_end, output_dt, _sets(set), max_steps)
    return RunResult(out["columns"], out["values"], json.loads(out["summary"]))


def advise(scene, error, budget=10.0, set=None, threads=0):
    """``stepwise advise``: the method that reaches ``error`` at t_end cheapest on this scene, measured within
    ``budget`` seconds. advice.json's fields as a dict (method, dt or rtol and atol, error, cpu_seconds, stiff,
    runner_up, candidates: each method's verdict and reason), with markdown (advice.md's text) and sweep (every
    run: advice_sweep.csv's columns as numpy arrays)."""
    out = _stepwise.advise(str(scene), float(error), float(budget), _sets(set), int(threads))
    advice = json.loads(out["advice"])
    advice["markdown"] = out["markdown"]
    advice["sweep"] = out["sweep"]
    return advice


def study(name, scene, set=None, quick=True, threads=0):
    """``stepwise study NAME --scene FILE`` (work-precision, convergence, stability-regions, energy): a dict
    with ``tables`` ({stem: {column: numpy array or list}}) and ``markdown``."""
    return _stepwise.study(str(name), str(scene), _sets(set), bool(quick), int(threads))


class OdeResult(dict):
    """SciPy's result: t, y, sol, t_events, y_events, nfev, njev, nlu, status, message, success; and
    stepwise's own: method, stats (every counter: steps, rejected, rhs_evals, ...)."""

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError as e:
            raise AttributeError(name) from e

    __setattr__ = dict.__setitem__
    __delattr__ = dict.__delitem__

    def __repr__(self):
        return "\n".join(f"{k:>9}: {v!r}" for k, v in self.items())


# SciPy's methods where stepwise has the same one; the others are named with what comes closest
_SCIPY_SAME = {"RK45": "arkode-erk-dormand-prince54", "RK23": "arkode-erk-bogacki-shampine32", "BDF": "cvode-bdf"}
_SCIPY_CLOSEST = {
    "DOP853": "gsl-rk8pd (Prince-Dormand 8(9)) or verner98",
    "Radau": "rodas5 (L-stable, order 5) or arkode-dirk-kvaerno54",
    "LSODA": "cvode-bdf on a stiff system, verner98 or cvode-adams otherwise",
}
# SciPy's options that a stepwise method does not take: accepted, with SciPy's warning
_SCIPY_NO_EFFECT = {"first_step", "min_step", "jac_sparsity", "lband", "uband"}


def _number(name, value):
    if type(value) is float:  # the common case, checked first: a solve's own cost is a few microseconds
        return value
    if type(value) is int:
        return float(value)
    if isinstance(value, (bool, np.bool_)) or not np.isscalar(value) or np.iscomplexobj(value):
        raise TypeError(f"{name} must be a real number, not {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError) as e:
        raise TypeError(f"{name} must be a real number, not {value!r}") from e


def solve_ivp(fun, t_span, y0, method="verner98", t_eval=None, dense_output=False, events=None, vectorized=False, args=None, **options):
    """``scipy.integrate.solve_ivp``'s signature and result, stepped by a stepwise method.

    fun: ``fun(t, y)`` returning dy/dt (shape (n,)), or a ``stepwise.Equations`` (compiled, no Python in
    the loop). method: any of ``methods()`` (default verner98); SciPy's "RK45", "RK23" and "BDF" name the
    same methods here. Options: rtol (1e-3), atol (1e-6, a number), jac (callable or matrix), max_step,
    and stepwise's dt (a fixed step, which the fixed-step methods need) and max_steps. Without t_eval the
    result holds t_span's two ends (stepwise does not report its internal steps). A reversed t_span
    integrates backwards. dense_output and events are not offered (a ValueError says so)."""
    options = dict(options)
    rtol = _number("rtol", options.pop("rtol", 1e-3))
    atol = options.pop("atol", 1e-6)
    if type(atol) is not float and not np.isscalar(atol):
        raise ValueError("atol: stepwise's tolerance is one number for every component, not an array")
    atol = _number("atol", atol)
    jac = options.pop("jac", None)
    dt = options.pop("dt", None)
    dt = None if dt is None else _number("dt", dt)
    max_step = _number("max_step", options.pop("max_step", np.inf))
    if not max_step > 0:  # SciPy's rule and message (a negative step cap would integrate backwards)
        raise ValueError("`max_step` must be positive.")
    max_steps = options.pop("max_steps", None)  # None: StepControl's own cap
    max_steps = None if max_steps is None else _number("max_steps", max_steps)
    if options:
        ignored = sorted(k for k in options if k in _SCIPY_NO_EFFECT)
        unknown = sorted(k for k in options if k not in _SCIPY_NO_EFFECT)
        if unknown:
            raise TypeError(f"solve_ivp() got unexpected keyword arguments: {', '.join(unknown)}")
        warnings.warn(f"The following arguments have no effect for a chosen solver: {', '.join(ignored)}.", stacklevel=2)
    if dense_output:
        raise ValueError("dense_output: not offered by stepwise.solve_ivp; pass t_eval for the times you need")
    if events is not None:
        raise ValueError("events: not offered by stepwise.solve_ivp (a scene file's models have events: stepwise.run)")
    if not isinstance(method, str):
        raise TypeError("method must be a method's name (stepwise.methods() lists them)")
    if method in _SCIPY_CLOSEST:
        raise ValueError(f"method: SciPy's {method} is not in stepwise; the closest are {_SCIPY_CLOSEST[method]}")
    method = _SCIPY_SAME.get(method, method)

    if not isinstance(fun, Equations):
        if not callable(fun):
            raise TypeError("fun must be a callable fun(t, y) or a stepwise.Equations")
        if args is not None:
            if not isinstance(args, tuple):
                args = (args,)
            user_fun = fun
            fun = lambda t, y: user_fun(t, y, *args)  # noqa: E731
            if callable(jac):
                user_jac = jac
                jac = lambda t, y: user_jac(t, y, *args)  # noqa: E731
        if jac is not None and not callable(jac):
            jac = np.asarray(jac, dtype=float)
    elif args is not None:
        raise ValueError("args: an Equations system takes its parameters when it is made (Equations(..., parameters=...))")

    try:
        t0, t1 = (_number("t_span", t) for t in t_span)
    except ValueError as e:
        raise ValueError(f"t_span must be two numbers (t0, t1), not {t_span!r}") from e
    y0 = np.asarray(y0)
    if y0.dtype != np.float64:
        if y0.dtype.kind == "c":
            raise TypeError("y0: complex states are not supported; split them into real and imaginary parts")
        try:
            y0 = y0.astype(float)
        except (TypeError, ValueError) as e:
            raise TypeError(f"y0 must hold real numbers: {e}") from e
    if y0.ndim != 1:
        raise ValueError(f"`y0` must be 1-dimensional, not of shape {y0.shape}.")
    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=float)
        if t_eval.ndim != 1:
            raise ValueError("`t_eval` must be 1-dimensional.")
        t_eval = t_eval.tolist()

    out = _stepwise.solve(fun, t0, t1, y0, method, rtol, atol, dt, max_step, t_eval, jac, max_steps)
    ok = out["status"] == "ok"
    stats = out["stats"]
    return OdeResult(
        t=out["t"], y=out["y"], sol=None, t_events=None, y_events=None,
        nfev=stats["rhs_evals"], njev=stats["jac_evals"], nlu=stats["factorizations"],
        status=0 if ok else -1,
        message="The solver successfully reached the end of the integration interval." if ok else out["message"],
        success=ok, method=out["method"], stats=stats)
