#!/usr/bin/env python3
"""What an interruption leaves: the previous outputs intact, no litter after the next run.

usage: interruptions.py STEPWISE SCENES_DIR

- `report --quick` killed at several points (SIGTERM, SIGINT, SIGKILL) over a previous report that holds a
  file of the user's: the previous report and the user's file intact each time; after SIGTERM and SIGINT no
  staging directory, after SIGKILL the next report's start removes the one left.
- `run` killed while streaming a long trajectory: the previous trajectory.csv and summary.json intact, no
  temporary after SIGTERM, and the one a SIGKILL left removed by the next run.
- `render` stopped: render.json written for the frames finished.
- the report's pictures (`study pictures --quick`: every scene drawn by its own sweep thread and GL context,
  frames encoded, ffmpeg children) sent SIGTERM 20 times at random moments of their first 3 s: each exit 143
  with the interruption's one line and nothing else of ours (a run's threads fail as their files go; a main
  returning then ran the static destructors under them: SIGSEGV one try in three), no litter.
- plot.py's figure workers (a fork pool) die with plot.py when it is killed outright (they outlived a killed
  report by two seconds and wrote into its staging directory).

    interruptions.py STEPWISE SCENES_DIR --report-pictures N

runs instead `report --quick` over a previous report N times, each sent SIGTERM 0.5-4 s after its pictures phase
begins (its drawing threads, GL contexts, encoder children, the cloth's CHOLMOD analyses): each exit 143 with
the interruption's one line, no temporary left, the previous report and the user's file beside it unchanged.
METIS, called by CHOLMOD from several sweep threads at once, used to leave its own SIGTERM handler installed (a
longjmp to a jump buffer of another thread): SIGSEGV 6 tries in 6 (solvers/sparse_cholesky.cpp)."""
import json
import os
import random
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


def litter(d):
    return sorted(os.path.join(r, n) for r, ds, fs in os.walk(d) for n in ds + fs if ".stepwise-" in n and n != ".stepwise-report.json")


def start(args):
    return subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def stop(p, sig, after):
    time.sleep(after)
    p.send_signal(sig)
    try:
        _, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        # a hang: say whether stepwise itself was still running, or only something holding its standard error
        # (a child it started), and which processes those were
        alive = p.poll() is None
        try:
            holders = subprocess.run(["ps", "-eo", "pid,ppid,stat,args"], capture_output=True, text=True).stdout.splitlines()
        except OSError:
            holders = []
        suspects = [line for line in holders if "stepwise" in line or "ffmpeg" in line or "cc1" in line]
        expect(False, f"{signal.Signals(sig).name} after {after:.2f} s: no end within 60 s (stepwise {'still running' if alive else f'exited {p.returncode}'}); "
                      f"processes: {suspects[:8]}")
        p.kill()
        _, err = p.communicate()
    return p.returncode, err


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie (ended, not yet reaped by its new parent) counts as ended
    with open(f"/proc/{pid}/stat") as f:
        return f.read().rsplit(")", 1)[1].split()[0] != "Z"


def figure_workers_die_with_plot(report_dir):
    """plot.py's pool as plot.py makes it, each worker napping; plot.py killed outright: the workers end too"""
    code = (f"import multiprocessing, os, sys, time\nsys.path.insert(0, {report_dir!r})\nimport plot\n"
            "def nap(_):\n    time.sleep(30)\n"
            "if __name__ == '__main__':\n"
            "    pool = multiprocessing.get_context('fork').Pool(2, plot.die_with_parent, (os.getpid(),))\n"
            "    pool.map_async(nap, range(2))\n"
            "    time.sleep(0.5)\n"
            "    print(' '.join(str(p.pid) for p in pool._pool), flush=True)\n"
            "    time.sleep(30)\n")
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    workers = [int(p) for p in parent.stdout.readline().split()]
    expect(len(workers) == 2 and all(alive(w) for w in workers), f"plot.py's pool did not start: {workers}")
    parent.kill()
    parent.wait()
    time.sleep(0.5)
    left = [w for w in workers if alive(w)]
    expect(not left, f"plot.py killed outright: its figure workers {left} still run 0.5 s later")
    for w in left:
        os.kill(w, signal.SIGKILL)
    if not left:
        print(f"plot.py killed: its {len(workers)} figure workers ended with it")


def previous_report(d):
    """a previous report (its files and the marker listing them) with a file of the user's beside them; its snapshot"""
    prev = os.path.join(d, "prev")
    os.mkdir(prev)
    for name, text in [("report.md", "# the previous report\n"), ("a.csv", "x\n1\n")]:
        with open(os.path.join(prev, name), "w") as f:
            f.write(text)
    with open(os.path.join(prev, ".stepwise-report.json"), "w") as f:
        json.dump({"written_by": "stepwise report", "files": ["report.md", "a.csv"]}, f)
    with open(os.path.join(prev, "mine.txt"), "w") as f:
        f.write("the user's\n")
    return prev, {n: open(os.path.join(prev, n)).read() for n in os.listdir(prev)}


def ours(err):
    """our lines, less the progress lines ("stepwise: study pictures ...", "stepwise:   3/25 points, ...")"""
    return [line for line in err.splitlines() if line.startswith("stepwise") and not line.startswith(("stepwise: study ", "stepwise:   "))]


def report_pictures(binary, tries):
    """`report --quick` stopped by SIGTERM 0.5-4 s into its pictures phase, `tries` times"""
    d = tempfile.mkdtemp(prefix="stepwise-interrupt-")
    try:
        prev, snapshot = previous_report(d)
        rng = random.Random(55)
        delays = [0.5 + 3.5 * k / max(tries - 1, 1) for k in range(tries)] if tries <= 3 else [rng.uniform(0.5, 4.0) for _ in range(tries)]
        for k, delay in enumerate(delays):
            p = subprocess.Popen([binary, "report", "--quick", "--out", prev], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            said = []
            for line in p.stderr:
                said.append(line)
                if line.startswith("stepwise: study pictures"):
                    time.sleep(delay)
                    p.send_signal(signal.SIGTERM)
                    break
            _, err = p.communicate(timeout=120)
            err = "".join(said) + err
            what = f"report stopped by SIGTERM {delay:.2f} s into its pictures (try {k + 1})"
            expect(any(line.startswith("stepwise: study pictures") for line in said), f"{what}: the report never reached its pictures: {err[-300:]!r}")
            expect(p.returncode == 128 + signal.SIGTERM, f"{what}: exit status {p.returncode}; said {err[-300:]!r}")
            expect(len(ours(err)) == 1 and "interrupted (SIGTERM)" in ours(err)[0], f"{what}: said {ours(err)!r}")
            expect(not litter(d), f"{what}: left {litter(d)}")
            now = {n: open(os.path.join(prev, n)).read() for n in os.listdir(prev)}
            expect(now == snapshot, f"{what}: the previous report changed")
        print(f"report --quick stopped in its pictures phase {tries} times: {len(failures)} failure(s)")
    finally:
        shutil.rmtree(d, ignore_errors=True)


def main():
    binary, scenes = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if len(sys.argv) > 4 and sys.argv[3] == "--report-pictures":
        report_pictures(binary, int(sys.argv[4]))
        print("interruptions:", "ok" if not failures else f"{len(failures)} failure(s)")
        sys.exit(1 if failures else 0)
    figure_workers_die_with_plot(os.path.join(os.path.dirname(scenes), "report"))
    d = tempfile.mkdtemp(prefix="stepwise-interrupt-")
    try:
        prev, snapshot = previous_report(d)

        for sig, after in [(signal.SIGTERM, 1.0), (signal.SIGINT, 4.0), (signal.SIGKILL, 2.5)]:
            code, err = stop(start([binary, "report", "--quick", "--out", prev]), sig, after)
            name = signal.Signals(sig).name
            expect(code in (128 + sig, -sig), f"report killed by {name}: exit status {code}")
            now = {n: open(os.path.join(prev, n)).read() for n in os.listdir(prev)}
            expect(now == snapshot, f"report killed by {name} after {after} s: the previous report changed")
            if sig != signal.SIGKILL:
                expect(not litter(d), f"report killed by {name}: left {litter(d)}")
                expect("interrupted" in err, f"report killed by {name}: said {err[-200:]!r}")
        expect(litter(d), "a report killed outright leaves its staging directory (the next run's to remove)")
        code, _ = stop(start([binary, "report", "--quick", "--out", prev]), signal.SIGTERM, 2.0)
        expect(not litter(d), f"the next report removed the staging a SIGKILL left: {litter(d)}")

        # run: a previous run's outputs, then a long run stopped while it streams
        out = os.path.join(d, "run")
        subprocess.run([binary, "run", os.path.join(scenes, "pendulum.toml"), "--out", out], check=True, capture_output=True)
        before = {n: open(os.path.join(out, n)).read() for n in ("trajectory.csv", "summary.json")}
        long_run = [binary, "run", os.path.join(scenes, "pendulum.toml"), "--dt", "1e-6", "--output-dt", "1e-6", "--t-end", "40",
                    "--max-steps", "1e8", "--out", out]
        for sig in (signal.SIGTERM, signal.SIGKILL):
            code, _ = stop(start(long_run), sig, 1.5)
            after = {n: open(os.path.join(out, n)).read() for n in ("trajectory.csv", "summary.json")}
            expect(after == before, f"run killed by {signal.Signals(sig).name}: the previous outputs changed")
            if sig == signal.SIGTERM:
                expect(not litter(out), f"run killed by SIGTERM: left {litter(out)}")
        expect(litter(out), "a run killed outright leaves its temporary (the next run's to remove)")
        subprocess.run([binary, "run", os.path.join(scenes, "pendulum.toml"), "--out", out], check=True, capture_output=True)
        expect(not litter(out), f"the next run removed the temporary a SIGKILL left: {litter(out)}")

        # render stopped part-way: render.json lists the frames written
        frames = os.path.join(d, "frames")
        code, _ = stop(start([binary, "render", os.path.join(scenes, "water-drop.toml"), "--frames", "1000", "--dt", "0.001", "--t-end", "3",
                              "--size", "1280x720", "--out", frames]), signal.SIGTERM, 8.0)
        summary = os.path.join(frames, "render.json")
        expect(os.path.exists(summary), "render stopped by SIGTERM: no render.json")
        if os.path.exists(summary):
            j = json.load(open(summary))
            listed = [f["file"] for f in j["frames"]]
            expect(j["status"] == "interrupted", f"render.json says {j['status']}")
            expect(all(os.path.exists(os.path.join(frames, f)) for f in listed), "render.json lists a frame not written")
            print(f"render stopped after {len(listed)} frames; render.json lists them")
        expect(not litter(frames), f"render stopped by SIGTERM: left {litter(frames)}")

        # the pictures' sweep threads stopped at random moments
        rng = random.Random(42)
        tries, started = 20, time.time()
        for k in range(tries):
            pictures = os.path.join(d, f"pictures{k}")
            code, err = stop(start([binary, "study", "pictures", "--quick", "--out", pictures]), signal.SIGTERM, rng.uniform(0.2, 3.0))
            expect(code == 128 + signal.SIGTERM, f"pictures stopped by SIGTERM (try {k + 1}): exit status {code}; said {err[-300:]!r}")
            expect(len(ours(err)) == 1 and "interrupted (SIGTERM)" in ours(err)[0], f"pictures stopped by SIGTERM (try {k + 1}): said {ours(err)!r}")
            expect(not litter(pictures), f"pictures stopped by SIGTERM (try {k + 1}): left {litter(pictures)}")
            shutil.rmtree(pictures, ignore_errors=True)
        print(f"pictures: {tries} SIGTERMs in {time.time() - started:.0f} s")
    finally:
        shutil.rmtree(d, ignore_errors=True)
    print("interruptions:", "ok" if not failures else f"{len(failures)} failure(s)")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
