"""The report's figures to explore in index.html: each drawn with plotly.js from its spec (figures.json:
report/studies.hpp's FigureSpec) and the same CSVs, read by report/figure_spec.py as plot.py reads them for the PNGs.

A method is a trace in its own colour and marker, a shade of its group's (the method table's `group`: whose code
steps, ARKODE by kind), as report/figure_spec.py resolves it for both drawers; the legend lists the methods group by group, the first
of each under its group's title (the titles are not clickable in the plotly.js Debian ships, 2.6.3), a method's
entry hides or shows it in every panel, and a button per group above the plot shows or hides the whole group.
Hover shows the line, its x and y and the values its spec names (setting, calls, CPU time). Log axes where the
spec says. A diagram of many methods shows at first each group's best method and those on the Pareto front the
study found (a layer of its spec); the others are one click away. plotly.js comes from Debian's python3-plotly, copied once into
the report's folder (no network when the page is viewed); the figures are built with plotly's Python API
(plotly.graph_objects), not by hand.

Used by plot.py: twin() for each figure in the worker that draws its PNG, copy_plotly() once for the page."""
import os
import shutil

from figure_spec import Mark, Methods


PLOTLY_JS = "/usr/share/python3-plotly/plotly.js"
PX_PER_POINT = 1.5  # the styles' sizes, in points, as plotly's pixels (a page's figure is drawn larger than a PNG's)
DASH = {"solid": None, "dash": "dash", "dot": "dot"}


def available():
    try:
        import plotly  # noqa: F401
    except ImportError:
        return False
    return os.path.exists(PLOTLY_JS)


def scatter_style(style):
    """a figure_spec.Style as plotly Scatter's mode, line, marker and opacity (its marker names are plotly's own)"""
    mode = "+".join(part for part, drawn in (("lines", style.dash), ("markers", style.marker)) if drawn) or "lines"
    marker = dict(symbol=style.marker or "circle", size=style.size * PX_PER_POINT, color=style.colour)
    if style.edge:
        marker["line"] = dict(color=style.edge, width=1)
    return dict(mode=mode, line=dict(color=style.colour, width=style.width * PX_PER_POINT, dash=DASH[style.dash or "solid"]),
                marker=marker, opacity=style.opacity)


def figure(groups, spec, panels):
    """a figure's panels (its spec as figure_spec reads it), the twin of plot.py's draw_figure: a panel each side
    by side, each line, failed run and contour as its resolved Style says; a method's traces share one legend entry
    across panels and layers (a click hides or shows the method everywhere), the first of each group titled with
    the group. Where more than 12 methods are drawn, only each group's best (the least y) and the methods
    with a point on a front are shown at first; a button per group shows or hides the whole group"""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots
    fig = make_subplots(rows=1, cols=len(panels), subplot_titles=[p.title for p in panels] if len(panels) > 1 else None)
    fig.update_annotations(font_size=12)  # the panels' titles, side by side
    methods = {line.name: line.key for p in panels for line in p.lines if line.method and line.mark != Mark.STAR}
    # at first: every line, or (many methods) each group's best and the methods with a point on a front
    shown = set(methods)
    if len(methods) > 12:
        best = {}
        for p in panels:
            for line in (line for line in p.lines if line.name in methods):
                g, least = groups.of(line.key), min(line.y)
                if g not in best or least < best[g][1]:
                    best[g] = (line.name, least)
        shown = {name for name, _ in best.values()}
        for p in panels:
            on_front = {(x, y) for line in p.lines if line.mark == Mark.FRONT for x, y in zip(line.x, line.y)}
            shown |= {line.name for line in p.lines if line.name in methods and on_front.intersection(zip(line.x, line.y))}
    legend_seen, titled = set(), set()

    def legend_of(name, key, method):
        first = name not in legend_seen
        legend_seen.add(name)
        group = groups.of(key) if method else ""
        title = group if method and first and group not in titled else None
        if title:
            titled.add(group)
        return dict(name=name, legendgroup=name, showlegend=first, legendgrouptitle_text=title,
                    visible=True if name not in methods or name in shown else "legendonly")
    for col, p in enumerate(panels, start=1):
        for c in p.contours:
            hue = c.style.colour
            fig.add_trace(go.Contour(x=c.x, y=c.y, z=c.z, contours=dict(start=1, end=1, size=1, coloring="lines"), showscale=False,
                                     colorscale=[[0, hue], [1, hue]], line=dict(width=c.style.width * PX_PER_POINT), hoverinfo="skip", name=c.name, legendgroup=c.name),
                          row=1, col=col)
            # a contour has no legend entry of its own: a line without points stands for it
            fig.add_trace(go.Scatter(x=[None], y=[None], mode="lines", line=dict(color=hue, width=c.style.width * PX_PER_POINT), name=c.name, legendgroup=c.name,
                                     showlegend=col == 1), row=1, col=col)
        # a method's traces group by group (the legend lists them in this order, each group under its title)
        rank = {g: i for i, g in enumerate(groups.order)}
        for line in sorted(p.lines, key=lambda line: rank.get(groups.of(line.key), len(rank)) if line.method else -1):
            extra = ["<br>" + "<br>".join(h) if h else "" for h in line.hover] if line.hover else None
            fig.add_trace(go.Scatter(
                x=line.x, y=line.y, **scatter_style(line.style), customdata=extra,
                hovertemplate=f"<b>{line.name}</b><br>{p.y_label} %{{y:.3g}}<br>{p.x_label} %{{x:.3g}}{'%{customdata}' if extra else ''}"
                              f"<extra>{groups.of(line.key) if line.method else ''}</extra>",
                **legend_of(line.name, line.key, line.method)), row=1, col=col)
        for f in p.failed:
            fig.add_trace(go.Scatter(x=f.x, y=[p.failed_y] * len(f.x), **scatter_style(f.style),
                                         hovertemplate=f"<b>{f.name}</b>: failed or diverged<br>{p.x_label} %{{x:.3g}}<extra></extra>",
                                         **{**legend_of(f.name, f.key, f.method), "showlegend": False}), row=1, col=col)
        for ref in p.references:
            line = scatter_style(ref["style"])["line"]
            add = fig.add_vline if ref["axis"] == "x" else fig.add_hline
            add(**{ref["axis"]: ref["value"]}, line=line, row=1, col=col, **({"annotation_text": ref["label"]} if ref["label"] else {}))
        fig.update_xaxes(type="log" if p.log_x else "linear", title=p.x_label, exponentformat="power", row=1, col=col)
        fig.update_yaxes(type="log" if p.log_y else "linear", title=p.y_label, exponentformat="power", row=1, col=col)
        if p.equal_aspect:
            fig.update_yaxes(scaleanchor=f"x{col if col > 1 else ''}", scaleratio=1, row=1, col=col)
    # a button per group of methods: its first click shows the whole group, the next hides it (plotly's toggle
    # buttons: args, then args2)
    indices = {}
    for i, trace in enumerate(fig.data):
        if trace.name in methods:
            indices.setdefault(groups.of(methods[trace.name]), []).append(i)
    if len(indices) > 1:
        buttons = [dict(label=f"{g} ({len({fig.data[i].name for i in ix})})", method="restyle", args=[{"visible": True}, ix],
                        args2=[{"visible": "legendonly"}, ix]) for g, ix in indices.items()]
        fig.update_layout(updatemenus=[dict(type="buttons", direction="right", buttons=buttons, showactive=False, x=0, xanchor="left", y=1.09,
                                            yanchor="bottom", pad=dict(t=2, b=2), font=dict(size=10))])
    fig.update_layout(title=dict(text=spec["title"] if len(panels) > 1 else panels[0].title, y=0.99), height=620 if len(methods) > 12 else 520,
                      template="plotly_white", legend=dict(groupclick="togglegroup", font=dict(size=11)), margin=dict(l=70, r=20, t=120 if len(indices) > 1 else 80, b=60))
    return fig, bool(methods)


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


def twin(directory, stem, spec, panels):
    """(HTML of the figure to explore (its div and its JSON), how to use it), or None where python3-plotly is not
    installed (the page then shows the PNG alone); one figure, from the panels plot.py read for its PNG, so that
    plot.py's workers build them side by side"""
    if not available():
        return None
    fig, methods = figure(Methods(directory), spec, panels)
    spec = fig.to_json().replace("</", "<\\/")  # no text in the JSON can close its script element
    hint = ("hover for a point's method, setting, error and cost; click a legend entry to hide or show a method, a group's button above "
            "the plot for the whole group") if methods else "hover for a point's values; click a legend entry to hide or show its line"
    return (f'<div id="figure-{stem}" class="lazy-plot" style="height: {fig.layout.height}px"></div>'
            f'<script type="application/json" id="data-figure-{stem}">{spec}</script>'), hint


def copy_plotly(directory):
    """plotly.js into the report's folder, once, for the page to load without a network"""
    shutil.copyfile(PLOTLY_JS, os.path.join(directory, "plotly.js"))
