"""The report's figures to explore in index.html: plotly.js figures of the same CSVs the PNGs are drawn from.

Each method is a trace in its group's colour (the method table's `group`: whose code steps, ARKODE by kind;
Okabe and Ito's colour-blind-safe palette) with a marker of its own; the legend gathers the groups, a method's
entry hides or shows that method, and a button per group above the plot shows or hides the whole group (the
legend's group titles are not clickable in the plotly.js Debian ships, 2.6.3). Hover shows method, setting,
error and CPU time (or steps and calls). Log axes. By default a diagram shows its Pareto front and each group's
best method; the others are one click away in the legend. plotly.js comes from Debian's python3-plotly, copied
once into the report's folder (no network when the page is viewed); the figures are built with plotly's
Python API (plotly.graph_objects), not by hand.

The declared figures (figures.json: report/studies.hpp's FigureSpec) are drawn here from the same spec and data
(report/figure_spec.py) as plot.py draws their PNGs.

Used by plot.py's html(); figures(directory) returns {png stem: (HTML of its interactive twin, how to use it)}."""
import csv
import math
import os
import shutil

import figure_spec

PLOTLY_JS = "/usr/share/python3-plotly/plotly.js"
# Okabe & Ito (2008): eight colours told apart under the common colour-vision deficiencies
PALETTE = ["#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442", "#000000"]
MARKERS = ["circle", "square", "diamond", "triangle-up", "triangle-down", "cross", "x", "star", "hexagon", "pentagon",
           "triangle-left", "triangle-right", "hourglass", "bowtie", "circle-open", "square-open", "diamond-open", "star-open"]


def available():
    try:
        import plotly  # noqa: F401
    except ImportError:
        return False
    return os.path.exists(PLOTLY_JS)


def rows(directory, stem):
    path = os.path.join(directory, stem + ".csv")
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


number = figure_spec.number  # a CSV cell as a float, nan where it is none


class Groups:
    """each method's group, colour and marker, fixed by the method table's order"""

    def __init__(self, directory):
        table = rows(directory, "methods")
        self.group = {r["name"]: r.get("group") or r["source"] for r in table}
        order = []
        for r in table:
            if self.group[r["name"]] not in order:
                order.append(self.group[r["name"]])
        self.order = order
        self.colour = {g: PALETTE[i % len(PALETTE)] for i, g in enumerate(order)}
        self.marker = {}
        for g in order:
            for k, name in enumerate(n for n in self.group if self.group[n] == g):
                self.marker[name] = MARKERS[k % len(MARKERS)]

    def of(self, method):
        return self.group.get(method, "other")


def pareto(points):
    """the points no other is both cheaper and more accurate than: (cost, error, ...) sorted by cost"""
    front, best = [], math.inf
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def diagram(groups, curves, front, x_title, y_title, title, hover_x, hover_y):
    """curves: {method: [(x, y, setting, extra)]}, front: [(x, y, method, setting)] or None; a method shown at first
    where it is on the front or is its group's best (the least y reached)"""
    import plotly.graph_objects as go
    on_front = {p[2] for p in front} if front else set()
    best_of_group = {}
    for method, pts in curves.items():
        least = min((p[1] for p in pts), default=math.inf)
        g = groups.of(method)
        if g not in best_of_group or least < best_of_group[g][1]:
            best_of_group[g] = (method, least)
    shown = on_front | {m for m, _ in best_of_group.values()}
    fig = go.Figure()
    if front:
        fig.add_trace(go.Scatter(x=[p[0] for p in front], y=[p[1] for p in front], mode="lines", name="Pareto front",
                                 line=dict(color="#888888", width=6), opacity=0.35, legendgroup="front", legendgrouptitle_text="front",
                                 hoverinfo="skip"))
    for g in groups.order + ["other"]:
        for method in [m for m in curves if groups.of(m) == g]:
            pts = sorted(curves[method])
            fig.add_trace(go.Scatter(
                x=[p[0] for p in pts], y=[p[1] for p in pts], mode="lines+markers", name=method,
                legendgroup=g, legendgrouptitle_text=g, visible=True if method in shown else "legendonly",
                line=dict(color=groups.colour.get(g, "#999999"), width=1.5),
                marker=dict(symbol=groups.marker.get(method, "circle"), size=8, color=groups.colour.get(g, "#999999")),
                customdata=[[p[2], p[3]] for p in pts],
                hovertemplate=f"<b>{method}</b><br>%{{customdata[0]}}<br>{hover_y} %{{y:.3e}}<br>{hover_x} %{{x:.3e}}%{{customdata[1]}}<extra>{g}</extra>"))
    # a button per group: its first click shows the whole group, the next hides it (plotly's toggle buttons: args, then
    # args2); the legend's entries show or hide one method each
    indices = {}
    for i, trace in enumerate(fig.data):
        if trace.legendgroup != "front":
            indices.setdefault(trace.legendgroup, []).append(i)
    buttons = [dict(label=f"{g} ({len(ix)})", method="restyle", args=[{"visible": True}, ix], args2=[{"visible": "legendonly"}, ix])
               for g, ix in indices.items()]
    fig.update_layout(updatemenus=[dict(type="buttons", direction="right", buttons=buttons, showactive=False, x=0, xanchor="left", y=1.0,
                                        yanchor="bottom", pad=dict(t=2, b=2), font=dict(size=10))])
    fig.update_xaxes(type="log", title=x_title, exponentformat="power")
    fig.update_yaxes(type="log", title=y_title, exponentformat="power")
    fig.update_layout(title=dict(text=title, y=0.99), height=620, template="plotly_white", legend=dict(groupclick="toggleitem", font=dict(size=11)),
                      margin=dict(l=70, r=20, t=80, b=60))
    return fig


def per_scene(directory, groups, table, x_column, point, front, x_title, title):
    """one diagram per scene of `table`'s ok rows: x = the row's `x_column`, y = its error; point(row) gives the
    hover's setting and extra line; `front`: with the Pareto front"""
    out = {}
    data = rows(directory, table)
    for scene in dict.fromkeys(r["scene"] for r in data):
        curves = {}
        for r in data:
            x, error = number(r[x_column]), number(r["error"])
            if r["scene"] == scene and r["status"] == "ok" and error > 0 and x > 0 and math.isfinite(error):
                curves.setdefault(r["method"], []).append((x, error, *point(r)))
        line = pareto([(x, y, m, s) for m, pts in curves.items() for x, y, s, _ in pts]) if front else None
        out[f"{table}_{scene}"] = diagram(groups, curves, line, x_title, "error at t_end", f"{title}, {scene}", x_title, "error")
    return out


def work_precision(directory, groups):
    def point(r):
        setting = f"dt {number(r['dt']):.3g}" if r["mode"] == "fixed" else f"rtol {number(r['rtol']):.1e}"
        return setting, f"<br>calls of f {int(number(r['rhs_evals']))}"
    return per_scene(directory, groups, "work_precision", "cpu_seconds", point, True, "CPU time (s)", "Work against precision")


def convergence(directory, groups):
    def point(r):
        return f"dt {number(r['dt']):.3g}", f"<br>steps {int(number(r['steps']))}"
    return per_scene(directory, groups, "convergence", "dt", point, False, "dt (s)", "Convergence")


def declared(directory, groups, spec):
    """a declared figure (figures.json's spec) as figure_spec reads it, the twin of plot.py's declared(): a method's
    line in its group's colour and its own marker, measurements as markers alone, the reference lines dotted;
    a panel per facet side by side"""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots
    panels = figure_spec.panels(directory, spec)
    fig = make_subplots(rows=1, cols=len(panels), subplot_titles=[f"{spec['facet']} {f}" if f else "" for f, _ in panels])
    for col, (facet, lines) in enumerate(panels, start=1):
        for i, line in enumerate(lines):
            colour = groups.colour.get(groups.of(line.series), PALETTE[i % len(PALETTE)]) if spec["series"] == "method" else PALETTE[i % len(PALETTE)]
            fig.add_trace(go.Scatter(
                x=line.x, y=line.y, mode="markers" if line.points_only else "lines+markers", name=line.name, legendgroup=line.name,
                showlegend=col == 1, line=dict(color=colour, width=1.5),
                marker=dict(symbol=groups.marker.get(line.series, MARKERS[i % len(MARKERS)]), size=8, color=colour),
                hovertemplate=f"<b>{line.name}</b><br>{spec['y_label']} %{{y:.3g}}<br>{spec['x_label']} %{{x:.3g}}<extra></extra>"),
                row=1, col=col)
        for k, ref in enumerate(spec["lines"]):
            dash = ("dot", "dash")[k % 2]
            if ref["axis"] == "x":
                fig.add_vline(x=ref["value"], line=dict(color="#444444", dash=dash, width=1), annotation_text=ref["label"], row=1, col=col)
            else:
                fig.add_hline(y=ref["value"], line=dict(color="#444444", dash=dash, width=1), annotation_text=ref["label"], row=1, col=col)
    fig.update_xaxes(type="log" if spec["log_x"] else "linear", title=spec["x_label"], exponentformat="power")
    fig.update_yaxes(type="log" if spec["log_y"] else "linear", title=spec["y_label"], exponentformat="power")
    fig.update_layout(title=dict(text=spec["title"], y=0.99), height=520, template="plotly_white", legend=dict(font=dict(size=11)),
                      margin=dict(l=70, r=20, t=80, b=60))
    return fig


# draws each figure when it comes near the window (the page is usable at once; a dozen figures of forty traces
# drawn at load would hold it for seconds): plotly.js's newPlot on the figure's JSON
LOADER = """<script>
document.addEventListener('DOMContentLoaded', () => {
  const draw = div => {
    const spec = JSON.parse(document.getElementById('data-' + div.id).textContent);
    Plotly.newPlot(div, spec.data, spec.layout, {displaylogo: false, responsive: true});
  };
  const near = new IntersectionObserver(entries => entries.forEach(e => {
    if (e.isIntersecting) { near.unobserve(e.target); draw(e.target); }
  }), {rootMargin: '600px'});
  document.querySelectorAll('div.lazy-plot').forEach(div => near.observe(div));
});
</script>"""


def figures(directory):
    """{png stem: (HTML of the interactive figure (its div and its JSON), how to use it)}; plotly.js copied into the directory once.
    Empty where python3-plotly is not installed (the page then shows the PNGs alone)"""
    if not available():
        return {}
    shutil.copyfile(PLOTLY_JS, os.path.join(directory, "plotly.js"))
    groups = Groups(directory)
    diagrams = {**work_precision(directory, groups), **convergence(directory, groups)}
    declared_figures = {stem: declared(directory, groups, spec) for stem, spec in figure_spec.specs(directory).items()}
    def embedded(stem, fig):
        spec = fig.to_json().replace("</", "<\\/")  # no text in the JSON can close its script element
        return (f'<div id="figure-{stem}" class="lazy-plot" style="height: {fig.layout.height}px"></div>'
                f'<script type="application/json" id="data-figure-{stem}">{spec}</script>')
    hint = ("hover for a point's method, setting, error and cost; click a legend entry to hide or show a method, a group's button above "
            "the plot for the whole group")
    return {**{stem: (embedded(stem, fig), hint) for stem, fig in diagrams.items()},
            **{stem: (embedded(stem, fig), "hover for a point's values; click a legend entry to hide or show its line")
               for stem, fig in declared_figures.items()}}
