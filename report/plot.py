#!/usr/bin/python3
"""Draw the report's figures from the CSV files a stepwise study or report wrote, and turn report.md into index.html.

    plot.py DIR [--html] [--dpi N] [--jobs N]

DIR/figures.csv lists the figures (stem, kind, subject) and DIR/figures.json declares each (report/studies.hpp's
FigureSpec): every one is drawn by draw_figure below, from its spec and the CSVs in DIR only (report/figure_spec.py
reads them), into DIR/stem.png, by N processes at once (--jobs; default 1). DIR/methods.csv (the method table)
fixes one colour and marker per method, the same in every figure and its twin (report/figure_spec.py resolves
every line's style; this script and interactive.py only translate it). With --html, DIR/report.md becomes
DIR/index.html (Python-Markdown, tables), each figure to explore in place of its PNG (report/interactive.py draws
it from the same spec: plotly.js from Debian's python3-plotly).
Needs Debian's python3-matplotlib (and python3-markdown for --html); exit status 3 names a missing one.
"""
import csv
import ctypes
import multiprocessing
import os
import re
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # report/interactive.py and figure_spec.py beside it
import figure_spec  # noqa: E402
import interactive  # noqa: E402

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as e:
    print(f"plot.py: {e.name} is missing: install Debian's python3-matplotlib (apt-get install python3-matplotlib)", file=sys.stderr)
    sys.exit(3)

DPI = 100  # 1200 x 550 pixels for a two-panel figure; --dpi changes it (the README's copies are drawn smaller)


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


def finish(fig, directory, stem):
    fig.tight_layout()
    path = os.path.join(directory, stem + ".png")
    fig.savefig(path + ".tmp.png", dpi=DPI)
    os.replace(path + ".tmp.png", path)
    plt.close(fig)


def legend(ax, **kw):
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=kw.pop("fontsize", 7), ncol=kw.pop("ncol", 2), **kw)


# ---- every figure, from its spec


# MARKERS' names (report/figure_spec.py) in matplotlib's words
MARKER = {"circle": "o", "square": "s", "diamond": "D", "triangle-up": "^", "triangle-down": "v", "triangle-left": "<", "triangle-right": ">",
          "pentagon": "p", "hexagon": "h", "cross": "P", "x": "X", "diamond-tall": "d", "star": "*"}
DASH = {"solid": "-", "dash": "--", "dot": ":"}


def plot_style(style):
    """a figure_spec.Style as matplotlib's plot() keywords"""
    kw = dict(color=style.colour, linewidth=style.width, alpha=style.opacity, linestyle=DASH[style.dash] if style.dash else "none")
    if style.marker:
        name, hollow = style.marker.removesuffix("-open"), style.marker.endswith("-open")
        kw.update(marker=MARKER[name], markersize=style.size)
        if hollow:
            kw["markerfacecolor"] = "none"
        if style.edge:
            kw["markeredgecolor"] = style.edge
    else:
        kw["marker"] = None
    if style.behind:
        kw["zorder"] = 0
    return kw


def draw_figure(directory, stem, panels):
    """a figure's panels (its spec as figure_spec reads and styles it) side by side: each line as its Style says,
    a failed run a cross at the panel's top, a contour at level 1, the reference lines grey"""
    many = max(len({line.name for line in p.lines}) for p in panels) > 12  # a legend this long goes beside the panel
    width = (5.2 if all(p.equal_aspect for p in panels) else 6) * len(panels) + (3 if many else 0)
    fig, axes = plt.subplots(1, len(panels), figsize=(8 if len(panels) == 1 and not many else width, 5.5 if many else 5), squeeze=False)
    same_legends = len({tuple(sorted({line.name for line in p.lines})) for p in panels}) == 1
    for k, (ax, panel) in enumerate(zip(axes[0], panels)):
        named = set()
        for c in panel.contours:
            ax.contour(c.x, c.y, c.z, levels=[1], colors=[c.style.colour], linewidths=c.style.width)
            ax.plot([], [], color=c.style.colour, label=c.name)
        for line in panel.lines:
            ax.plot(line.x, line.y, label=None if line.name in named else line.name, **plot_style(line.style))
            named.add(line.name)
        for f in panel.failed:
            ax.plot(f.x, [panel.failed_y] * len(f.x), **plot_style(f.style))
        for ref in panel.references:
            kw = plot_style(ref["style"])
            del kw["marker"]
            (ax.axvline if ref["axis"] == "x" else ax.axhline)(ref["value"], label=ref["label"] or None, **kw)
        if panel.symlog_x:
            least = min((x for line in panel.lines for x in line.x if x > 0), default=1.0)
            ax.set_xscale("symlog", linthresh=least)
        else:
            ax.set_xscale("log" if panel.log_x else "linear")
        ax.set_yscale("log" if panel.log_y else "linear")
        if panel.equal_aspect:
            ax.set_aspect("equal")
        ax.set_xlabel(panel.x_label)
        ax.set_ylabel(panel.y_label)
        ax.set_title(panel.title, fontsize=9)
        ax.grid(True, which="both" if panel.log_x or panel.log_y else "major", alpha=0.3)
        if same_legends and k + 1 < len(panels):
            continue  # the panels' legends alike: the last one's alone
        entries = len(ax.get_legend_handles_labels()[0])
        if many:
            legend(ax, ncol=2 if entries > 24 else 1, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=6)
        else:
            legend(ax, ncol=1 if entries < 8 else 2)
    finish(fig, directory, stem)


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


def html(directory, twins):
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
    # the figures to explore in place of their PNGs (`twins`: report/interactive.py's), each captioned with a link to its PNG
    if twins:
        interactive.copy_plotly(directory)

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


def draw(directory, stem, dpi, explore):
    """One figure (in a worker process: the resolution passed, not inherited), its data read once; with `explore`,
    its twin to explore in index.html (report/interactive.py's, or None without python3-plotly)."""
    global DPI
    DPI = dpi
    spec = figure_spec.specs(directory)[stem]
    panels = figure_spec.panels(directory, spec)
    draw_figure(directory, stem, panels)
    return interactive.twin(directory, stem, spec, panels) if explore else None


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
    specs = figure_spec.specs(directory)
    explore = "--html" in sys.argv[2:]
    figures = [(directory, f["stem"], DPI, explore) for f in read(directory, "figures")]
    for _, stem, _, _ in figures:
        if stem not in specs:
            sys.exit(f"plot.py: figures.csv: {stem} has no spec in figures.json")
        if problems := figure_spec.problems(directory, stem, specs[stem]):
            sys.exit(f"plot.py: figures.json: {problems[0]}")
    if explore and interactive.available():
        import plotly.graph_objects  # noqa: F401  (imported once, before the workers fork, rather than in each)
        import plotly.subplots  # noqa: F401
    if jobs > 1 and len(figures) > 1:
        # the figures are independent (each reads CSVs and writes its own PNG, and returns its twin to explore):
        # drawn by forked workers, one figure at a time each; a worker's exception is raised here
        with multiprocessing.get_context("fork").Pool(min(jobs, len(figures)), die_with_parent, (os.getpid(),)) as pool:
            twins = pool.starmap(draw, figures, chunksize=1)
    else:
        twins = [draw(*figure) for figure in figures]
    if explore:
        html(directory, {figure[1]: twin for figure, twin in zip(figures, twins) if twin})


if __name__ == "__main__":
    main()
