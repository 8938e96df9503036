#!/usr/bin/env python3
"""A PDE written as text (scenes/gray-scott.toml at 128 x 128, two fields: 32768 unknowns) under stepwise's cvode-bdf
with its exact sparse Jacobian (UMFPACK from 16384 unknowns), against SciPy's solve_ivp(method="BDF") given the same f in NumPy (np.roll
stencils) and the same exact sparse Jacobian (scipy.sparse), as a SciPy user would write them: at equal rtol and
atol, to t = T, each timed on the wall clock (the best of REPEATS), each side's error against stepwise at rtol 1e-10.
Prints each side's time and error, and the ratio SciPy / stepwise.

usage: PYTHONPATH=build/release/python /usr/bin/python3 bench/pde_vs_scipy.py [--quick]"""
import argparse
import os
import time

import numpy as np
import scipy.integrate
import scipy.sparse as sp

import stepwise

parser = argparse.ArgumentParser()
parser.add_argument("--quick", action="store_true", help="a shorter run and one repeat (a smoke run)")
args = parser.parse_args()
N = 128
T = 50.0 if args.quick else 200.0
REPEATS = 1 if args.quick else 3
RTOL, ATOL = 1e-6, 1e-9
SCENE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "gray-scott.toml")
Du, Dv, F, k, L = 2e-5, 1e-5, 0.04, 0.06, 0.5  # the scene's parameters and square
h = L / N


def laplacian_matrix():
    """the periodic five-point Laplacian on the N x N grid, row-major, as scipy.sparse"""
    one = sp.diags([np.ones(N - 1), -2 * np.ones(N), np.ones(N - 1)], [-1, 0, 1], format="lil")
    one[0, N - 1] = one[N - 1, 0] = 1
    eye = sp.identity(N, format="csr")
    return (sp.kron(eye, one.tocsr()) + sp.kron(one.tocsr(), eye)).tocsr() / h**2


LAP = laplacian_matrix()


def lap(u):
    return (np.roll(u, 1, 0) + np.roll(u, -1, 0) + np.roll(u, 1, 1) + np.roll(u, -1, 1) - 4 * u) / h**2


def fun(t, y):
    u, v = y[: N * N].reshape(N, N), y[N * N:].reshape(N, N)
    uvv = u * v * v
    return np.concatenate([(Du * lap(u) - uvv + F * (1 - u)).ravel(), (Dv * lap(v) + uvv - (F + k) * v).ravel()])


def jac(t, y):
    u, v = y[: N * N], y[N * N:]
    I = sp.identity(N * N, format="csr")
    return sp.bmat([[Du * LAP - sp.diags(v * v) - F * I, sp.diags(-2 * u * v)], [sp.diags(v * v), Dv * LAP + sp.diags(2 * u * v) - (F + k) * I]],
                   format="csc")


def timed(run):
    best, out = float("inf"), None
    for _ in range(REPEATS):
        start = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - start)
    return best, out


def final_state(r):
    return np.concatenate([r.fields["u"][-1].ravel(), r.fields["v"][-1].ravel()])


ref = final_state(stepwise.run(SCENE, method="cvode-bdf", rtol=1e-10, atol=1e-13, t_end=T, output_dt=T, set={"points": N}))
# the initial fields as the scene's formulas give them (the run's first row)
first = stepwise.run(SCENE, method="cvode-bdf", rtol=RTOL, atol=ATOL, t_end=1e-9, output_dt=1e-9, set={"points": N})
y0 = np.concatenate([first.fields["u"][0].ravel(), first.fields["v"][0].ravel()])
ours_s, ours = timed(lambda: stepwise.run(SCENE, method="cvode-bdf", rtol=RTOL, atol=ATOL, t_end=T, output_dt=T, set={"points": N}))
scipy_s, theirs = timed(lambda: scipy.integrate.solve_ivp(fun, (0, T), y0, method="BDF", rtol=RTOL, atol=ATOL, jac=jac, t_eval=[T]))
ours_err = np.abs(final_state(ours) - ref).max()
scipy_err = np.abs(theirs.y[:, -1] - ref).max()
print(f"gray-scott {N}x{N}, t = {T:g}, rtol {RTOL:g}, atol {ATOL:g}")
print(f"stepwise cvode-bdf (UMFPACK): {ours_s:8.3f} s, error {ours_err:.2e}, steps {ours.summary['steps']}")
print(f"SciPy BDF (sparse jac):       {scipy_s:8.3f} s, error {scipy_err:.2e}, nfev {theirs.nfev}, njev {theirs.njev}, nlu {theirs.nlu}")
print(f"ratio SciPy / stepwise = {scipy_s / ours_s:.2f}")
