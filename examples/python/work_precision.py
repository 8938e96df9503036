#!/usr/bin/env python3
"""A work-precision diagram of three methods on your own fun: error at t_end against the solve's time.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/work_precision.py [out.png]

Replace `fun`, `y0` and `t_end` with your system; the reference is the tightest solve of the best method."""
import sys
import time

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import stepwise  # noqa: E402


def fun(t, y):  # your system: here a damped, driven pendulum
    return [y[1], -9.81 * np.sin(y[0]) - 0.1 * y[1] + 0.5 * np.cos(2 * t)]


y0, t_end = [2.5, 0.0], 20.0
methods = ["verner98", "tsitouras54", "cvode-adams"]
reference = stepwise.solve_ivp(fun, (0, t_end), y0, method="verner98", rtol=1e-13, atol=1e-15).y[:, -1]

for method in methods:
    errors, seconds = [], []
    for rtol in 10.0 ** -np.arange(3, 12):
        start = time.perf_counter()
        sol = stepwise.solve_ivp(fun, (0, t_end), y0, method=method, rtol=rtol, atol=rtol * 1e-3)
        seconds.append(time.perf_counter() - start)
        errors.append(np.max(np.abs(sol.y[:, -1] - reference)))
    plt.loglog(errors, seconds, "o-", label=method)
    print(f"{method:12s} errors {min(errors):.1e}..{max(errors):.1e}, {min(seconds) * 1e3:.2f}..{max(seconds) * 1e3:.2f} ms")

plt.xlabel("error at t_end")
plt.ylabel("time per solve (s)")
plt.title("work against precision on your own fun")
plt.legend()
plt.grid(True, which="both", alpha=0.3)
out = sys.argv[1] if len(sys.argv) > 1 else "work_precision.png"
plt.savefig(out, dpi=100)
print("wrote", out)
