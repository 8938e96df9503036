#!/usr/bin/python3
"""Draw the report's figures from the CSV files a stepwise study or report wrote, and turn report.md into index.html.

    plot.py DIR [--html] [--dpi N] [--jobs N]

DIR/figures.csv lists the figures (stem, kind, subject): each is drawn by the function of that kind below, from
the CSVs in DIR only, into DIR/stem.png, by N processes at once (--jobs; default 1). DIR/methods.csv (the method table) fixes one colour and marker per
method, the same in every figure. With --html, DIR/report.md becomes DIR/index.html (Python-Markdown, tables), its work-precision and convergence
diagrams to explore (report/interactive.py: plotly.js from Debian's python3-plotly).
Needs Debian's python3-matplotlib (and python3-markdown for --html); exit status 3 names a missing one.
"""
import csv
import ctypes
import math
import multiprocessing
import os
import re
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # report/interactive.py and figure_spec.py beside it
import figure_spec  # noqa: E402

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    import numpy as np
except ImportError as e:
    print(f"plot.py: {e.name} is missing: install Debian's python3-matplotlib (apt-get install python3-matplotlib)", file=sys.stderr)
    sys.exit(3)

DPI = 100  # 1200 x 550 pixels for a two-panel figure; --dpi changes it (the README's copies are drawn smaller)
FAILED_MARKER = dict(marker="x", linestyle="none", markersize=7)


def read(directory, stem):
    """A CSV as a list of dicts, numbers as floats (nan for empty or nan)."""
    with open(os.path.join(directory, stem + ".csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    for row in rows:
        for key, value in row.items():
            try:
                row[key] = float(value)
            except ValueError:
                pass
    return rows


class Styles:
    """One colour and marker per method, fixed by the method table's order."""

    def __init__(self, directory):
        names = [row["name"] for row in read(directory, "methods")]
        colours = plt.get_cmap("tab20").colors + plt.get_cmap("tab20b").colors
        markers = "os^vD<>phP*Xd"
        self.style = {name: dict(color=colours[i % len(colours)], marker=markers[i % len(markers)]) for i, name in enumerate(names)}

    def __call__(self, method):
        return self.style.get(method, dict(color="black", marker="."))


def finish(fig, directory, stem):
    fig.tight_layout()
    path = os.path.join(directory, stem + ".png")
    fig.savefig(path + ".tmp.png", dpi=DPI)
    os.replace(path + ".tmp.png", path)
    plt.close(fig)


def single(fig, ax, directory, stem, xlabel, ylabel, title, grid="major"):
    """Label a one-panel figure, add its grid and legend, and write it."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(True, which=grid, alpha=0.3)
    legend(ax, ncol=1 if len(ax.get_legend_handles_labels()[0]) < 8 else 2)
    finish(fig, directory, stem)


def legend(ax, **kw):
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, ncol=kw.pop("ncol", 2), **kw)


def ok(row):
    return row["status"] == "ok" and not math.isnan(row["error"])


def by_method(rows):
    methods = {}
    for row in rows:
        methods.setdefault(row["method"], []).append(row)
    return methods


# ---- figures, one function per kind


def convergence(directory, scene, styles):
    rows = [r for r in read(directory, "convergence") if r["scene"] == scene]
    orders = {r["method"]: r for r in read(directory, "convergence_orders") if r["scene"] == scene}
    fig, ax = plt.subplots(figsize=(8, 5.5))
    for method, points in by_method(rows).items():
        good = [r for r in points if ok(r) and r["error"] > 0]
        order = orders[method]
        label = f"{method}: {order['observed_order']:.2f} (order {order['documented_order']:g})" if isinstance(
            order["documented_order"], float) else f"{method}: {order['observed_order']:.2f} ({order['documented_order']})"
        ax.loglog([r["dt"] for r in good], [r["error"] for r in good], label=label, **styles(method), markersize=4, linewidth=1)
        failed = [r for r in points if not ok(r)]
        if failed:
            ax.loglog([r["dt"] for r in failed], [1e2] * len(failed), color=styles(method)["color"], **FAILED_MARKER)
    single(fig, ax, directory, f"convergence_{scene}", "step dt (s)", "max-norm error at t_end",
           f"{scene}: convergence (legend: observed slope, documented order; x: diverged or failed, drawn at 1e2)", grid="major")


def work_precision(directory, scene, styles):
    rows = [r for r in read(directory, "work_precision") if r["scene"] == scene]
    fronts = [r for r in read(directory, "work_precision_pareto") if r["scene"] == scene]
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.5), sharey=True)
    for ax, cost, label in ((axes[0], "cpu_seconds", "CPU time (s)"), (axes[1], "rhs_evals", "right-hand-side evaluations")):
        top = max([r["error"] for r in rows if ok(r)] + [1.0]) * 10
        for method, points in by_method(rows).items():
            style = styles(method)
            for mode, line in (("fixed", "-"), ("adaptive", "--")):
                good = sorted((r for r in points if r["mode"] == mode and ok(r) and r["error"] > 0 and r[cost] > 0), key=lambda r: r[cost])
                if good:
                    ax.loglog([r[cost] for r in good], [r["error"] for r in good], linestyle=line, linewidth=1, markersize=3,
                              label=method if mode == "fixed" or not any(r["mode"] == "fixed" for r in points) else None, **style)
            failed = [r for r in points if not ok(r) and r[cost] > 0]
            if failed:
                ax.loglog([r[cost] for r in failed], [top] * len(failed), color=style["color"], **FAILED_MARKER)
        front = [r for r in fronts if r["cost"] == cost and r["error"] > 0]
        if front:
            ax.step([r[cost] for r in front], [r["error"] for r in front], where="post", color="black", linewidth=2, alpha=0.5,
                    label="Pareto front")
        ax.set_xlabel(label)
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel("max-norm error at t_end")
    axes[0].set_title(f"{scene}: error against CPU time (dashed: adaptive; x: failed)", fontsize=9)
    axes[1].set_title(f"{scene}: error against evaluations", fontsize=9)
    legend(axes[1], ncol=2, loc="upper right")
    finish(fig, directory, f"work_precision_{scene}")


def advice(directory, scene, styles):
    """stepwise advise's sweep: error against CPU time per method, the target error, the advised point"""
    rows = [r for r in read(directory, "advice_sweep") if r["scene"] == scene]
    advised = next(r for r in read(directory, "advice_summary") if r["scene"] == scene)
    fig, ax = plt.subplots(figsize=(9, 6))
    top = max([r["error"] for r in rows if ok(r)] + [1.0]) * 10
    for method, points in by_method(rows).items():
        style = styles(method)
        good = sorted((r for r in points if ok(r) and r["error"] > 0 and r["cpu_seconds"] > 0), key=lambda r: r["cpu_seconds"])
        if good:
            ax.loglog([r["cpu_seconds"] for r in good], [r["error"] for r in good], linestyle="--" if good[0]["mode"] == "adaptive" else "-",
                      linewidth=1, markersize=3, label=method, **style)
        failed = [r for r in points if not ok(r) and r["cpu_seconds"] > 0]
        if failed:
            ax.loglog([r["cpu_seconds"] for r in failed], [top] * len(failed), color=style["color"], **FAILED_MARKER)
    ax.axhline(advised["target_error"], color="black", linewidth=1, linestyle=":", label="the error asked")
    if advised["method"] != "none":
        ax.loglog([advised["cpu_seconds"]], [advised["error"]], marker="*", markersize=16, color="gold", markeredgecolor="black",
                  linestyle="none", label=f"advised: {advised['method']}")
    ax.set_xlabel("CPU time (s)")
    ax.set_ylabel("max-norm error at t_end")
    ax.set_title(f"{scene}: the advice's sweep (dashed: adaptive; x: failed or diverged)", fontsize=9)
    ax.grid(True, which="major", alpha=0.3)
    legend(ax, ncol=2, loc="upper right")
    finish(fig, directory, f"advice_{scene}")


def energy(directory, _, styles):
    rows = read(directory, "energy")
    fig, ax = plt.subplots(figsize=(8, 5))
    for method, points in by_method(rows).items():
        style = dict(styles(method), marker=None)
        ax.semilogy([r["t"] for r in points], [max(abs(r["relative_energy_error"]), 1e-17) for r in points], label=method, linewidth=1, **style)
    single(fig, ax, directory, "energy", "t (s)", "|E - E0| / E0",
           "Relative energy error over the run, per method (the text above gives the scene and the step)", grid="major")


def bouncing_ball_curve(directory, _, styles):
    rows = read(directory, "bouncing_ball_curve")
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    n = [r["bounce"] for r in rows]
    axes[0].plot(n, [r["physical_flight_s"] for r in rows], marker="o", label="physical ball")
    axes[0].plot(n, [r["curve_flight_s"] for r in rows], marker="s", label="seeds' curve")
    axes[0].set_ylabel("flight time (s)")
    axes[1].semilogy(n, [r["physical_apex_m"] for r in rows], marker="o", label="physical ball")
    axes[1].semilogy(n, [r["curve_apex_m"] for r in rows], marker="s", linestyle="--", label="seeds' curve")
    axes[1].set_ylabel("apex height (m)")
    for ax in axes:
        ax.set_xlabel("bounce")
        ax.grid(True, alpha=0.3)
        legend(ax, ncol=1)
    axes[0].set_title("Flights: the curve's never shorten", fontsize=9)
    axes[1].set_title("Apexes: matched bounce for bounce", fontsize=9)
    finish(fig, directory, "bouncing_ball_curve")


def wave_stability(directory, _, styles):
    rows = read(directory, "wave_stability")
    grids = sorted({(r["c"], r["d"]) for r in rows})
    fig, axes = plt.subplots(1, len(grids), figsize=(6 * len(grids), 4.8), squeeze=False)
    for ax, (c, d) in zip(axes[0], grids):
        mine = [r for r in rows if (r["c"], r["d"]) == (c, d)]
        for method, points in by_method(mine).items():
            style = styles(method)
            mu = [r["mu"] for r in points]
            ax.plot(mu, [r["measured_dt"] for r in points], linestyle="none", label=f"{method}: measured", **style)
            ax.plot(mu, [r["derived_dt"] for r in points], color=style["color"], label=f"{method}: derived")
        seeds = sorted({(r["mu"], r["seeds_dt"]) for r in mine})
        ax.plot([m for m, _ in seeds], [s for _, s in seeds], color="black", linestyle="--", label="seeds' condition")
        ax.set_xscale("symlog", linthresh=0.5)
        ax.set_xlabel("damping mu (1/s)")
        ax.set_ylabel("largest stable dt (s)")
        ax.set_title(f"c = {c:g} m/s, d = {d:g} m", fontsize=9)
        ax.grid(True, alpha=0.3)
        legend(ax, ncol=1)
    finish(fig, directory, "wave_stability")



def fluid_viscosity(directory, _, styles):
    rows = read(directory, "fluid_viscosity")
    methods = list(dict.fromkeys(r["method"] for r in rows))
    fig, axes = plt.subplots(1, len(methods), figsize=(11, 4.5), sharey=True, squeeze=False)
    for ax, method in zip(axes[0], methods):
        points = [r for r in rows if r["method"] == method]
        for cfl in sorted(set(r["cfl"] for r in points)):
            line = sorted((r for r in points if r["cfl"] == cfl), key=lambda r: r["size"])
            ax.loglog([r["size"] for r in line], [r["nu_effective_over_nu"] - 1 for r in line], marker="o", label=f"CFL {cfl:g}")
        sizes = sorted(set(r["size"] for r in points))
        top = max(r["nu_effective_over_nu"] - 1 for r in points)
        ax.loglog(sizes, [top * sizes[0] / n for n in sizes], color="black", linestyle=":", label="first order (1/n)")
        ax.set_xticks(sizes, [str(int(n)) for n in sizes])
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("grid points per side n")
        ax.set_title(method, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        legend(ax, ncol=1)
    axes[0][0].set_ylabel("excess viscosity (nu_eff - nu) / nu")
    finish(fig, directory, "fluid_viscosity")


REGIONS = {
    "euler": lambda z: 1 + z,
    "rk4": lambda z: 1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24,
    "implicit-euler": lambda z: 1 / (1 - z),
}


def stability_regions(directory, _, styles):
    spectrum = read(directory, "stability_spectrum")
    limits = read(directory, "stability_limits")
    scenes = list(dict.fromkeys(r["scene"] for r in spectrum))
    fig, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 5.5), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        h = next(r["spectrum_dt"] for r in limits if r["scene"] == scene and r["method"] == "rk4")
        z = np.array([complex(r["re"], r["im"]) for r in spectrum if r["scene"] == scene]) * h
        reach = max(3.2, 1.15 * np.abs(z).max())
        x, y = np.meshgrid(np.linspace(-reach, 0.6 * reach, 600), np.linspace(-reach, reach, 600))
        for method, region in REGIONS.items():
            with np.errstate(divide="ignore"):
                magnitude = np.abs(region(x + 1j * y))
            ax.contour(x, y, magnitude, levels=[1], colors=[styles(method)["color"]], linewidths=1.5)
            ax.plot([], [], color=styles(method)["color"], label=f"|R(z)| = 1, {method}")
        ax.plot(z.real, z.imag, linestyle="none", marker=".", markersize=4, color="black", label="h lambda, h = rk4's predicted limit")
        ax.plot((1.5 * z).real, (1.5 * z).imag, linestyle="none", marker=".", markersize=3, color="grey", alpha=0.6, label="at 1.5 h")
        ax.axhline(0, color="grey", linewidth=0.5)
        ax.axvline(0, color="grey", linewidth=0.5)
        ax.set_aspect("equal")
        ax.set_xlabel("Re z")
        ax.set_ylabel("Im z")
        ax.set_title(f"{scene}: spectrum times h = {h:.3g} s", fontsize=9)
        legend(ax, ncol=1, loc="lower left")
    finish(fig, directory, "stability_regions")


def rigid_body_invariants(directory, _, styles):
    rows = read(directory, "rigid_body_invariants_series")
    runs = {}
    for r in rows:
        setting = f"dt {r['dt']:g}" if not math.isnan(r["dt"]) else f"rtol {r['rtol']:g}"
        runs.setdefault((r["method"], setting), []).append(r)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharex=True)
    seen = {}
    for (method, setting), points in runs.items():
        # a method's finer setting dashed
        line = "-" if seen.setdefault(method, setting) == setting else "--"
        style = dict(styles(method), marker=None)
        for ax, key in ((axes[0], "energy_error"), (axes[1], "momentum_error")):
            ax.semilogy([r["t"] for r in points], [max(r[key], 1e-17) for r in points], linestyle=line, linewidth=1,
                        label=f"{method}, {setting}", **style)
    axes[0].set_ylabel("|E / E0 - 1|")
    axes[1].set_ylabel("|L - L0| / |L0| (world frame)")
    axes[0].set_title("Energy: bounded for the splitting, drifting for rk4", fontsize=9)
    axes[1].set_title("Angular momentum: the splitting keeps it to round-off", fontsize=9)
    for ax in axes:
        ax.set_xlabel("t (s)")
        ax.grid(True, alpha=0.3)
    legend(axes[1], ncol=2, loc="lower right")
    finish(fig, directory, "rigid_body_invariants")


def event_times(directory, _, styles):
    rows = [r for r in read(directory, "event_times") if r["status"] == "ok"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    fixed = [r for r in rows if isinstance(r["dt"], float)]
    adaptive = [r for r in rows if isinstance(r["rtol"], float)]
    for ax, points, key, label in ((axes[0], fixed, "dt", "step dt (s)"), (axes[1], adaptive, "rtol", "relative tolerance")):
        for (method, location), mine in sorted({(r["method"], r["location"]): None for r in points}.items()):
            mine = sorted((r for r in points if (r["method"], r["location"]) == (method, location)), key=lambda r: r[key])
            style = styles(method)
            ax.loglog([r[key] for r in mine], [max(r["max_time_error_s"], 1e-17) for r in mine], linestyle="--" if location == "restep" else "-",
                      linewidth=1, markersize=4, label=f"{method} ({location})", **style)
        ax.set_xlabel(label)
        ax.grid(True, alpha=0.3)
        legend(ax, ncol=1, loc="lower right")
    axes[0].set_ylabel("largest impact-time error (s)")
    axes[0].set_title("Fixed steps: the impact on the step's segment (solid) or re-stepped to the root (dashed)", fontsize=9)
    axes[1].set_title("Adaptive: CVODE's root finding, GSL re-stepped", fontsize=9)
    finish(fig, directory, "event_times")


def contacts(directory, _, styles):
    rows = [r for r in read(directory, "contacts") if r["status"] == "ok"]
    dt = [r["dt"] for r in rows]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    axes[0].loglog(dt, [r["tumble_sink"] for r in rows], marker="o", label="tumbling box: final depth below its resting height (m)")
    axes[0].loglog(dt, [max(r["slope_creep"], 1e-20) for r in rows], marker="s", label="box at rest on a slope: creep (m)")
    axes[0].loglog(dt, [max(r["slide_error"], 1e-20) for r in rows], marker="^", label="box sliding: speed against Coulomb's, relative")
    axes[0].set_ylabel("error")
    axes[0].set_title("Resting and sliding contact against the step (an exact 0 drawn at 1e-20)", fontsize=9)
    axes[1].semilogx(dt, [r["collapse_energy_kept"] for r in rows], marker="o", color="C3", label="energy kept")
    axes[1].set_ylabel("collapse: fraction of the energy kept", color="C3")
    twin = axes[1].twinx()
    twin.semilogx(dt, [r["collapse_impacts"] for r in rows], marker="s", color="C0", linestyle="--", label="impacts")
    twin.set_ylabel("collapse: impacts", color="C0")
    axes[1].set_title("The wall's collapse: chaotic, so it changes with the step", fontsize=9)
    for ax in axes:
        ax.set_xlabel("step dt (s)")
        ax.grid(True, alpha=0.3)
    legend(axes[0], ncol=1, loc="center left")
    finish(fig, directory, "contacts")


# ---- the page


# a table longer than this shows its first rows and a button for the rest
LONG_TABLE_ROWS = 12


def collapse_long_tables(body):
    """each table of more than LONG_TABLE_ROWS body rows: its first rows shown, the rest one click away"""
    def wrap(m):
        table = m.group(0)
        rows = table.count("<tr>") - 1  # the header's row
        if rows <= LONG_TABLE_ROWS:
            return table
        return (f'<div class="long-table collapsed">{table}<button type="button" onclick="this.parentElement.classList.toggle(\'collapsed\')">'
                f'<span class="more">show all {rows} rows</span><span class="less">show the first {LONG_TABLE_ROWS}</span></button></div>')
    return re.sub(r"<table>.*?</table>", wrap, body, flags=re.S)


def html(directory):
    """report.md as index.html: a table of contents at hand beside the text (every section and subsection), the
    long tables folded to their first rows"""
    try:
        import markdown
    except ImportError:
        print("plot.py: markdown is missing: install Debian's python3-markdown (apt-get install python3-markdown)", file=sys.stderr)
        sys.exit(3)
    with open(os.path.join(directory, "report.md")) as f:
        converter = markdown.Markdown(extensions=["tables", "toc"], extension_configs={"toc": {"toc_depth": "2-3"}})
        body = collapse_long_tables(converter.convert(f.read()))
    # the figures to explore in place of their PNGs (report/interactive.py), each captioned with a link to its PNG
    import interactive
    twins = interactive.figures(directory)

    def explore(m):
        alt, stem = m.group(1), m.group(2)
        if stem not in twins:
            return m.group(0)
        html_of, hint = twins[stem]
        return f'<figure class="interactive">{html_of}<figcaption>{alt}: {hint} (<a href="{stem}.png">the static figure</a>)</figcaption></figure>'
    body = re.sub(r'<p><img alt="([^"]*)" src="([\w.\-]+)\.png" /></p>', explore, body)
    script = ('<script src="plotly.js" charset="utf-8" defer></script>' + interactive.LOADER) if twins else ""
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>stepwise report</title>
<style>
body {{ font-family: sans-serif; margin: 0; line-height: 1.45; }}
nav {{ position: fixed; top: 0; left: 0; bottom: 0; width: 270px; overflow-y: auto; padding: 1em; box-sizing: border-box;
       background: #f7f7f7; border-right: 1px solid #ddd; font-size: 0.82em; }}
nav ul {{ padding-left: 1.1em; margin: 0.2em 0; }}
nav a {{ text-decoration: none; }}
main {{ margin-left: 290px; max-width: 1250px; padding: 0 1em 2em; }}
@media (max-width: 900px) {{ nav {{ position: static; width: auto; border-right: none; }} main {{ margin-left: 0; }} }}
table {{ border-collapse: collapse; margin: 1em 0 0.3em; font-size: 0.85em; }}
th, td {{ border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; }}
th {{ background: #f0f0f0; }}
td:first-child, th:first-child {{ text-align: left; }}
.long-table {{ margin-bottom: 1em; }}
.long-table.collapsed tbody tr:nth-child(n+{LONG_TABLE_ROWS + 1}) {{ display: none; }}
.long-table .less, .long-table.collapsed .more {{ display: inline; }}
.long-table .more, .long-table.collapsed .less {{ display: none; }}
img {{ max-width: 100%; }}
code {{ background: #f4f4f4; }}
figure.interactive {{ margin: 1em 0; }}
figcaption {{ font-size: 0.85em; color: #555; }}
</style>{script}</head><body>
<nav aria-label="contents"><strong><a href="#in-short">stepwise report</a></strong>
{converter.toc}</nav>
<main>
{body}
</main>
</body></html>
"""
    path = os.path.join(directory, "index.html")
    with open(path + ".tmp", "w") as f:
        f.write(page)
    os.replace(path + ".tmp", path)


def declared(directory, stem, styles):
    """a declared figure (figures.json's spec): its panels and lines as figure_spec reads them, a method's line in
    its own colour and marker, measurements as markers alone, the reference lines dotted"""
    spec = figure_spec.specs(directory)[stem]
    panels = figure_spec.panels(directory, spec)
    fig, axes = plt.subplots(1, len(panels), figsize=(8 if len(panels) == 1 else 6 * len(panels), 5), squeeze=False)
    for ax, (facet, lines) in zip(axes[0], panels):
        for i, line in enumerate(lines):
            style = styles(line.series) if spec["series"] == "method" else dict(color=f"C{i}", marker="os^vD"[i % 5])
            ax.plot(line.x, line.y, label=line.name, markersize=4, linewidth=1, **style, **({"linestyle": "none"} if line.points_only else {}))
        for i, ref in enumerate(spec["lines"]):
            (ax.axvline if ref["axis"] == "x" else ax.axhline)(ref["value"], color=("black", "grey")[i % 2], linestyle=(":", "--")[i % 2],
                                                                 linewidth=0.8, label=ref["label"])
        ax.set_xscale("log" if spec["log_x"] else "linear")
        ax.set_yscale("log" if spec["log_y"] else "linear")
        ax.set_xlabel(spec["x_label"])
        ax.set_ylabel(spec["y_label"])
        ax.set_title(f"{spec['title']}{', ' + spec['facet'] + ' ' + facet if facet else ''}", fontsize=9)
        ax.grid(True, which="both" if spec["log_x"] or spec["log_y"] else "major", alpha=0.3)
        legend(ax, ncol=1 if len(ax.get_legend_handles_labels()[0]) < 8 else 2)
    finish(fig, directory, stem)


DRAWERS = {f.__name__: f for f in (convergence, work_precision, advice, energy, bouncing_ball_curve, wave_stability, fluid_viscosity, stability_regions, rigid_body_invariants, event_times, contacts, declared)}


def draw(directory, kind, subject, dpi, stem):
    """One figure (in a worker process: the resolution passed, not inherited); a declared one by its stem."""
    global DPI
    DPI = dpi
    DRAWERS[kind](directory, stem if kind == "declared" else subject, Styles(directory))


def die_with_parent(parent):
    """a worker's first act: ask for SIGTERM when its parent (this script) dies, as stepwise asks of this script
    (prctl PR_SET_PDEATHSIG = 1), so that a report killed outright leaves no worker writing into its staging
    directory; a parent already gone ends it at once"""
    ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)
    if os.getppid() != parent:
        os._exit(1)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    global DPI
    directory = sys.argv[1]
    if "--dpi" in sys.argv:
        DPI = int(sys.argv[sys.argv.index("--dpi") + 1])
    jobs = int(sys.argv[sys.argv.index("--jobs") + 1]) if "--jobs" in sys.argv else 1
    figures = [(directory, f["kind"], f["subject"], DPI, f["stem"]) for f in read(directory, "figures")]
    for _, kind, _, _, _ in figures:
        if kind not in DRAWERS:
            sys.exit(f"plot.py: figures.csv: no drawing for kind '{kind}'")
    if jobs > 1 and len(figures) > 1:
        # the figures are independent (each reads CSVs and writes its own PNG): drawn by forked workers, one
        # figure at a time each; a worker's exception is raised here
        with multiprocessing.get_context("fork").Pool(min(jobs, len(figures)), die_with_parent, (os.getpid(),)) as pool:
            pool.starmap(draw, figures, chunksize=1)
    else:
        for figure in figures:
            draw(*figure)
    if "--html" in sys.argv[2:]:
        html(directory)


if __name__ == "__main__":
    main()
