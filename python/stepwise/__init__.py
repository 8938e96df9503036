"""stepwise from Python: the method table, scene files run as the command line runs them, the advice and
the studies on a scene, and ``solve_ivp`` with SciPy's signature and result, on a Python ``fun`` or on
equations compiled once (``Equations``) with no Python in the loop.

    import stepwise
    sol = stepwise.solve_ivp(lambda t, y: [y[1], -9.81 * np.sin(y[0])], (0, 10), [2.9, 0.0],
                             method="verner98", rtol=1e-8, atol=1e-10, t_eval=np.linspace(0, 10, 101))

Use Debian's /usr/bin/python3 (its dist-packages hold numpy); docs/library.md says how to install it.
"""

import warnings

import numpy as np

from . import _stepwise
from ._stepwise import Equations

__all__ = ["Equations", "OdeResult", "RunResult", "advise", "methods", "run", "solve_ivp", "study"]
__version__ = _stepwise.version()


def methods():
    """The method table, as ``stepwise methods`` prints it: a list of dicts (name, family, source,
    description, order, order_min, order_max, stepping, needs, and options: the method's own, each a dict as
    ``stepwise methods --json`` lists it, which ``run`` takes as keyword arguments)."""
    return _stepwise.methods()


class RunResult:
    """A scene's run: ``t`` (N,), ``y`` (n, N) of the columns ``names`` (the state's, or a large model's
    summary), ``energy`` (N,) where the model has one, and ``summary`` (summary.json's fields, a dict). A PDE
    scene's also ``fields`` ({name: (N, nodes), or (N, ny, nx) in 2-D}) and its nodes' ``x`` and ``y_nodes``
    (nodes,), row-major; else None."""

    def __init__(self, columns, values, summary, fields=None, x=None, y=None):
        self.fields = fields
        self.x, self.y_nodes = x, y
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


def run(scene, method=None, dt=None, rtol=None, atol=None, t_end=None, output_dt=None, set=None, max_steps=None, **options):
    """Run a scene file as ``stepwise run`` runs it, with the same overrides.

    Parameters
    ----------
    scene : str or path
        A scene file, or a shipped scene by name (``"pendulum"``).
    method : str, optional
        A method's name (``methods()``); default the scene's, else one chosen for it.
    dt, rtol, atol : float, optional
        A fixed step (s), or the tolerances of an adaptive method.
    t_end, output_dt : float, optional
        The end time and the sampling interval (s); default the scene's, and t_end / 1000.
    set : dict of str to float, optional
        Scene parameters overridden, as ``--set key=value``.
    max_steps : float, optional
        The steps (and output rows) the run may take.
    **options
        The method's own options (``methods()``' ``options``, ``stepwise run --NAME``), by name with ``_`` for
        ``-``: ``run("flag", method="vbd", dt=1/60, iterations=10, start="inertial")``. Checked as the command
        line checks them: one the method does not take, or out of its range, is a ValueError naming both.

    Returns
    -------
    RunResult
        ``t`` (N,), ``y`` (n, N) of the columns ``names``, ``energy`` (N,) where the model has one, and
        ``summary`` (summary.json's fields, docs/outputs.md). The numbers equal trajectory.csv's and
        summary.json's to the bit.

    Raises
    ------
    ValueError
        Bad input, with the command line's one-line message (the file, line or key).
    TypeError
        ``set`` not a dict.
    """
    given = {name.replace("_", "-"): str(value) for name, value in options.items()}
    out = _stepwise.run(str(scene), method, dt, rtol, atol, t_end, output_dt, _sets(set), max_steps, given)
    return RunResult(out["columns"], out["values"], out["summary"], out.get("fields"), out.get("x"), out.get("y"))


def advise(scene, error, budget=10.0, set=None, threads=0):
    """``stepwise advise``: the method that reaches ``error`` at t_end cheapest on this scene, measured within
    ``budget`` seconds. advice.json's fields as a dict (method, dt or rtol and atol, error, cpu_seconds, stiff,
    runner_up, candidates: each method's verdict and reason), with markdown (advice.md's text) and sweep (every
    run: advice_sweep.csv's columns as numpy arrays)."""
    out = _stepwise.advise(str(scene), float(error), float(budget), _sets(set), int(threads))
    advice = out["advice"]
    advice["markdown"] = out["markdown"]
    advice["sweep"] = out["sweep"]
    return advice


def study(name, scene, set=None, quick=True, threads=0):
    """``stepwise study NAME --scene FILE`` (work-precision, convergence, stability-regions, energy): a dict
    with ``tables`` ({stem: {column: numpy array or list}}) and ``markdown``."""
    return _stepwise.study(str(name), str(scene), _sets(set), bool(quick), int(threads))


class OdeResult(dict):
    """SciPy's result: t, y, sol, t_events, y_events, nfev, njev, nlu, status, message, success; and
    stepwise's own: method, stats (every counter: steps, rejected, rhs_evals, ...), equation_events (an
    Equations' own events: {name: (times, states just before its action)})."""

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


_FLOAT64 = np.dtype(np.float64)


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


class StepSolution:
    """``sol.sol`` of a ``solve_ivp(..., dense_output=True)``, like SciPy's ``OdeSolution``: ``sol(t)`` for a
    number (shape (n,)) or an array of times (shape (n, len(t))) within the steps taken (``ts``, ``t_min``,
    ``t_max``). Each value is the method's own solution there: integrated by the same method and tolerance from
    the start of the step that holds it, so it carries the method's error, not an interpolant's."""

    def __init__(self, ts, ys, resolve):
        self.ts = np.asarray(ts, dtype=float)
        self._ys = np.asarray(ys, dtype=float)
        self._resolve = resolve
        self.t_min, self.t_max = float(min(self.ts[0], self.ts[-1])), float(max(self.ts[0], self.ts[-1]))
        self.n_segments = max(len(self.ts) - 1, 0)
        self._ascending = len(self.ts) < 2 or self.ts[-1] >= self.ts[0]

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        scalar = t.ndim == 0
        ts = np.atleast_1d(t).ravel()
        out = np.empty((self._ys.shape[0], ts.size))
        key = self.ts if self._ascending else -self.ts
        q = ts if self._ascending else -ts
        # the step each time falls in: [ts[k], ts[k + 1]), the last step closed at its end
        k = np.clip(np.searchsorted(key, q, side="right") - 1, 0, max(self.n_segments - 1, 0))
        # at a step's end, that step's own value (the last step's end too, which no step starts)
        at_last = (q == key[-1]) if key.size else np.zeros(q.shape, dtype=bool)
        k[at_last] = key.size - 1
        exact = key[k] == q
        out[:, exact] = self._ys[:, k[exact]]
        for step in np.unique(k[~exact]):
            picked = np.flatnonzero((k == step) & ~exact)
            order = picked[np.argsort(q[picked])]
            y = self._resolve(self.ts[step], self.ts[min(step + 1, len(self.ts) - 1)], self._ys[:, step], ts[order])
            out[:, order] = y
        return out[:, 0] if scalar else out.reshape((self._ys.shape[0],) + t.shape)


def _event_attributes(events):
    """SciPy's events: a callable or a list of them, each with optional ``terminal`` (bool) and ``direction``
    attributes, checked here with SciPy's rules."""
    if events is None:
        return []
    try:
        events = [events] if callable(events) else list(events)
    except TypeError as e:
        raise TypeError(f"events must be a callable g(t, y) or a list of them, not {events!r}") from e
    for k, e in enumerate(events):
        if not callable(e):
            raise TypeError(f"events[{k}] must be a callable g(t, y)")
        terminal = getattr(e, "terminal", False)
        if not isinstance(terminal, (bool, np.bool_)) and not (isinstance(terminal, (int, np.integer)) and terminal in (0, 1)):
            raise ValueError(f"events[{k}].terminal: stepwise ends at the first occurrence (True) or never (False), not {terminal!r}")
    return events


def solve_ivp(fun, t_span, y0, method="verner98", t_eval=None, dense_output=False, events=None, vectorized=False, args=None, **options):
    """Solve an initial value problem with SciPy's signature and result, stepped by a stepwise method.

    Parameters
    ----------
    fun : callable or Equations
        ``fun(t, y)`` returning dy/dt of shape (n,) (with ``args``: ``fun(t, y, *args)``); or a
        ``stepwise.Equations``, compiled once, with no Python in the loop, whose own events are watched too.
    t_span : 2-tuple of float
        The interval (t0, tf); tf < t0 integrates backwards.
    y0 : array_like, shape (n,)
        The initial state (real numbers).
    method : str, optional
        Any name ``methods()`` lists (default ``"verner98"``). SciPy's ``"RK45"``, ``"RK23"`` and ``"BDF"`` name the
        same methods here; ``"DOP853"``, ``"Radau"`` and ``"LSODA"`` raise, naming the closest.
    t_eval : array_like, optional
        Times at which the solution is stored, within t_span; without them, the steps taken, as SciPy's.
    dense_output : bool, optional
        Whether ``sol`` is a ``StepSolution`` callable at any time in t_span.
    events : callable or list of callables, optional
        ``g(t, y)`` with SciPy's ``terminal`` and ``direction`` attributes, located on the method's solution.
        Events reaching zero at one instant are each recorded there once, in the order of the list, and a terminal
        one among them ends the solve after all of them (docs/scenes.md#events).
    vectorized : bool, optional
        ``fun`` is called with y of shape (n, 1).
    args : tuple, optional
        Extra arguments to ``fun``, ``jac`` and the events.
    **options
        ``rtol`` (1e-3) and ``atol`` (1e-6; a number, or one per component), ``jac`` (callable or matrix),
        ``max_step``; stepwise's ``dt`` (a fixed step, which the fixed-step methods need) and ``max_steps``.
        SciPy's ``first_step``, ``min_step``, ``jac_sparsity``, ``lband`` and ``uband`` are accepted with SciPy's
        warning that they have no effect.

    Returns
    -------
    OdeResult
        SciPy's fields: ``t`` (N,), ``y`` (n, N), ``sol``, ``t_events``, ``y_events``, ``nfev``, ``njev``, ``nlu``,
        ``status`` (0 reached tf, 1 a terminal event, -1 failed), ``message``, ``success``; and stepwise's:
        ``method``, ``stats`` (every counter: steps, rejected, rhs_evals, ...) and ``equation_events`` (an
        Equations' own events: {name: (times, states just before its action)}).

    Raises
    ------
    ValueError
        A bad t_span, y0 of another shape than 1-D, t_eval outside t_span or not 1-D, atol of the wrong shape or
        negative, a non-positive max_step, an unknown method or one of SciPy's that stepwise has not, ``args`` with
        an Equations, or a bad event attribute.
    TypeError
        ``fun`` not callable, complex or non-numeric y0 or options, a method that is not a string, or an option
        neither SciPy's nor stepwise's.

    Examples
    --------
    >>> import numpy as np, stepwise
    >>> sol = stepwise.solve_ivp(lambda t, y: [y[1], -9.81 * np.sin(y[0])], (0, 10), [2.9, 0.0],
    ...                          method="verner98", rtol=1e-8, atol=1e-10)
    >>> sol.success
    True
    """
    # (options is this call's own dict: popped as read. The checks below take the common case first, as a solve
    # of a compiled system costs a few microseconds)
    rtol = _number("rtol", options.pop("rtol", 1e-3))
    atol = options.pop("atol", 1e-6)
    scale = None  # atol per component: the system is solved in z = y / scale, with one atol (see below)
    if type(atol) is not float and not np.isscalar(atol):
        atol_array = np.asarray(atol, dtype=float)
        if atol_array.ndim != 1 or atol_array.shape != np.shape(y0):
            raise ValueError("`atol` has wrong shape.")
        if np.any(atol_array < 0):
            raise ValueError("`atol` must be positive.")
        if np.all(atol_array == atol_array.flat[0]):
            atol = float(atol_array.flat[0])
        else:
            if np.any(atol_array == 0):
                raise ValueError("atol: a component of 0 (a purely relative tolerance) is not supported with the others nonzero")
            if isinstance(fun, Equations):
                raise ValueError("atol: one number for a stepwise.Equations (its compiled system is not rescaled); per component with a Python fun")
            scale = atol_array / atol_array.min()
            atol = float(atol_array.min())
    else:
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
    events = _event_attributes(events)
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
        if args is not None:
            events = [_with_args(e, args) for e in events]
        if vectorized:
            user_vectorized = fun
            fun = lambda t, y: np.asarray(user_vectorized(t, y[:, None]), dtype=float).reshape(-1)  # noqa: E731
    elif args is not None:
        raise ValueError("args: an Equations system takes its parameters when it is made (Equations(..., parameters=...))")

    try:
        t0, t1 = t_span
        t0, t1 = _number("t_span", t0), _number("t_span", t1)
    except ValueError as e:
        raise ValueError(f"t_span must be two numbers (t0, t1), not {t_span!r}") from e
    if type(y0) is not np.ndarray:
        y0 = np.asarray(y0)
    if y0.dtype is not _FLOAT64 and y0.dtype != _FLOAT64:
        if y0.dtype.kind == "c":
            raise TypeError("y0: complex states are not supported; split them into real and imaginary parts")
        try:
            y0 = y0.astype(float)
        except (TypeError, ValueError) as e:
            raise TypeError(f"y0 must hold real numbers: {e}") from e
    if y0.ndim != 1:
        raise ValueError(f"`y0` must be 1-dimensional, not of shape {y0.shape}.")
    if t_eval is not None:
        if type(t_eval) is not np.ndarray or t_eval.dtype is not _FLOAT64:
            t_eval = np.asarray(t_eval, dtype=float)
        if t_eval.ndim != 1:
            raise ValueError("`t_eval` must be 1-dimensional.")
    if scale is not None:
        if scale.shape != y0.shape:
            raise ValueError("`atol` has wrong shape.")
        fun, jac, events, y0 = _rescaled(fun, jac, events, y0, scale)

    def solve(ta, tb, ya, times, record_steps, with_events):
        return _stepwise.solve(fun, ta, tb, ya, method, rtol, atol, dt, max_step, times, jac, max_steps,
                               events if with_events else [], record_steps)

    out = solve(t0, t1, y0, t_eval, t_eval is None, True)
    sol = None
    if dense_output:
        steps = out if t_eval is None else solve(t0, t1, y0, None, True, True)
        unscale = (lambda y: y) if scale is None else (lambda y: y * scale[:, None])
        sol = StepSolution(steps["t"], unscale(steps["y"]),
                           lambda ta, tb, ya, times: unscale(_segment(solve, ta, tb, ya / (1 if scale is None else scale), times)))
    y = out["y"] if scale is None else out["y"] * scale[:, None]
    # t_events and y_events: one array for each of the events given, in their order; an Equations' own by name
    t_events = out["t_events"] if events else None
    y_events = out["y_events"] if events else None
    if events and scale is not None:
        y_events = [ys * scale for ys in y_events]
    ok = out["status"] == "ok"
    stats = out["stats"]
    status = (1 if out["terminated"] else 0) if ok else -1
    message = ("A termination event occurred." if out["terminated"] else
               "The solver successfully reached the end of the integration interval.") if ok else out["message"]
    return OdeResult(
        t=out["t"], y=y, sol=sol, t_events=t_events, y_events=y_events,
        nfev=stats["rhs_evals"], njev=stats["jac_evals"], nlu=stats["factorizations"],
        status=status, message=message, success=ok, method=out["method"], stats=stats, equation_events=out["own_events"])


def _like(wrapped, event):
    """`wrapped` with the event's SciPy attributes (terminal, direction)"""
    for attribute in ("terminal", "direction"):
        if hasattr(event, attribute):
            setattr(wrapped, attribute, getattr(event, attribute))
    return wrapped


def _with_args(event, args):
    return _like(lambda t, y: event(t, y, *args), event)


def _rescaled(fun, jac, events, y0, scale):
    """The system in z = y / scale, so one atol (the smallest) on z is SciPy's atol per component on y: the
    error weight 1 / (rtol |y_i| + atol_i) is 1 / (scale_i (rtol |z_i| + atol)). f, its Jacobian and the events
    are read through y = scale z."""
    user_fun = fun
    z_fun = lambda t, z: np.asarray(user_fun(t, z * scale), dtype=float) / scale  # noqa: E731
    z_jac = jac
    if callable(jac):
        user_jac = jac
        z_jac = lambda t, z: np.asarray(user_jac(t, z * scale), dtype=float) * scale[None, :] / scale[:, None]  # noqa: E731
    elif jac is not None:
        z_jac = np.asarray(jac, dtype=float) * scale[None, :] / scale[:, None]
    z_events = [_like((lambda e: lambda t, z: e(t, z * scale))(event), event) for event in events]
    return z_fun, z_jac, z_events, y0 / scale


def _segment(solve, ta, tb, ya, times):
    """The method's solution at `times` (sorted, within [ta, tb]), integrated from (ta, ya) without events."""
    if ta == tb:
        return np.repeat(np.asarray(ya, dtype=float)[:, None], len(times), axis=1)
    out = solve(ta, tb, np.asarray(ya, dtype=float), list(times), False, False)
    if out["status"] != "ok":
        raise RuntimeError(f"sol({times[0]}): the re-integration from t = {ta} failed: {out['message']}")
    return out["y"]
