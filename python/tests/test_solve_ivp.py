"""stepwise.solve_ivp: SciPy's signature and result, every method against an exact solution and against SciPy,
compiled equations, and what bad input, a raising fun and Ctrl-C do."""
import math
import os
import signal
import threading
import time

import numpy as np
import pytest
import scipy.integrate

import stepwise
from conftest import tolerance

# the harmonic oscillator x' = v, v' = -x from (1, 0): x = cos t, v = -sin t
T = 2.0


def oscillator(t, y):
    return [y[1], -y[0]]


def exact(t):
    return np.array([np.cos(t), -np.sin(t)])


PLAIN = [m for m in stepwise.methods() if not m["needs"]]
ADAPTIVE = [m["name"] for m in PLAIN if m["stepping"] != "fixed"]
ORDER = {m["name"]: m["order_min"] for m in PLAIN}
FIXED = [m for m in PLAIN if m["stepping"] != "adaptive"]


def test_result_has_scipys_attributes():
    sol = stepwise.solve_ivp(oscillator, (0, T), [1.0, 0.0])
    ref = scipy.integrate.solve_ivp(oscillator, (0, T), [1.0, 0.0])
    for name in ("t", "y", "sol", "t_events", "y_events", "nfev", "njev", "nlu", "status", "message", "success"):
        assert hasattr(sol, name), name
        assert hasattr(ref, name), name
    assert sol.y.shape == (2, len(sol.t))
    assert sol.success and sol.status == 0 and sol.t[0] == 0 and sol.t[-1] == T
    assert sol.nfev == sol.stats["rhs_evals"] > 0


@pytest.mark.parametrize("method", ADAPTIVE)
def test_adaptive_method_meets_its_tolerance(method):
    """a code controlling the error per step of an order-p solution to rtol takes steps h ~ rtol^(1/(p+1)), and
    their errors add to ~ rtol^(p/(p+1)) over unit times on a unit-Lipschitz problem (the tolerance slope
    p/(p+1) of min_tolerance_slope); within adaptive_agreement_factor of that (measured: 1e-5 to 0.4 of it)"""
    rtol = 1e-6
    sol = stepwise.solve_ivp(oscillator, (0, T), [1.0, 0.0], method=method, rtol=rtol, atol=rtol * 1e-3)
    assert sol.success, sol.message
    err = np.max(np.abs(sol.y[:, -1] - exact(T)))
    p = max(ORDER[method], 1)
    assert err <= tolerance("adaptive_agreement_factor") * rtol ** (p / (p + 1)), f"{method}: error {err:.2e}"


@pytest.mark.parametrize("method", [m for m in FIXED if m["stepping"] == "fixed"], ids=lambda m: m["name"])
def test_fixed_step_method_converges_at_its_order(method):
    """the fixed-step methods (the adaptive ones' fixed steps are verified in C++, test_order): error against dt
    over four halvings, the least-squares slope is the method's order within order_band"""
    dts = [T / 32 / 2**k for k in range(4)]
    errs = []
    for dt in dts:
        sol = stepwise.solve_ivp(oscillator, (0, T), [1.0, 0.0], method=method["name"], dt=dt)
        assert sol.success, sol.message
        errs.append(np.max(np.abs(sol.y[:, -1] - exact(T))))
    assert tolerance("roundoff_floor") < min(errs) and max(errs) < tolerance("asymptotic_ceiling"), errs
    slope = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert abs(slope - method["order_min"]) <= tolerance("order_band"), f"{method['name']}: order {slope:.3f}, errors {errs}"


def test_agrees_with_scipy_to_the_tolerance():
    """Van der Pol mu = 1 to t = 10: stepwise at rtol 1e-8 against SciPy's DOP853 at 1e-12"""
    def vdp(t, y):
        return [y[1], (1 - y[0] ** 2) * y[1] - y[0]]
    t_eval = np.linspace(0, 10, 11)
    ref = scipy.integrate.solve_ivp(vdp, (0, 10), [2.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14, t_eval=t_eval)
    for method in ("verner98", "RK45", "BDF", "rodas5"):
        rtol = 1e-8
        sol = stepwise.solve_ivp(vdp, (0, 10), [2.0, 0.0], method=method, rtol=rtol, atol=rtol * 1e-2, t_eval=t_eval)
        assert np.array_equal(sol.t, ref.t)
        err = np.max(np.abs(sol.y - ref.y))
        assert err <= tolerance("adaptive_agreement_factor") * rtol * np.max(np.abs(ref.y)), f"{method}: {err:.2e}"


def test_t_eval_and_backwards():
    t_eval = np.linspace(0, T, 9)
    sol = stepwise.solve_ivp(oscillator, (0, T), [1.0, 0.0], t_eval=t_eval, rtol=1e-10, atol=1e-12)
    assert np.array_equal(sol.t, t_eval)
    assert np.max(np.abs(sol.y - exact(t_eval))) <= tolerance("adaptive_agreement_factor") * 1e-10
    back = stepwise.solve_ivp(oscillator, (T, 0), sol.y[:, -1], t_eval=t_eval[::-1], rtol=1e-10, atol=1e-12)
    assert np.array_equal(back.t, t_eval[::-1])
    assert np.max(np.abs(back.y[:, -1] - [1.0, 0.0])) <= 2 * tolerance("adaptive_agreement_factor") * 1e-10


def test_jacobian_is_used():
    jac = np.array([[0.0, 1.0], [-1.0, 0.0]])
    sol = stepwise.solve_ivp(oscillator, (0, T), [1.0, 0.0], method="rodas5", jac=jac, rtol=1e-8, atol=1e-10)
    fd = stepwise.solve_ivp(oscillator, (0, T), [1.0, 0.0], method="rodas5", rtol=1e-8, atol=1e-10)
    assert sol.njev > 0 and sol.nfev < fd.nfev  # no calls of fun spent on differences
    assert np.max(np.abs(sol.y[:, -1] - exact(T))) <= tolerance("adaptive_agreement_factor") * 1e-8


def test_args_pass_through():
    sol = stepwise.solve_ivp(lambda t, y, k: -k * y, (0, 1), [1.0], args=(2.0,), rtol=1e-10, atol=1e-12)
    assert abs(sol.y[0, -1] - np.exp(-2)) <= tolerance("adaptive_agreement_factor") * 1e-10


# compiled equations: no Python in the loop

PENDULUM = {"x": "v", "v": "-g/L*sin(x)"}


def test_equations_agree_with_the_same_python_fun():
    eq = stepwise.Equations(PENDULUM, parameters={"g": 9.81, "L": 1.0})
    assert eq.variables == ["x", "v"] and eq.compiled, eq.evaluation
    # libm's sin, which the compiled equations call: the same formula by the same code, so the same steps; and
    # numpy's, another implementation of sin (its AVX-512 code differs from libm's by up to 3 ulps on some machines),
    # after which two adaptive runs may take different steps (docs/verification.md#what-is-compared-bitwise)
    same = lambda t, y: [y[1], -9.81 * math.sin(y[0])]  # noqa: E731
    other = lambda t, y: [y[1], -9.81 * np.sin(y[0])]  # noqa: E731
    t_end, rtol = 10.0, 1e-10
    t_eval = np.linspace(0, t_end, 41)
    # explicit methods: the same f (a Newton method would differ by its Jacobian, exact against differences of fun)
    for method in ("verner98", "gsl-rk8pd", "odeint-dopri5"):
        a = stepwise.solve_ivp(eq, (0, t_end), [2.9, 0.0], method=method, rtol=rtol, atol=1e-12, t_eval=t_eval)
        b = stepwise.solve_ivp(same, (0, t_end), [2.9, 0.0], method=method, rtol=rtol, atol=1e-12, t_eval=t_eval)
        c = stepwise.solve_ivp(other, (0, t_end), [2.9, 0.0], method=method, rtol=rtol, atol=1e-12, t_eval=t_eval)
        # the same steps: a few ulps a call, summed over the run
        assert np.max(np.abs(a.y - b.y)) <= tolerance("equations_run_roundoff") * 1e3, method
        # maybe other steps: each run within its tolerance-proportional global error of the solution (a multiple
        # of rtol |y| a unit of time), so within twice that of each other, at the same times
        bound = 2 * tolerance("adaptive_agreement_factor") * rtol * np.max(np.abs(a.y)) * t_end
        assert np.max(np.abs(a.y - c.y)) <= bound, method
    # second order: symplectic-euler applies to the equations, not to a Python fun
    assert stepwise.solve_ivp(eq, (0, 1), [1.0, 0.0], method="symplectic-euler", dt=1e-3).success
    with pytest.raises(ValueError, match="symplectic-euler"):
        stepwise.solve_ivp(other, (0, 1), [1.0, 0.0], method="symplectic-euler", dt=1e-3)


def test_equations_from_a_scene_file():
    from conftest import scene
    eq = stepwise.Equations.from_scene(scene("lorenz"))
    assert eq.variables == ["x", "y", "z"]
    with pytest.raises(ValueError, match="not \"equations\""):
        stepwise.Equations.from_scene(scene("pendulum"))


def test_equations_errors_name_the_formula():
    with pytest.raises(ValueError, match="equations.v"):
        stepwise.Equations({"x": "v", "v": "-g*sinn(x)"}, parameters={"g": 1.0})
    eq = stepwise.Equations(PENDULUM, parameters={"g": 9.81, "L": 1.0})
    with pytest.raises(ValueError, match="2 variables"):
        stepwise.solve_ivp(eq, (0, 1), [1.0, 0.0, 0.0])


def test_gil_is_released_while_compiled_equations_run():
    eq = stepwise.Equations(PENDULUM, parameters={"g": 9.81, "L": 1.0})
    done = []
    worker = threading.Thread(target=lambda: done.append(stepwise.solve_ivp(eq, (0, 2000), [2.9, 0.0], rtol=1e-13, atol=1e-15)))
    worker.start()
    beats = 0
    while worker.is_alive():
        beats += 1
        time.sleep(0.001)
    assert done and done[0].success
    assert beats >= 10, f"the main thread ran {beats} times while the solve ran"


# bad input: a clear exception, never a crash

@pytest.mark.parametrize("kwargs, error, text", [
    (dict(y0=[[1.0, 0.0]]), ValueError, "1-dimensional"),
    (dict(method="no-such-method"), ValueError, "unknown method"),
    (dict(method="DOP853"), ValueError, "gsl-rk8pd"),
    (dict(rtol=-1.0), ValueError, "rtol"),
    (dict(rtol=float("nan")), ValueError, "rtol"),
    (dict(atol=[1e-6, 1e-6, 1e-6]), ValueError, "`atol` has wrong shape"),
    (dict(atol=[-1e-6, 1e-6]), ValueError, "`atol` must be positive"),
    (dict(t_span=(1.0, 1.0)), ValueError, "zero length"),
    (dict(method="rk4"), ValueError, "dt="),
    (dict(t_eval=[0.5, 0.2]), ValueError, "sorted"),
    (dict(t_eval=[3.0]), ValueError, "within"),
    (dict(fun=lambda t, y: [1.0, 2.0, 3.0]), ValueError, r"shape \(3,\)"),
    (dict(fun=lambda t, y: [np.nan, 0.0]), ValueError, "not finite"),
    (dict(fun=lambda t, y: "no"), TypeError, "real numbers"),
    (dict(fun=42), TypeError, "callable"),
    (dict(y0=[1j, 0]), TypeError, "complex"),
    (dict(events=42), TypeError, "callable"),
    (dict(max_step=-1.0), ValueError, "`max_step` must be positive"),  # SciPy's rule: not a backwards solve that diverges
    (dict(max_step=0), ValueError, "`max_step` must be positive"),
    (dict(nonsense=1), TypeError, "nonsense"),
])
def test_bad_input_raises(kwargs, error, text):
    args = dict(fun=oscillator, t_span=(0, 1), y0=[1.0, 0.0])
    args.update(kwargs)
    with pytest.raises(error, match=text):
        stepwise.solve_ivp(**args)


class Raised(Exception):
    pass


@pytest.mark.parametrize("method", ADAPTIVE + [m["name"] for m in FIXED if m["stepping"] == "fixed"])
def test_an_exception_in_fun_propagates_from_every_method(method):
    calls = [0]

    def fun(t, y):
        calls[0] += 1
        if calls[0] == 40:
            raise Raised("from fun")
        return [y[1], -y[0]]

    dt = None if method in ADAPTIVE else 1e-3
    with pytest.raises(Raised) as info:
        stepwise.solve_ivp(fun, (0, 10), [1.0, 0.0], method=method, dt=dt)
    assert any("t = " in note for note in getattr(info.value, "__notes__", [])), info.value
    # and the interpreter goes on
    assert stepwise.solve_ivp(oscillator, (0, 1), [1.0, 0.0], method=method, dt=dt).success


def test_ctrl_c_stops_a_python_solve():
    calls = [0]

    def fun(t, y):
        calls[0] += 1
        if calls[0] == 100:
            os.kill(os.getpid(), signal.SIGINT)
        return [y[1], -y[0]]

    with pytest.raises(KeyboardInterrupt):
        stepwise.solve_ivp(fun, (0, 1e6), [1.0, 0.0], rtol=1e-12, atol=1e-14)
    assert calls[0] <= 101


def test_ctrl_c_stops_a_compiled_solve():
    eq = stepwise.Equations(PENDULUM, parameters={"g": 9.81, "L": 1.0})
    timer = threading.Timer(0.2, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        stepwise.solve_ivp(eq, (0, 1e9), [2.9, 0.0], rtol=1e-13, atol=1e-15)
    # a hang bound, not a speed: without the interruption the solve would run for hours
    assert time.monotonic() - start < 60


# ---- events, the steps taken, dense output and atol per component

def falling_ball(t, y):
    return [y[1], -9.81]


def _floor(t, y):
    return y[0]


def _apex(t, y):
    return y[1]


_floor.direction = -1
_apex.direction = -1


def test_t_events_and_y_events_are_scipys_within_both_tolerances():
    import scipy.integrate as si
    ball = lambda t, y: [y[1], -9.81 - 0.1 * y[1]]  # noqa: E731  (with drag: no closed form in the test's head)
    for method in ["verner98", "tsitouras54", "cvode-bdf", "RK45", "rodas5"]:
        for rtol in (1e-6, 1e-9):
            ours = stepwise.solve_ivp(ball, (0, 3), [1.0, 2.0], method=method, rtol=rtol, atol=rtol * 1e-2, events=[_floor, _apex])
            theirs = si.solve_ivp(ball, (0, 3), [1.0, 2.0], method="DOP853", rtol=rtol, atol=rtol * 1e-2, events=[_floor, _apex])
            for k in range(2):
                assert len(ours.t_events[k]) == len(theirs.t_events[k]) == 1, (method, k)
                # each within its tolerance of the truth: within both of each other (times of order 1 s)
                assert abs(ours.t_events[k][0] - theirs.t_events[k][0]) < 100 * rtol, (method, k)
                assert np.allclose(ours.y_events[k][0], theirs.y_events[k][0], rtol=100 * rtol, atol=100 * rtol)


def test_a_terminal_event_ends_the_solve_there_with_scipys_status():
    floor = lambda t, y: y[0]  # noqa: E731
    floor.terminal = True
    floor.direction = -1
    t_eval = np.linspace(0, 2, 21)
    sol = stepwise.solve_ivp(falling_ball, (0, 2), [1.0, 0.0], rtol=1e-10, atol=1e-12, events=floor, t_eval=t_eval)
    t_hit = np.sqrt(2 / 9.81)
    assert sol.status == 1 and sol.success and "termination" in sol.message
    assert abs(sol.t_events[0][0] - t_hit) < 1e-9
    assert np.array_equal(sol.t, t_eval[t_eval <= t_hit])


def test_without_t_eval_t_and_y_are_the_accepted_steps():
    for method in ["verner98", "cvode-adams"]:
        sol = stepwise.solve_ivp(oscillator, (0, 10), [1.0, 0.0], method=method, rtol=1e-8, atol=1e-10)
        assert sol.t[0] == 0 and sol.t[-1] == 10
        assert len(sol.t) == sol.stats["steps"] + 1, method  # t0 and each accepted step's end
        assert np.all(np.diff(sol.t) > 0)
        assert np.allclose(sol.y[0], np.cos(sol.t), atol=1e-6)


def test_dense_output_is_within_the_methods_error_at_any_time():
    rtol = 1e-8
    for method in ["verner98", "tsitouras54", "cvode-bdf"]:
        sol = stepwise.solve_ivp(oscillator, (0, 10), [1.0, 0.0], method=method, rtol=rtol, atol=rtol * 1e-2, dense_output=True)
        t = np.linspace(0, 10, 997)
        y = sol.sol(t)
        assert y.shape == (2, t.size)
        # the method's own error at its tolerance: a tolerance-proportional global error over 10/(2 pi) periods
        assert np.max(np.abs(y[0] - np.cos(t))) < 1e3 * rtol, method
        assert np.allclose(sol.sol(sol.t[3]), sol.y[:, 3])  # at a step, the step's own value
        assert sol.sol(2.5).shape == (2,)


def test_atol_per_component_is_scipys_error_weight():
    # a component 1e6 times larger, with an atol 1e6 times larger: the same relative accuracy as the scaled-down
    # problem with one atol, to round-off
    big = lambda t, y: [y[1] * 1e6, -y[0] * 1e-6]  # noqa: E731  (x = 1e6 cos t, v = -sin t)
    sol = stepwise.solve_ivp(big, (0, 5), [1e6, 0.0], rtol=1e-9, atol=[1e-6, 1e-12], t_eval=[5.0])
    small = stepwise.solve_ivp(oscillator, (0, 5), [1.0, 0.0], rtol=1e-9, atol=1e-12, t_eval=[5.0])
    assert np.allclose(sol.y[0] / 1e6, small.y[0], rtol=1e-12, atol=1e-15)
    assert abs(sol.y[0, -1] / 1e6 - np.cos(5)) < 1e-7


def test_vectorized_fun_is_called_with_a_column():
    calls = []

    def fun(t, y):
        calls.append(y.shape)
        return np.vstack([y[1], -y[0]])

    sol = stepwise.solve_ivp(fun, (0, 1), [1.0, 0.0], vectorized=True, rtol=1e-8, t_eval=[1.0])
    assert calls[0] == (2, 1) and abs(sol.y[0, -1] - np.cos(1)) < 1e-7


def test_equations_take_events_in_the_scene_files_layout():
    ball = stepwise.Equations({"y": "vy", "vy": "-g"}, parameters={"g": 9.81, "e": 0.8}, initial={"y": 1.0},
                              events={"floor": {"when": "y", "direction": "falling", "action": {"vy": "-e*vy"},
                                                "rest": "e*abs(vy) < 0.01"}})
    sol = stepwise.solve_ivp(ball, (0, 5), [1.0, 0.0], rtol=1e-10, atol=1e-12, t_eval=[5.0])
    assert sol.success and sol.stats["events"] == 28 and len(sol.equation_events["floor"][0]) == 28
    assert sol.y[1, -1] == 0.0 and abs(sol.y[0, -1]) < 1e-9  # at rest on the floor
    with pytest.raises(ValueError, match="direction"):
        stepwise.Equations({"y": "1"}, events={"e": {"when": "y", "direction": "down"}})


def test_an_equations_own_events_and_python_events_are_found_backwards():
    # thrown up at 5 m/s from the floor at t = 0, read back from t = 1: its apex (v = 0) at 5/g, and the height
    # 1 m at the roots of g t^2/2 - 5 t + 1 = 0, the later first. The system's own event alone, and beside a
    # Python event (its own are then mapped to reversed time with the Python one)
    g = 9.81
    ball = stepwise.Equations({"y": "v", "v": "-g"}, parameters={"g": g}, events={"apex": {"when": "v", "direction": "falling"}})
    at_one = [5.0 - g / 2, 5.0 - g]
    height = lambda t, y: y[0] - 1.0  # noqa: E731
    roots = [(5 + np.sqrt(25 - 2 * g)) / g, (5 - np.sqrt(25 - 2 * g)) / g]
    for events in (None, height):
        sol = stepwise.solve_ivp(ball, (1.0, 0.0), at_one, rtol=1e-10, atol=1e-12, events=events)
        apex = sol.equation_events["apex"][0]
        assert sol.success and len(apex) == 1 and abs(apex[0] - 5 / g) < 1e-9, (events, apex)
        assert abs(sol.y[0, -1]) < 1e-9 and abs(sol.y[1, -1] - 5.0) < 1e-9
        if events:
            assert np.allclose(sol.t_events[0], roots, atol=1e-9, rtol=0), sol.t_events
            assert np.allclose(sol.y_events[0][:, 0], 1.0, atol=1e-9, rtol=0)


def test_a_scene_runs_events_into_its_summary_and_trajectory():
    r = stepwise.run("bouncing-ball-equations")
    events = r.summary["events"]
    assert len(events) == 28 and events[-1]["kind"] == "rest"
    for e in events:
        assert set(e["state"]) == {"y", "vy", "floor.resting"}
        # trajectory.csv holds the states just before and after, two rows at the event's time
        rows = np.flatnonzero(r.t == e["t"])
        assert len(rows) == 2
        assert r.y[r.names.index("vy"), rows[0]] == e["state"]["vy"]
        assert r.y[r.names.index("vy"), rows[1]] == e["state_after"]["vy"]
    assert np.all(np.diff(r.t) >= 0)


# ---- events at one instant (docs/scenes.md#events): each fires once there, in the order of the events list

def _rising(t, y):
    return y[0] - 0.5


def _falling(t, y):
    return 0.5 - y[0]


def _unit_speed(t, y):
    return [1.0]


def _solvers(rtol):
    """stepwise's methods of each kind for the event cases: a fixed step landing on the instant, an explicit pair, BDF"""
    return [("rk4", {"dt": 0.1}), ("verner98", {"rtol": rtol, "atol": rtol * 1e-3}), ("tsitouras54", {"rtol": rtol, "atol": rtol * 1e-3}),
            ("cvode-bdf", {"rtol": rtol, "atol": rtol * 1e-3})]


def test_events_at_one_instant_are_each_recorded_as_scipy_records_them():
    rtol = 1e-9
    theirs = scipy.integrate.solve_ivp(_unit_speed, (0, 1), [0.0], method="DOP853", rtol=rtol, atol=rtol * 1e-3, events=[_rising, _falling])
    assert [len(t) for t in theirs.t_events] == [1, 1]
    for method, options in _solvers(rtol):
        ours = stepwise.solve_ivp(_unit_speed, (0, 1), [0.0], method=method, events=[_rising, _falling], **options)
        assert [len(t) for t in ours.t_events] == [1, 1], (method, ours.t_events)
        for k in range(2):
            assert abs(ours.t_events[k][0] - theirs.t_events[k][0]) < 100 * rtol, (method, k)
            assert np.allclose(ours.y_events[k][0], theirs.y_events[k][0], rtol=100 * rtol, atol=100 * rtol)


def test_two_balls_falling_together_cross_the_floor_at_one_instant_as_in_scipy():
    def balls(t, y):
        return [y[2], y[3], -9.81, -9.81]

    def floor1(t, y):
        return y[0]

    def floor2(t, y):
        return y[1]

    floor1.direction = floor2.direction = -1
    rtol = 1e-9
    y0 = [1.0, 1.0, 0.0, 0.0]
    theirs = scipy.integrate.solve_ivp(balls, (0, 1), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-3, events=[floor1, floor2])
    t_hit = np.sqrt(2 / 9.81)
    for method, options in _solvers(rtol):
        ours = stepwise.solve_ivp(balls, (0, 1), y0, method=method, events=[floor1, floor2], **options)
        assert [len(t) for t in ours.t_events] == [len(t) for t in theirs.t_events] == [1, 1], (method, ours.t_events)
        assert ours.t_events[0][0] == ours.t_events[1][0], method
        tol = 1e-12 if method == "rk4" else 100 * rtol
        assert abs(ours.t_events[0][0] - t_hit) < tol and abs(theirs.t_events[0][0] - t_hit) < 100 * rtol, method
        assert np.array_equal(ours.y[0], ours.y[1]), method


def test_two_bouncing_balls_written_as_equations_stay_equal_to_the_bit():
    balls = stepwise.Equations({"y1": "v1", "y2": "v2", "v1": "-g", "v2": "-g"}, parameters={"g": 9.81, "e": 0.8},
                               events={"floor1": {"when": "y1", "direction": "falling", "action": {"v1": "-e*v1"}},
                                       "floor2": {"when": "y2", "direction": "falling", "action": {"v2": "-e*v2"}}})
    impacts = [np.sqrt(2 / 9.81)]
    for k in (1, 2):
        impacts.append(impacts[-1] + 2 * 0.8**k * np.sqrt(2 * 9.81) / 9.81)
    for method in ("verner98", "tsitouras54", "cvode-bdf"):
        sol = stepwise.solve_ivp(balls, (0, 2), [1.0, 1.0, 0.0, 0.0], method=method, rtol=1e-10, atol=1e-12)
        first, second = sol.equation_events["floor1"][0], sol.equation_events["floor2"][0]
        assert np.array_equal(first, second), (method, first, second)
        assert np.allclose(first, impacts, atol=tolerance("event_time_per_rtol") * 1e-10, rtol=0), (method, first)
        assert np.array_equal(sol.y[0], sol.y[1]) and np.array_equal(sol.y[2], sol.y[3]), method


def test_a_terminal_event_at_an_instant_with_others_records_them_all():
    # SciPy records the events of the step up to the first terminal one in its sorted order, so at one instant it
    # drops those listed after the terminal one; stepwise records every event of the instant (docs/scenes.md#events)
    def terminal(t, y):
        return 0.5 - y[0]

    terminal.terminal = True
    rtol = 1e-9
    theirs = scipy.integrate.solve_ivp(_unit_speed, (0, 1), [0.0], method="DOP853", rtol=rtol, atol=rtol * 1e-3,
                                       events=[_rising, terminal, _rising])
    for method, options in _solvers(rtol):
        ours = stepwise.solve_ivp(_unit_speed, (0, 1), [0.0], method=method, events=[_rising, terminal, _rising], **options)
        assert ours.status == 1 and abs(ours.t[-1] - 0.5) < 100 * rtol, method
        assert [len(t) for t in ours.t_events] == [1, 1, 1], (method, ours.t_events)
        # up to the terminal one, SciPy's
        for k in range(2):
            assert len(theirs.t_events[k]) == 1 and abs(ours.t_events[k][0] - theirs.t_events[k][0]) < 100 * rtol, (method, k)


def test_dense_output_backwards_is_scipys_and_the_exact_solution():
    rtol = 1e-8
    t = np.linspace(10, 0, 997)
    for method in ("verner98", "tsitouras54", "cvode-bdf"):
        ours = stepwise.solve_ivp(oscillator, (10, 0), exact(10), method=method, rtol=rtol, atol=rtol * 1e-2, dense_output=True)
        theirs = scipy.integrate.solve_ivp(oscillator, (10, 0), exact(10), method="DOP853", rtol=rtol, atol=rtol * 1e-2, dense_output=True)
        y = ours.sol(t)
        assert y.shape == (2, t.size)
        # each a tolerance-proportional error over 10/(2 pi) periods: within it of the exact solution and of SciPy's
        assert np.max(np.abs(y - exact(t))) < 1e3 * rtol, method
        assert np.max(np.abs(y - theirs.sol(t))) < 2e3 * rtol, method
        # at each step's end, the step's own value: the segment lookup finds the right step in decreasing time
        for k in range(1, ours.t.size, max(1, ours.t.size // 7)):
            assert np.allclose(ours.sol(ours.t[k]), ours.y[:, k], rtol=0, atol=1e-12), (method, k)
