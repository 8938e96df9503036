#!/usr/bin/env python3
"""A user's own system as a new user writes it: no method, a large system, a run killed mid-compile.

usage: open_world.py STEPWISE [--large N]

- a scene whose [run] holds only t_end (HIRES, Schaefer's 8-variable stiff chemistry, and a Kepler orbit) runs:
  summary.json names the method chosen and why (cvode-bdf for the stiff one, tsitouras54 for the orbit), and
  `stepwise advise` advises on it without a method, a step or a tolerance in the scene;
- a dense mean-field system of 100 oscillators (each formula sums all 100: C past the size compiled in the
  background) runs its first steps on the interpreter while the compiler works and says so; killed then by SIGTERM
  and by SIGKILL, it leaves no compiler process (none with its working directory), and after the next run no
  temporary of the killed process in the cache;
- with --large N (the slow label): N oscillators, the time from the command to the first step printed and held
  to a hang bound, the run's peak memory printed (docs/performance.md has the figures).
Exit 0 when all hold, 1 when not."""
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time

failures = []


def expect(condition, what):
    if not condition:
        failures.append(what)
        print("FAIL", what)


HIRES = """model = "equations"
variables = ["y1", "y2", "y3", "y4", "y5", "y6", "y7", "y8"]
[initial]
y1 = 1.0
y2 = 0.0
y3 = 0.0
y4 = 0.0
y5 = 0.0
y6 = 0.0
y7 = 0.0
y8 = 0.0057
[equations]
y1 = "-1.71*y1 + 0.43*y2 + 8.32*y3 + 0.0007"
y2 = "1.71*y1 - 8.75*y2"
y3 = "-10.03*y3 + 0.43*y4 + 0.035*y5"
y4 = "8.32*y2 + 1.71*y3 - 1.12*y4"
y5 = "-1.745*y5 + 0.43*y6 + 0.43*y7"
y6 = "-280*y6*y8 + 0.69*y4 + 1.71*y5 - 0.43*y6 + 0.69*y7"
y7 = "280*y6*y8 - 1.81*y7"
y8 = "-280*y6*y8 + 1.81*y7"
[run]
t_end = 321.8122
"""

KEPLER = """model = "equations"
variables = ["x", "y", "vx", "vy"]
[initial]
x = 0.5
y = 0.0
vx = 0.0
vy = 1.7320508075688772
[equations]
x = "vx"
y = "vy"
vx = "-x/(x^2 + y^2)^(3/2)"
vy = "-y/(x^2 + y^2)^(3/2)"
[run]
t_end = 6.283185307179586
"""


def mean_field(n):
    """n phase oscillators, each pulled by all: x_i' = w_i + K/n sum_j sin(x_j - x_i) (Kuramoto)"""
    names = [f"x{i}" for i in range(n)]
    lines = ['model = "equations"', f"variables = {json.dumps(names)}", "[initial]"]
    lines += [f"x{i} = {0.1 * i % 6.283:.4f}" for i in range(n)]
    lines += ["[parameters]", "K = 2.0"] + [f"w{i} = {1 + 0.01 * i:.3f}" for i in range(n)]
    lines += ["[equations]"]
    for i in range(n):
        lines.append(f'x{i} = "w{i} + K/{n}*(' + "+".join(f"sin(x{j}-x{i})" for j in range(n) if j != i) + ')"')
    lines += ["[run]", "t_end = 1.0", 'method = "rk4"', "dt = 0.01"]
    return "\n".join(lines) + "\n"


def leaked(workdir):
    """processes whose working directory is `workdir` (a compiler started by a stepwise run there)"""
    found = []
    for pid in os.listdir("/proc"):
        if pid.isdigit():
            try:
                if os.readlink(f"/proc/{pid}/cwd") == workdir:
                    found.append((int(pid), open(f"/proc/{pid}/cmdline").read().replace("\0", " ")[:80]))
            except OSError:
                pass
    return found


def without_method(binary, d, env):
    for name, text, expected in [("hires", HIRES, "cvode-bdf"), ("kepler", KEPLER, "tsitouras54")]:
        scene = os.path.join(d, name + ".toml")
        with open(scene, "w") as f:
            f.write(text)
        out = os.path.join(d, name)
        r = subprocess.run([binary, "run", scene, "--out", out], capture_output=True, text=True, env=env, timeout=600)
        expect(r.returncode == 0, f"{name} without a method: exit {r.returncode}: {r.stderr[-300:]}")
        if r.returncode == 0:
            s = json.load(open(os.path.join(out, "summary.json")))
            expect(s["method"] == expected, f"{name}: ran {s['method']}, expected {expected}")
            expect("no method named" in s.get("method_choice", ""), f"{name}: summary.json says no method_choice: {s.get('method_choice')}")
            expect("no method named" in r.stderr, f"{name}: the run did not say which method it chose: {r.stderr[-200:]}")
            print(f"{name}: {s.get('method_choice')}")
        a = subprocess.run([binary, "advise", scene, "--error", "1e-4", "--budget", "8", "--out", out + "-advice"], capture_output=True, text=True,
                           env=env, timeout=300)
        expect(a.returncode == 0, f"advise {name} without a method: exit {a.returncode}: {a.stderr[-300:]}")
        if a.returncode == 0:
            print(f"advise {name}: {json.load(open(os.path.join(out + '-advice', 'advice.json')))['method']}")


def killed_mid_compile(binary, d, env):
    scene = os.path.join(d, "mean-field.toml")
    with open(scene, "w") as f:
        f.write(mean_field(100))
    work = os.path.join(d, "work")
    os.mkdir(work)
    cache = env["STEPWISE_CACHE"]
    for sig in (signal.SIGTERM, signal.SIGKILL):
        p = subprocess.Popen([binary, "run", scene, "--t-end", "1000", "--out", os.path.join(d, "mf")], cwd=work, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, text=True, env=env)
        said = []
        for line in p.stderr:
            said.append(line)
            if "compiled in the background" in line:
                break
        # the Jacobian is made first, then the compiler starts: wait for it and for its temporaries (a hang bound)
        for _ in range(600):
            if leaked(work) and os.path.isdir(cache) and any(n.startswith(f".tmp-{p.pid}-") for n in os.listdir(cache)):
                break
            time.sleep(0.1)
        expect(any("compiled in the background" in line for line in said), f"the mean field did not say it compiles in the background: {said[-3:]}")
        expect(leaked(work), "no compiler ran beside the mean field's run (the test would see nothing)")
        p.send_signal(sig)
        p.communicate(timeout=60)
        expect(p.returncode in (128 + sig, -sig), f"run killed by {signal.Signals(sig).name} mid-compile: exit {p.returncode}")
        for _ in range(50):  # the guard kills its group as soon as it hears of our death
            if not leaked(work):
                break
            time.sleep(0.1)
        left = leaked(work)
        expect(not left, f"run killed by {signal.Signals(sig).name} mid-compile: compiler processes left {left}")
        for pid, _ in left:
            os.kill(pid, signal.SIGKILL)
        if sig == signal.SIGKILL:
            stale = [n for n in os.listdir(cache) if n.startswith(f".tmp-{p.pid}-")]
            expect(stale, "a run killed outright mid-compile left no temporary (the next run's to remove): the test would see nothing")
            # the next compile into the cache removes them (a small system not yet in the cache, compiled in the foreground)
            decay = os.path.join(d, "decay.toml")
            with open(decay, "w") as f:
                f.write('model = "equations"\nvariables = ["u"]\n[initial]\nu = 1.0\n[equations]\nu = "-u"\n[run]\nt_end = 1.0\n')
            r = subprocess.run([binary, "run", decay, "--out", os.path.join(d, "decay")], capture_output=True, text=True, env=env, timeout=300)
            expect(r.returncode == 0, f"the next run: exit {r.returncode}: {r.stderr[-200:]}")
            left = [n for n in os.listdir(cache) if n.startswith(f".tmp-{p.pid}-")]
            expect(not left, f"the next compile left the killed run's temporaries: {left}")
    print("killed mid-compile: no compiler left, temporaries removed by the next compile")


def large(binary, d, env, n):
    """n dense oscillators: the first step within a hang bound, and for up to 300 the run goes on past the background
    compile and ends on the compiled f (the interpreter about 2 s a unit of time at 300; the compile about a minute)"""
    scene = os.path.join(d, f"mean-field-{n}.toml")
    with open(scene, "w") as f:
        f.write(mean_field(n))
    t_end = "100" if n <= 300 else "0.05"
    start = time.monotonic()
    p = subprocess.Popen([binary, "run", scene, "--t-end", t_end, "--out", os.path.join(d, f"mf{n}")], stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True, env=env)
    first = None
    for line in p.stderr:
        if "compiled in the background" in line and first is None:
            first = time.monotonic() - start
    p.wait()
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    expect(p.returncode == 0, f"{n} oscillators: exit {p.returncode}")
    expect(first is not None and first < 120, f"{n} oscillators: the first step after {first} s (a hang bound)")
    s = json.load(open(os.path.join(d, f"mf{n}", "summary.json")))
    e = s["equations"]
    if n <= 300:
        expect(e["evaluation"] == "compiled" and e["compiled_in_background"], f"{n} oscillators: the run did not switch to the compiled f: {e}")
    print(f"{n} dense oscillators: first step {first:.1f} s after the command; peak memory {usage.ru_maxrss / 1024:.0f} MB (the largest of "
          f"stepwise and its compilers); {e['c_bytes'] / 1e6:.3g} MB of C in {e['compile_units']} units; {e['detail']}")


def main():
    binary = os.path.abspath(sys.argv[1])
    d = tempfile.mkdtemp(prefix="stepwise-open-world-")
    env = dict(os.environ, STEPWISE_CACHE=os.path.join(d, "cache"))
    try:
        if len(sys.argv) > 3 and sys.argv[2] == "--large":
            large(binary, d, env, int(sys.argv[3]))
        else:
            without_method(binary, d, env)
            killed_mid_compile(binary, d, env)
    finally:
        shutil.rmtree(d, ignore_errors=True)
    print("open_world:", "ok" if not failures else f"{len(failures)} failure(s)")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
