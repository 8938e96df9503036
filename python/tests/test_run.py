"""stepwise.run, advise, study and methods against the command line: the same numbers, to the bit."""
import csv
import json
import subprocess

import numpy as np
import pytest

import stepwise
from conftest import BINARY, scene, tolerance


def test_methods_are_the_command_lines_table():
    cli = json.loads(subprocess.run([BINARY, "methods", "--json"], capture_output=True, text=True, check=True).stdout)
    ours = stepwise.methods()
    assert [m["name"] for m in ours] == [m["name"] for m in cli]
    for a, b in zip(ours, cli):
        assert (a["family"], a["source"], a["order"]) == (b["family"], b["source"], b["order"])
        assert (a["stepping"] != "adaptive") == b["fixed_step"] and (a["stepping"] != "fixed") == b["adaptive"]
        assert a["options"] == b["options"], a["name"]


@pytest.mark.parametrize("name, args", [
    ("pendulum", dict(method="rk4", dt=1e-3)),
    ("pendulum", dict(method="cvode-bdf", rtol=1e-8, atol=1e-10)),
    ("pendulum-equations", dict(method="verner98", rtol=1e-9, atol=1e-12)),
    ("van-der-pol", dict(method="gsl-rk8pd", rtol=1e-8, atol=1e-10, set={"mu": 2.0})),
    ("bouncing-ball", dict(method="tsitouras54", rtol=1e-8, atol=1e-10)),
    ("hanging-chain", dict(method="vbd", dt=1 / 60, t_end=0.1, iterations=7, start="inertial")),
])
def test_run_equals_the_command_line_bit_for_bit(tmp_path, name, args):
    r = stepwise.run(scene(name), **args)
    cmd = [BINARY, "run", scene(name), "--out", str(tmp_path)]
    for key in ("method", "dt", "rtol", "atol", "t_end", "iterations", "start"):
        if key in args:
            cmd += ["--" + key.replace("_", "-"), args[key] if isinstance(args[key], str) else repr(args[key])]
    for key, value in args.get("set", {}).items():
        cmd += ["--set", f"{key}={value!r}"]
    subprocess.run(cmd, check=True, capture_output=True)
    with open(tmp_path / "trajectory.csv") as f:
        rows = list(csv.reader(f))
    # 17 significant digits read back exactly
    table = np.array([[float(v) for v in row] for row in rows[1:]]).T
    assert rows[0] == r.columns
    assert np.array_equal(table[0], r.t)
    values = np.vstack([r.y] + ([r.energy] if r.energy is not None else []))
    assert np.array_equal(table[1:], values)
    summary = json.loads((tmp_path / "summary.json").read_text())
    for key in ("status", "steps", "rejected", "rhs_evals", "jac_evals", "final_state", "error", "events", "parameters"):
        assert summary[key] == r.summary[key], key
    # a method's own options, as keyword arguments: taken, and echoed as the command line echoes them
    for key in ("iterations", "start"):
        assert (summary.get(key), r.summary.get(key)) == (args.get(key),) * 2, key


def test_run_by_name_and_bad_input():
    assert stepwise.run("pendulum", t_end=0.5).summary["scene"] == "pendulum"
    with pytest.raises(ValueError, match="no-such-scene"):
        stepwise.run("no-such-scene")
    with pytest.raises(ValueError, match="dt"):
        stepwise.run("pendulum", dt=-1.0)
    with pytest.raises(ValueError, match="nonsense"):
        stepwise.run("pendulum", set={"nonsense": 1.0})
    # a method's option: out of its range, or for a method that does not take it, refused naming both
    with pytest.raises(ValueError, match=r"--iterations 0: must be a whole number in 1\.\.1000000"):
        stepwise.run("hanging-chain", method="vbd", dt=0.01, iterations=0)
    with pytest.raises(ValueError, match="--iterations: rk4 takes no --iterations"):
        stepwise.run("pendulum", method="rk4", dt=0.01, iterations=3)


def test_advise_meets_the_error_asked():
    a = stepwise.advise(scene("van-der-pol"), error=1e-6, budget=4)
    assert a["method"] in {m["name"] for m in stepwise.methods()}
    best = a["candidates"][0]
    assert best["method"] == a["method"] and best["status"] == "advised"
    assert a["error"] <= 1e-6 and best["cheapest"]["error"] == a["error"]
    assert a["markdown"].startswith("#")
    assert len(a["sweep"]["method"]) == len(a["sweep"]["cpu_seconds"]) > 0


def test_study_convergence_on_a_scene():
    out = stepwise.study("convergence", scene("damped-oscillator"), quick=True, threads=1)
    assert out["markdown"]
    orders = out["tables"]["convergence_orders"]
    # every fixed-step method's observed order on the user's scene: its documented one within order_band
    for method, documented, observed in zip(orders["method"], orders["documented_order"], orders["observed_order"]):
        if method in ("rk4", "euler", "odeint-rk4"):
            assert abs(observed - float(documented)) <= tolerance("order_band"), (method, observed)
    assert "rk4" in orders["method"]
    with pytest.raises(ValueError, match="runs on its own scenes"):
        stepwise.study("cloth", scene("damped-oscillator"))


def test_the_readmes_python_runs():
    """the README's Python section, as written"""
    import os
    import re
    from conftest import SOURCE
    text = open(os.path.join(SOURCE, "README.md")).read()
    code = re.search(r"## From C\+\+ and Python.*?```python\n(.*?)```", text, re.S).group(1)
    exec(compile(code, "README.md", "exec"), {})


def test_the_python_example_draws_its_diagram(tmp_path):
    import os
    import sys
    from conftest import SOURCE
    out = tmp_path / "wp.png"
    subprocess.run([sys.executable, os.path.join(SOURCE, "examples", "python", "work_precision.py"), str(out)], check=True,
                   capture_output=True, timeout=120)
    assert out.stat().st_size > 10000


@pytest.mark.parametrize("name, shape", [("heat-1d", (65,)), ("heat-2d", (33, 33))])
def test_a_pde_scenes_fields_are_arrays_equal_to_the_command_lines_files(tmp_path, name, shape):
    # each field (time x nodes, or time x ny x nx), its nodes' coordinates, and the same numbers as field_u.csv and
    # grid.csv of `stepwise run` (both written with 17 significant digits: read back exactly)
    r = stepwise.run(scene(name), output_dt=0.25)
    assert r.fields["u"].shape == (len(r.t),) + shape
    subprocess.run([BINARY, "run", scene(name), "--output-dt", "0.25", "--out", str(tmp_path)], check=True, capture_output=True)
    field = np.loadtxt(tmp_path / "field_u.csv", delimiter=",", skiprows=1)
    grid = np.loadtxt(tmp_path / "grid.csv", delimiter=",", skiprows=1)
    assert np.array_equal(field[:, 0], r.t)
    assert np.array_equal(field[:, 1:], r.fields["u"].reshape(len(r.t), -1))
    assert np.array_equal(grid[:, 0], r.x) and np.array_equal(grid[:, 1], r.y_nodes)
    # the trajectory's columns are the fields' summary: u.max is the field's largest value at each time
    assert np.array_equal(r.y[r.names.index("u.max")], r.fields["u"].reshape(len(r.t), -1).max(axis=1))
