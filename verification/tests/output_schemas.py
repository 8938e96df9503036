#!/usr/bin/env python3
"""Every kind of summary.json `stepwise run` writes, validated against docs/summary.schema.json, and a
render.json and an advice.json against theirs (Debian's python3-jsonschema): a schema allows no field it does not
list, so a field added to the code without the docs fails here.

usage: output_schemas.py STEPWISE SCENES_DIR DOCS_DIR

The runs cover each field the summary writes only sometimes: a fixed and an adaptive step, events and a scene's own
events with their states, a method chosen for the user, a constrained scene (drift, projection, a position-based
method's substeps), backward Euler's Newton, the vbd methods, a divergence, and a scene's own equations."""
import json
import os
import subprocess
import sys
import tempfile

import jsonschema

RUNS = [
    ("bouncing-ball.toml", ["--t-end", "2"]),
    ("pendulum.toml", ["--method", "rk4", "--dt", "0.01", "--t-end", "1"]),
    ("pendulum.toml", ["--method", "rk4", "--dt", "2", "--t-end", "2000"]),  # diverges
    ("pendulum-cartesian.toml", ["--method", "xpbd", "--dt", "0.01", "--substeps", "4", "--t-end", "1"]),
    ("pendulum-cartesian.toml", ["--method", "rk4", "--dt", "0.01", "--constraint", "project", "--t-end", "1"]),
    ("flag.toml", ["--method", "implicit-euler-newton", "--dt", "0.0166666666666667", "--t-end", "0.05"]),
    ("flag.toml", ["--method", "vbd-chebyshev", "--dt", "0.0166666666666667", "--iterations", "3", "--threads", "2", "--rho", "0.95", "--t-end", "0.05"]),
    ("bouncing-ball-equations.toml", ["--t-end", "1"]),
    ("lorenz.toml", ["--t-end", "1"]),
    (None, ["--t-end", "1"]),  # a scene that names no method: model = "pendulum" alone
]


def main():
    stepwise, scenes, docs = sys.argv[1:4]

    def validator(name):
        schema = json.load(open(os.path.join(docs, f"{name}.schema.json")))
        jsonschema.Draft202012Validator.check_schema(schema)
        return jsonschema.Draft202012Validator(schema)

    summaries = validator("summary")
    seen, problems = set(), []
    with tempfile.TemporaryDirectory() as d:
        for k, (scene, args) in enumerate(RUNS):
            out = os.path.join(d, f"run{k}")
            if scene is None:
                scene = os.path.join(d, "no-method.toml")
                with open(scene, "w") as f:
                    f.write('model = "pendulum"\n')
            cmd = [stepwise, "run", os.path.join(scenes, scene), *args, "--out", out]
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
            if done.returncode not in (0, 1):
                problems.append(f"{' '.join(cmd[1:])}: exit {done.returncode}: {done.stderr.strip()}")
                continue
            summary = json.load(open(os.path.join(out, "summary.json")))
            seen |= set(summary) | {f"events.{key}" for e in summary["events"] for key in e}
            for error in summaries.iter_errors(summary):
                problems.append(f"{scene} {' '.join(args)}: {'/'.join(map(str, error.absolute_path)) or 'summary'}: {error.message}")
        # a render (two small frames; a 1-D PDE's too, with its fields and space-time picture) and an advice (a short budget)
        others = [("render", "render.json", ["render", os.path.join(scenes, "pendulum.toml"), "--frames", "2", "--size", "64x48"]),
                  ("render", "render.json", ["render", os.path.join(scenes, "heat-1d.toml"), "--frames", "2", "--size", "64x48"]),
                  ("advice", "advice.json", ["advise", os.path.join(scenes, "pendulum.toml"), "--error", "1e-4", "--budget", "3"])]
        for k, (name, file, args) in enumerate(others):
            out = os.path.join(d, f"{name}-{k}")
            done = subprocess.run([stepwise, *args, "--out", out], capture_output=True, text=True, timeout=600)
            if done.returncode != 0:
                problems.append(f"{' '.join(args)}: exit {done.returncode}: {done.stderr.strip()}")
                continue
            for error in validator(name).iter_errors(json.load(open(os.path.join(out, file)))):
                problems.append(f"{file}: {'/'.join(map(str, error.absolute_path)) or name}: {error.message}")
    # the runs reach what they are for: the fields written only sometimes
    for field in ("dt", "rtol", "events.state", "method_choice", "constraint_drift", "constraint", "substeps", "newton_iterations", "colours",
                  "chebyshev_rho", "start", "equations", "energy_initial"):
        if field not in seen:
            problems.append(f"no run wrote {field}: the runs no longer cover it")
    for p in problems:
        print(p)
    print(f"output_schemas: {len(RUNS)} runs, two renders and an advice, {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
