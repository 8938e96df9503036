#!/usr/bin/env python3
"""The installed package from outside: `cmake --install` into a temporary prefix, then

- no installed header includes a backend's header (SUNDIALS, GSL, CHOLMOD, FFTW, GL, MPI, GiNaC, Boost, TOML);
- every installed header includes the project's others as <stepwise/...>, each installed, and the consumer's
  include path (the CMake package's, pkg-config's) is the prefix's include/ alone;
- examples/cpp, a fresh CMake project whose CMakeLists only says find_package(stepwise) and links
  stepwise::stepwise, configures, builds and runs against the prefix: three methods on the user's own Lorenz
  system agree at t = 1 to what their tolerance allows (verification/tolerances.hpp adaptive_agreement_factor);
- the same program built with nothing but `pkg-config --cflags --libs stepwise` runs and prints the same;
- the installed Python package imports from the prefix (not from the build tree) and solves.

usage: install_check.py BUILD_DIR SOURCE_DIR PYTHON"""
import os
import re
import subprocess
import sys
import tempfile

build, source, python = sys.argv[1:4]
problems = []


def tolerance(name):
    text = open(os.path.join(source, "verification", "tolerances.hpp")).read()
    return float(re.search(rf"constexpr double {name} = ([0-9.e+-]+);", text).group(1))


def run(args, **kw):
    r = subprocess.run(args, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        raise SystemExit(f"install_check: {' '.join(args)} exited {r.returncode}:\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}")
    return r.stdout


def states(output):
    """{method: (x, y, z)} from the example's lines"""
    found = {}
    for line in output.splitlines():
        m = re.match(r"(\S+)\s+y\(1\) = \(([^,]+), ([^,]+), ([^)]+)\)", line)
        if m:
            found[m.group(1)] = tuple(float(m.group(k)) for k in (2, 3, 4))
    return found


def check_states(what, output):
    found = states(output)
    if sorted(found) != ["cvode-adams", "odeint-dopri5", "verner98"]:
        problems.append(f"{what}: expected three methods' states, got {output!r}")
        return
    # rtol 1e-10 on a state of size ~20 over a unit of time (Lyapunov exponent 0.9): each within
    # adaptive_agreement_factor x rtol x |y| of the others
    bound = tolerance("adaptive_agreement_factor") * 1e-10 * 30
    ref = found["verner98"]
    for method, y in found.items():
        if max(abs(a - b) for a, b in zip(y, ref)) > bound:
            problems.append(f"{what}: {method} {y} against verner98 {ref}: more than {bound:.1e} apart")


with tempfile.TemporaryDirectory() as d:
    prefix = os.path.join(d, "prefix")
    run(["cmake", "--install", build, "--prefix", prefix])

    # every header under the one prefix: a project header includes another only as <stepwise/...>, which is installed
    project = re.compile(r"#\s*include\s*\"(solvers|models|run|report|verification|render|kernels|gl|gpu)/")
    prefixed = re.compile(r"#\s*include\s*<stepwise/([^>]+)>")
    for root, _, files in os.walk(os.path.join(prefix, "include")):
        for f in files:
            for n, line in enumerate(open(os.path.join(root, f)), 1):
                where = f"installed header {os.path.relpath(os.path.join(root, f), prefix)}:{n}"
                if project.search(line):
                    problems.append(f"{where} includes a project header by a short path: {line.strip()}")
                if (m := prefixed.search(line)) and not os.path.exists(os.path.join(prefix, "include", "stepwise", m.group(1))):
                    problems.append(f"{where} includes <stepwise/{m.group(1)}>, which is not installed")
    targets = open(os.path.join(prefix, "lib", "cmake", "stepwise", "stepwise_targets.cmake")).read()
    if "include/stepwise" in re.search(r"INTERFACE_INCLUDE_DIRECTORIES \"([^\"]*)\"", targets).group(1):
        problems.append("the CMake package puts include/stepwise itself on a consumer's include path")

    backend = re.compile(r"#\s*include\s*[<\"](sundials|nvector|cvode|arkode|sunlinsol|sunmatrix|gsl|cholmod|fftw|mpi|GL|EGL|ginac|boost|toml|CLI|stb)")
    headers = 0
    for root, _, files in os.walk(os.path.join(prefix, "include")):
        for f in files:
            headers += 1
            for n, line in enumerate(open(os.path.join(root, f)), 1):
                if backend.search(line):
                    problems.append(f"installed header {os.path.relpath(os.path.join(root, f), prefix)}:{n} includes a backend: {line.strip()}")
    if not os.path.exists(os.path.join(prefix, "include", "stepwise", "stepwise.hpp")):
        problems.append("include/stepwise/stepwise.hpp not installed")

    # the example as a fresh CMake project: the prefix is all it is told
    example = os.path.join(d, "example")
    env = dict(os.environ)
    env.pop("CMAKE_PREFIX_PATH", None)
    run(["cmake", "-S", os.path.join(source, "examples", "cpp"), "-B", example, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
         f"-DCMAKE_PREFIX_PATH={prefix}"], env=env)
    run(["cmake", "--build", example], env=env)
    check_states("examples/cpp through find_package", run([os.path.join(example, "lorenz")]))

    # the same with pkg-config alone
    env["PKG_CONFIG_PATH"] = os.path.join(prefix, "lib", "pkgconfig")
    flags = run(["pkg-config", "--cflags", "--libs", "stepwise"], env=env).split()
    if any(f.startswith("-I") and f.rstrip("/").endswith("include/stepwise") for f in flags):
        problems.append(f"pkg-config puts include/stepwise itself on a consumer's include path: {flags}")
    binary = os.path.join(d, "lorenz-pkg-config")
    run(["c++", "-O2", os.path.join(source, "examples", "cpp", "lorenz.cpp"), "-o", binary] + flags, env=env)
    check_states("examples/cpp through pkg-config", run([binary]))

    # the installed Python package, from the prefix alone
    site = os.path.join(prefix, "lib", "python3", "dist-packages")
    code = ("import stepwise, numpy as np; assert stepwise.__file__.startswith(%r), stepwise.__file__; "
            "s = stepwise.solve_ivp(lambda t, y: -y, (0, 1), [1.0], rtol=1e-10, atol=1e-12); "
            "print(abs(s.y[0, -1] - np.exp(-1)))") % prefix
    err = float(run([python, "-c", code], env=dict(os.environ, PYTHONPATH=site), cwd=d))
    if err > tolerance("adaptive_agreement_factor") * 1e-10:
        problems.append(f"installed Python: y' = -y to t = 1 at rtol 1e-10 erred by {err:.2e}")
    print(f"install_check: {headers} headers installed; examples/cpp built by find_package and by pkg-config; Python from the prefix")

for p in problems:
    print("FAIL:", p)
sys.exit(1 if problems else 0)
