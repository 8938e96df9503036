#!/usr/bin/env python3
"""MPI ranks: the same outputs as one process, and a rank that dies fails the run cleanly.

usage: mpi_ranks.py STEPWISE SCENES_DIR TOLERANCES_HPP [SERIAL_QUICK_REPORT]

- `study NAME --quick` for two untimed studies under `mpirun -np 2` and `-np 3`: every CSV byte for byte the
  one-process run's; provenance.json says how many ranks ran and what each was busy for.
- `run` under mpirun: the pool (wave-fd on the water's grid) split among 2, 3 and 4 ranks writes the one-process
  run's trajectory.csv byte for byte and its summary.json (cpu_seconds aside) with `ranks` N; more ranks than the
  grid has rows: exit 2 naming both numbers, nothing written; past the scheme's limit: diverged at the one-process
  run's time, exit 1, its summary written, the warning said once; a model that is not split (the pendulum) runs on
  rank 0 alone, which says so in one line, with `ranks` 1.
- `report --quick` under `-np 2` and `-np 3` against the one-process report given (the report_quick test's):
  every CSV's non-timing columns alike (the cloth's to implicit-euler's kept-factor reproducibility, its counts of work aside, read from
  verification/tolerances.hpp; the rows chosen by CPU time, the recommendations and Pareto fronts, not
  compared).
- a rank killed in the middle of `report --quick` over a previous report: exit status non-zero, the rank named
  (by mpirun) with the points it had in hand (by rank 0), the previous report intact and no staging directory
  left.
Skipped (exit 77) where mpirun is missing, with the line that installs it."""
import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

failures = []
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "report"))
from timed_tables import CHOSEN_BY_TIME, KEPT_FACTOR_COUNTS, TIMING, kept_factor_agree, kept_factor_row  # noqa: E402


def expect(condition, what):
    if not condition:
        failures.append(what)
        print("FAIL", what)


def mpirun(n):
    args = ["mpirun", "--oversubscribe", "-np", str(n)]
    if os.geteuid() == 0:
        args.append("--allow-run-as-root")
    return args


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=900, **kw)


def compare_tables(serial, ranked, label, root):
    names = sorted(n for n in os.listdir(serial) if n.endswith(".csv"))
    expect(names == sorted(n for n in os.listdir(ranked) if n.endswith(".csv")), f"{label}: the same CSV files")
    compared = 0
    for name in names:
        if name in CHOSEN_BY_TIME or not os.path.exists(os.path.join(ranked, name)):
            continue
        a = list(csv.reader(open(os.path.join(serial, name))))
        b = list(csv.reader(open(os.path.join(ranked, name))))
        if not a or a[0] != (b[0] if b else None) or len(a) != len(b):
            expect(False, f"{label}: {name}: header or row count differs")
            continue
        keep = [i for i, h in enumerate(a[0]) if not TIMING.search(h)]
        for ra, rb in zip(a[1:], b[1:]):
            tolerant = kept_factor_row(name, a[0], ra)
            same = (all(kept_factor_agree(a[0][i], ra[i], rb[i], root) for i in keep if a[0][i] not in KEPT_FACTOR_COUNTS) if tolerant
                    else all(ra[i] == rb[i] for i in keep))
            if not same:
                expect(False, f"{label}: {name}: row {ra} against {rb}")
                break
        compared += 1
    print(f"{label}: {compared} CSV files compared with the one-process run's")


def main():
    binary, scenes, tolerances = (os.path.abspath(a) for a in sys.argv[1:4])
    serial_report = os.path.abspath(sys.argv[4]) if len(sys.argv) > 4 else None
    if not shutil.which("mpirun"):
        print("mpirun not found: install Open MPI's launcher (sudo apt-get install openmpi-bin) to run the MPI tests")
        return 77
    root = os.path.dirname(os.path.dirname(tolerances))  # the source tree whose tolerances.hpp the comparison reads
    d = tempfile.mkdtemp(prefix="stepwise-mpi-")
    try:
        # studies, byte for byte
        for study, files in [("convergence", ["convergence.csv", "convergence_orders.csv"]),
                             ("stability-regions", ["stability_spectrum.csv", "stability_limits.csv"])]:
            one = os.path.join(d, f"{study}-1")
            r = run([binary, "study", study, "--quick", "--out", one])
            expect(r.returncode == 0, f"study {study}: exit {r.returncode}: {r.stderr[-300:]}")
            for n in (2, 3):
                out = os.path.join(d, f"{study}-{n}")
                r = run(mpirun(n) + [binary, "study", study, "--quick", "--threads", "1", "--out", out])
                expect(r.returncode == 0, f"study {study} on {n} ranks: exit {r.returncode}: {r.stderr[-500:]}")
                for f in files:
                    same = open(os.path.join(one, f), "rb").read() == open(os.path.join(out, f), "rb").read()
                    expect(same, f"study {study} on {n} ranks: {f} differs from one process's")
                p = json.load(open(os.path.join(out, "provenance.json")))
                expect(p["ranks"] == n and len(p["rank_busy_seconds"]) == n, f"study {study} on {n} ranks: provenance.json says {p['ranks']} ranks")
                print(f"study {study} on {n} ranks: CSVs as one process's; ranks busy {p['rank_busy_seconds']}")
            p = json.load(open(os.path.join(one, "provenance.json")))
            expect(p["ranks"] == 1, "one process: provenance.json says 1 rank")

        # run: the pool split among the ranks, the same bytes as one process
        one = os.path.join(d, "pool-1")
        pool = [os.path.join(scenes, "pool.toml"), "--set", "size=67", "--t-end", "3"]
        r1 = run([binary, "run"] + pool + ["--out", one])
        expect(r1.returncode == 0, f"pool in one process: exit {r1.returncode}: {r1.stderr[-300:]}")
        for n in (2, 3, 4):
            out = os.path.join(d, f"pool-{n}")
            r = run(mpirun(n) + [binary, "run"] + pool + ["--out", out])
            expect(r.returncode == 0 and "rank 0 alone" not in r.stderr, f"pool on {n} ranks: exit {r.returncode}, split: {r.stderr[-300:]}")
            if r.returncode != 0:
                continue
            s1, sn = (json.load(open(os.path.join(x, "summary.json"))) for x in (one, out))
            expect(s1["ranks"] == 1 and sn["ranks"] == n, f"pool on {n} ranks: summary.json's ranks {sn['ranks']}")
            expect(len(sn["events"]) == len(s1["events"]) > 0, f"pool on {n} ranks: {len(sn['events'])} drops, one process {len(s1['events'])}")
            for s in (s1, sn):
                s.pop("cpu_seconds")
                s.pop("ranks")
            expect(s1 == sn, f"pool on {n} ranks: summary.json as one process's (cpu_seconds and ranks aside)")
            expect(open(os.path.join(one, "trajectory.csv"), "rb").read() == open(os.path.join(out, "trajectory.csv"), "rb").read(),
                   f"pool on {n} ranks: trajectory.csv as one process's, byte for byte")
            print(f"run pool (67 x 67, 3 s, {len(s1['events'])} drops) on {n} ranks: trajectory.csv and summary.json as one process's")
        # past the scheme's limit: diverged at the same time as one process, exit 1, the summary written, said once
        one, two = os.path.join(d, "pool-diverged-1"), os.path.join(d, "pool-diverged-2")
        past = [os.path.join(scenes, "pool.toml"), "--dt", "0.02"]
        r1 = run([binary, "run"] + past + ["--out", one])
        r2 = run(mpirun(2) + [binary, "run"] + past + ["--out", two])
        expect(r1.returncode == 1 and r2.returncode == 1, f"pool past its limit: exit {r1.returncode} and {r2.returncode} on 2 ranks (1)")
        if r2.returncode == 1:
            s1, s2 = (json.load(open(os.path.join(x, "summary.json"))) for x in (one, two))
            expect(s2["status"] == "diverged" and s2["t_stop"] == s1["t_stop"],
                   f"pool past its limit on 2 ranks: {s2['status']} at {s2['t_stop']}, one process at {s1['t_stop']}")
        expect(r2.stderr.count("warning: dt") == 1 and "interrupted" not in r2.stderr,
               f"pool past its limit on 2 ranks: the warning once, nobody interrupted: {r2.stderr[-300:]}")
        out = os.path.join(d, "pool-too-many")
        r = run(mpirun(5) + [binary, "run", os.path.join(scenes, "pool.toml"), "--set", "size=4", "--out", out])
        expect(r.returncode == 2 and re.search(r"5 ranks make a 5 x 1 decomposition, more than the grid's 4 rows or 4 columns", r.stderr) is not None,
               f"pool of 4 x 4 points on 5 ranks: exit {r.returncode} (2), naming both numbers: {r.stderr[-300:]}")
        expect(not os.path.exists(out), "pool on too many ranks: nothing written")

        # run: rank 0 alone, one line, the same summary
        one, two = os.path.join(d, "run-1"), os.path.join(d, "run-2")
        scene = os.path.join(scenes, "pendulum.toml")
        r1 = run([binary, "run", scene, "--t-end", "2", "--out", one])
        r2 = run(mpirun(2) + [binary, "run", scene, "--t-end", "2", "--out", two])
        expect(r1.returncode == 0 and r2.returncode == 0, f"run: exit {r1.returncode} and {r2.returncode} on 2 ranks: {r2.stderr[-300:]}")
        lines = [l for l in r2.stderr.splitlines() if "rank 0 alone" in l]
        expect(len(lines) == 1, f"run on 2 ranks: one line saying rank 0 runs it alone (stderr: {r2.stderr!r})")
        s1, s2 = (json.load(open(os.path.join(x, "summary.json"))) for x in (one, two))
        expect(s1["ranks"] == 1 and s2["ranks"] == 1, "run: summary.json's ranks is 1")
        for s in (s1, s2):
            s.pop("cpu_seconds")
        expect(s1 == s2, "run on 2 ranks: summary.json as one process's (cpu_seconds aside)")
        expect(open(os.path.join(one, "trajectory.csv"), "rb").read() == open(os.path.join(two, "trajectory.csv"), "rb").read(),
               "run on 2 ranks: trajectory.csv as one process's")

        # the quick report on 2 and 3 ranks against one process's
        if serial_report:
            for n in (2, 3):
                out = os.path.join(d, f"report-{n}")
                start = time.time()
                r = run(mpirun(n) + [binary, "report", "--quick", "--threads", "1", "--out", out])
                expect(r.returncode == 0, f"report on {n} ranks: exit {r.returncode}: {r.stderr[-500:]}")
                if r.returncode == 0:
                    compare_tables(serial_report, out, f"report --quick on {n} ranks ({time.time() - start:.0f} s)", root)
                    p = json.load(open(os.path.join(out, "provenance.json")))
                    print(f"report on {n} ranks: busy {p['rank_busy_seconds']}, busiest over mean {p['rank_busiest_over_mean']:.3f}")

        # a rank killed in the middle: the run fails naming it, the previous report intact, nothing left over
        prev = os.path.join(d, "prev")
        r = run([binary, "study", "convergence", "--quick", "--out", os.path.join(d, "scratch")])
        os.makedirs(prev)
        with open(os.path.join(prev, ".stepwise-report.json"), "w") as f:
            json.dump({"written_by": "stepwise report", "files": ["report.md"]}, f)
        with open(os.path.join(prev, "report.md"), "w") as f:
            f.write("the previous report\n")
        p = subprocess.Popen(mpirun(2) + [binary, "report", "--quick", "--threads", "1", "--out", prev], stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, text=True)
        victim = None
        for _ in range(200):
            time.sleep(0.1)
            for pid in (x for x in os.listdir("/proc") if x.isdigit()):
                try:
                    env = open(f"/proc/{pid}/environ", "rb").read().split(b"\0")
                    exe = os.readlink(f"/proc/{pid}/exe")
                except OSError:
                    continue
                if os.path.basename(exe) == "stepwise" and b"OMPI_COMM_WORLD_RANK=1" in env:
                    victim = int(pid)
            if victim:
                break
        expect(victim is not None, "killed rank: rank 1 found")
        if victim:
            time.sleep(8)  # into the work-precision sweep (its reference runs come first)
            os.kill(victim, signal.SIGKILL)
        _, err = p.communicate(timeout=120)
        expect(p.returncode != 0, f"killed rank: exit status {p.returncode}, not 0")
        expect(re.search(r"rank 1\b", err) is not None, f"killed rank: the message names rank 1 (stderr: {err[-600:]!r})")
        # rank 0 names the points rank 1 had in hand, the one it was running among them
        expect(re.search(r"rank 1 had \d+ point\(s\) of this sweep in hand \(run costliest first: ", err) is not None,
               f"killed rank: rank 0 names the points rank 1 had in hand (stderr: {err[-600:]!r})")
        expect(open(os.path.join(prev, "report.md")).read() == "the previous report\n", "killed rank: the previous report intact")
        left = [n for n in os.listdir(d) if n.startswith(".prev")]
        expect(not left, f"killed rank: staging left: {left}")
        print(f"killed rank 1: exit {p.returncode}; last lines: {err.strip().splitlines()[-3:] if err.strip() else []}")
    finally:
        shutil.rmtree(d, ignore_errors=True)
    if failures:
        print(f"{len(failures)} failure(s)")
        return 1
    print("all held")
    return 0


if __name__ == "__main__":
    sys.exit(main())
