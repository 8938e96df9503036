#!/usr/bin/env python3
"""The catalogue of bad inputs (verification/catalogue/bad_inputs.toml) against the stepwise binary.

usage: bad_inputs.py STEPWISE SCENES_DIR CATALOGUE

Every case runs in a fresh directory, 60 s at most. It passes when the exit status is the one listed, stderr's
last line matches the pattern, every line of stderr is one message (no line of a message split), and the
listed paths exist or do not; for any case, no temporary of ours (".stepwise-<pid>.") is left behind."""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib


def prepare(case, d):
    setup = case.get("setup")
    if "scene" in case:
        with open(os.path.join(d, "s.toml"), "w") as f:
            f.write(case["scene"])
    if "scene_repeat" in case:
        head, unit, count, tail = case["scene_repeat"]
        with open(os.path.join(d, "s.toml"), "w") as f:
            f.write(head + unit * count + tail)
    if setup == "fifo":
        os.mkfifo(os.path.join(d, "fifo"))
    elif setup == "unreadable":
        os.chmod(os.path.join(d, "s.toml"), 0)
    elif setup == "huge":
        with open(os.path.join(d, "s.toml"), "w") as f:
            f.write('model = "pendulum"\n' + "# padding\n" * (2 << 20))
    elif setup == "user_dir":
        os.mkdir(os.path.join(d, "out"))
        open(os.path.join(d, "out", "report.md"), "w").close()
        with open(os.path.join(d, "out", "data.csv"), "w") as f:
            f.write("a,b\n1,2\n")
    elif setup == "output_blocked":
        os.makedirs(os.path.join(d, "out", "trajectory.csv"))
    elif setup == "file":
        with open(os.path.join(d, "file"), "w") as f:
            f.write("mine\n")


def check(binary, scenes, case):
    d = tempfile.mkdtemp(prefix="stepwise-bad-")
    try:
        prepare(case, d)
        subst = lambda s: s.replace("{scenes}", scenes).replace("{dir}", d)
        env = dict(os.environ)
        for k, v in case.get("env", {}).items():
            env[k] = subst(v)
        args = [binary] + [subst(a) for a in case["args"]]
        try:
            r = subprocess.run(args, capture_output=True, text=True, errors="replace", timeout=60, env=env, cwd=d)
        except subprocess.TimeoutExpired:
            return "took more than 60 s"
        problems = []
        if r.returncode != case["exit"]:
            problems.append(f"exit status {r.returncode}, expected {case['exit']}")
        lines = r.stderr.splitlines()
        last = lines[-1] if lines else ""
        if not re.search(case["message"], last):
            problems.append(f"last line of stderr {last[:300]!r} does not match {case['message']!r}")
        stray = [l for l in lines if not l.startswith("stepwise") and not l.startswith("--") and ": warning:" not in l]
        if case["exit"] == 2 and (len(lines) != 1 or stray):
            problems.append(f"{len(lines)} lines of stderr, expected one: {r.stderr[:300]!r}")
        if len(last) > case.get("max_length", 1000):
            problems.append(f"a message of {len(last)} characters, more than {case.get('max_length', 1000)}")
        for p in case.get("present", []):
            if not os.path.exists(os.path.join(d, p)):
                problems.append(f"{p} is missing")
        for p in case.get("absent", []):
            if os.path.exists(os.path.join(d, p)):
                problems.append(f"{p} was written")
        for root, dirs, files in os.walk(d):
            for name in dirs + files:
                if ".stepwise-" in name and name != ".stepwise-report.json":
                    problems.append(f"temporary left behind: {os.path.join(root, name)}")
        return "; ".join(problems)
    finally:
        for root, dirs, files in os.walk(d):
            for name in files:
                try:
                    os.chmod(os.path.join(root, name), 0o600)
                except OSError:
                    pass
        shutil.rmtree(d, ignore_errors=True)


def main():
    binary, scenes, catalogue = sys.argv[1:4]
    with open(catalogue, "rb") as f:
        cases = tomllib.load(f)["case"]
    failures = skipped = 0
    for case in cases:
        if case.get("skip_as_root") and os.geteuid() == 0:
            skipped += 1  # root reads any file: an unreadable scene cannot be made
            continue
        problem = check(os.path.abspath(binary), os.path.abspath(scenes), case)
        if problem:
            failures += 1
            print(f"FAIL {case['name']}: {problem}")
    print(f"{len(cases) - failures - skipped} of {len(cases) - skipped} bad inputs handled as the catalogue says"
          + (f" ({skipped} skipped as root)" if skipped else ""))
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
