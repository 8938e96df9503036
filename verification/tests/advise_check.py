#!/usr/bin/env python3
"""stepwise advise against its contract and its claims, on shipped equation scenes.

usage: advise_check.py STEPWISE SCENES_DIR

For each case: advise within a small budget, then
- advice.json holds the contract's fields (method, dt or rtol and atol, error, cpu_seconds, stiff, runner_up,
  candidates with method, status and reason), one candidate per method that applies;
- the advice ended (a hang bound only: the advisor starts no run past its budget, but the run in flight finishes,
  and a loaded machine stretches it; the time it took is printed, never held to the budget here);
- the advised setting, given to `stepwise run` (the command a user is told to type), meets the error asked;
- on a stiff scene (Van der Pol at mu = 1e6) the advice says stiff and advises no explicit method, and says why
  the explicit ones lost (their predicted stable step);
- the budget bounds the whole command, the reference included: on the 32 x 32 flag, whose converged reference takes
  hours, advise says so in one line (which reference, how far it got, the budget that would do) with a progress
  line before it, exits 1 and writes nothing (a hang bound only; its time is measured in bench_advise)."""
import json
import os
import subprocess
import sys
import tempfile

binary, scenes = sys.argv[1], sys.argv[2]
problems = []
CASES = [
    # scene, --set, error, budget, stiff expected
    ("damped-oscillator", [], 1e-6, 6, False),
    ("van-der-pol", [], 1e-6, 6, False),
    ("van-der-pol-stiff", ["mu=1e6"], 1e-6, 12, True),
]
EXPLICIT_FAMILIES = ("euler", "rk4", "embedded-pairs")

with tempfile.TemporaryDirectory() as d:
    env = dict(os.environ, STEPWISE_CACHE=os.path.join(d, "cache"))
    methods = {m["name"]: m for m in json.loads(subprocess.run([binary, "methods", "--json"], capture_output=True, text=True, check=True).stdout)}
    for scene, sets, error, budget, stiff in CASES:
        out = os.path.join(d, scene)
        args = [binary, "advise", os.path.join(scenes, scene + ".toml"), "--error", str(error), "--budget", str(budget), "--out", out]
        for s in sets:
            args += ["--set", s]
        r = subprocess.run(args, capture_output=True, text=True, env=env, timeout=budget * 3 + 30)
        if r.returncode != 0:
            problems.append(f"{scene}: advise exit {r.returncode}: {r.stderr[-500:]}")
            continue
        with open(os.path.join(out, "advice.json")) as f:
            a = json.load(f)
        for key in ("method", "error", "cpu_seconds", "stiff", "runner_up", "candidates"):
            if key not in a:
                problems.append(f"{scene}: advice.json has no {key}")
        if not ("dt" in a or ("rtol" in a and "atol" in a)):
            problems.append(f"{scene}: advice.json has neither dt nor rtol and atol")
        for c in a["candidates"]:
            for key in ("method", "status", "reason"):
                if key not in c:
                    problems.append(f"{scene}: a candidate has no {key}: {c}")
        if a["elapsed_seconds"] > 3 * budget + 20:
            problems.append(f"{scene}: took {a['elapsed_seconds']:.1f} s of a {budget} s budget: hung")
        if a["stiff"] != stiff:
            problems.append(f"{scene}: stiff = {a['stiff']}, expected {stiff} (stiffness {a['stiffness']:.3g})")
        print(f"{scene} {' '.join(sets)}: {a['method']} {a.get('dt', a.get('rtol'))}, error {a['error']:.3g} in {a['cpu_seconds']:.3g} s; "
              f"stiffness {a['stiffness']:.3g}; {a['elapsed_seconds']:.1f} s of {budget}")
        if stiff:
            family = methods[a["method"]]["family"]
            if family in EXPLICIT_FAMILIES or a["method"].startswith(("arkode-erk", "odeint-rk", "gsl-rk")) and not a["method"].endswith("imp"):
                problems.append(f"{scene}: advised the explicit method {a['method']} on a stiff system")
            lost = [c for c in a["candidates"] if c["method"] in ("rk4", "verner98")]
            if not lost or any("stab" not in c["reason"] and "times the advised" not in c["reason"] for c in lost):
                problems.append(f"{scene}: the explicit methods' reasons do not say why: {[c['reason'] for c in lost]}")
        # the advised setting through `stepwise run`
        run = [binary, "run", os.path.join(scenes, scene + ".toml"), "--method", a["method"], "--out", os.path.join(out, "run")]
        run += ["--dt", repr(a["dt"])] if "dt" in a else ["--rtol", repr(a["rtol"]), "--atol", repr(a["atol"])]
        for s in sets:
            run += ["--set", s]
        r = subprocess.run(run, capture_output=True, text=True, env=env, timeout=120)
        with open(os.path.join(out, "run", "summary.json")) as f:
            summary = json.load(f)
        measured = summary["error"]
        if measured is None:
            # no exact solution: the advice's own reproduction, measured against its reference, is the check
            measured = a["reproduced"]["error"]
        if r.returncode != 0 or measured is None or measured > error:
            problems.append(f"{scene}: the advised setting run again gave error {measured} (exit {r.returncode}), asked {error}")

    # the flag's reference cannot be had in a small budget: refused, within a (generous) hang bound
    out = os.path.join(d, "flag")
    budget = 4
    r = subprocess.run([binary, "advise", os.path.join(scenes, "flag.toml"), "--error", "1e-2", "--budget", str(budget), "--out", out],
                       capture_output=True, text=True, env=env, timeout=budget * 10 + 60)
    lines = r.stderr.strip().splitlines()
    last = lines[-1] if lines else ""
    if r.returncode != 1 or "the converged reference cannot be had within its share" not in last or "--budget" not in last:
        problems.append(f"flag: advise at --budget {budget}: exit {r.returncode}, last line {last!r}")
    if not any(line.startswith("stepwise advise: the reference: ") for line in lines[:-1]):
        problems.append(f"flag: no progress line during the reference: {lines}")
    if os.path.exists(out):
        problems.append("flag: advise refused but wrote its directory")
    print(f"flag: {last}")

for p in problems:
    print("FAIL", p)
sys.exit(1 if problems else 0)
