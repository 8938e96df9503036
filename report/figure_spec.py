"""A figure's data, as its spec declares it (report/studies.hpp's FigureSpec, written into figures.json by stem):
its panels, each with its lines, contours, failed points and reference lines, read from the study's tables once
for both of its drawers, plot.py's PNG and interactive.py's plotly figure.

A row counts where its `status` (if the table has one) is ok, its layer's `where` and the panel's facet keep it,
its `complete` columns are finite numbers, and its x and y are finite (and positive on a log axis) after the
layer's transform and floor; a line's points are sorted by x, each (x, y) once. A layer with `failures` keeps its
rows whose status is not ok apart: their x, drawn as crosses at the panel's top.

Each line's style (colour, marker, dash, width) is resolved here once, for the figure as a whole; the drawers only
translate a Style into matplotlib's or plotly's words. A method's colour is a shade of its group's (the method
table's `group`, in Okabe and Ito's colour-blind-safe palette) by its place in the group, and so is its marker,
the same in every figure and in both drawers."""
import colorsys
import csv
import enum
import json
import math
import os
from dataclasses import dataclass, field


class Mark(enum.Enum):
    """how a line is drawn, as figures.json names it (report/studies.hpp's FigureMark), and the slope guide"""
    LINE = "line"
    POINTS = "points"
    LINE_POINTS = "line+points"
    STAR = "star"          # a point marked out (the advised method)
    CONTOUR = "contour"    # z's level 1 over the grid of x and y
    FRONT = "front"        # a Pareto front: broad and pale, behind
    GUIDE = "guide"        # the panel's y ~ x^slope guide


@dataclass(frozen=True)
class Style:
    """a line's look, in the drawers' common terms: a colour "#rrggbb"; a marker by MARKERS' names (an "-open"
    suffix: its outline alone), None for none; a dash "solid", "dash" or "dot", None for points alone; sizes in
    points (1/72 inch)"""
    colour: str
    marker: str | None = None
    dash: str | None = "solid"
    width: float = 1.0
    size: float = 4.0
    opacity: float = 1.0
    edge: str | None = None   # the marker's outline colour, where it differs from the fill
    behind: bool = False      # drawn beneath the other lines


# Okabe & Ito (2008): eight colours told apart under the common colour-vision deficiencies
PALETTE = ["#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442", "#000000"]
# a line that is not a method's, beside methods' lines: black and greys (alone, such lines take PALETTE)
GREYS = ["#000000", "#808080", "#A9A9A9", "#696969"]
MARKERS = ["circle", "square", "diamond", "triangle-up", "triangle-down", "triangle-left", "triangle-right", "pentagon", "hexagon",
           "cross", "x", "diamond-tall"]
GUIDE_STYLE = Style("#000000", dash="dot")
STAR_STYLE = Style("#FFD700", marker="star", dash=None, size=12, edge="#000000")
FRONT_STYLE = Style("#AAAAAA", dash="solid", width=6, opacity=0.5, behind=True)


def reference_style(i, labelled):
    """a panel's i-th reference line: a labelled one dotted or dashed in turn, black or grey; another faint"""
    return Style(("#000000", "#808080")[i % 2], dash=("dot", "dash")[i % 2], width=0.8) if labelled else Style("#BBBBBB", width=0.5)


def shade(colour, place, count):
    """the place-th of `count` shades of a colour (the colour itself alone): lightness and hue moved by
    low-discrepancy sequences, so that neighbours in the method table, often drawn together, differ most"""
    if count <= 1:
        return colour
    r, g, b = (int(colour[i:i + 2], 16) / 255 for i in (1, 3, 5))
    hue, lightness, saturation = colorsys.rgb_to_hls(r, g, b)
    t, u = (place * 0.6180339887) % 1, (place * 0.7548776662) % 1
    # lightness over +-0.25 about the colour's, kept within [0.12, 0.78] so that every shade shows on white; hue +-0.05
    low, high = max(0.12, lightness - 0.25), min(0.78, lightness + 0.25)
    r, g, b = colorsys.hls_to_rgb((hue + 0.1 * (u - 0.5)) % 1, low + (high - low) * t, saturation)
    return "#{:02X}{:02X}{:02X}".format(*(round(255 * c) for c in (r, g, b)))


@dataclass
class Line:
    name: str          # the legend's
    key: str           # what styles it: a method (coloured by its group, marked by itself), else its name
    method: bool       # its series is a method
    mark: Mark
    dashed: bool
    x: list
    y: list
    hover: list = field(default_factory=list)  # a point's other values, as "heading value" lines
    style: Style = None  # resolved by panels()


@dataclass
class Contour:
    name: str
    key: str           # what styles it: its z column (a method's name, the method's colour)
    x: list            # the grid's columns
    y: list            # and rows
    z: list            # z[row][column]; the contour drawn is its level 1
    style: Style = None


@dataclass
class Failed:
    name: str
    key: str
    method: bool
    x: list
    style: Style = None


@dataclass
class Panel:
    title: str
    x_label: str
    y_label: str
    log_x: bool
    log_y: bool
    symlog_x: bool
    equal_aspect: bool
    lines: list
    contours: list
    failed: list
    references: list   # {"axis": "x" or "y", "value", "label"}
    failed_y: float = math.nan  # where the failed runs' crosses go: above the panel's highest point


class Methods:
    """each method's group, colour and marker, fixed by the method table's order (methods.csv): a group takes the
    next PALETTE colour, its k-th method the k-th of its shades and MARKERS' k-th marker (outlined past the list)"""

    def __init__(self, directory):
        path = os.path.join(directory, "methods.csv")
        table = list(csv.DictReader(open(path, newline=""))) if os.path.exists(path) else []
        self.group = {r["name"]: r.get("group") or r["source"] for r in table}
        self.order = list(dict.fromkeys(self.group.values()))
        self.colour, self.marker = {}, {}
        for i, g in enumerate(self.order):
            members = [n for n in self.group if self.group[n] == g]
            for k, name in enumerate(members):
                self.colour[name] = shade(PALETTE[i % len(PALETTE)], k, len(members))
                self.marker[name] = MARKERS[k % len(MARKERS)] + ("-open" if k // len(MARKERS) % 2 else "")

    def of(self, method):
        return self.group.get(method, "other")


class Styler:
    """one figure's styles: a method's from Methods, another line's a colour and marker of its own by name (the
    same in every panel): greys beside methods' lines, PALETTE alone"""

    def __init__(self, methods, panels):
        self.methods, self.others = methods, {}
        with_methods = any(line.method for p in panels for line in p.lines) or any(c.key in methods.colour for p in panels for c in p.contours)
        self.colours = GREYS if with_methods else PALETTE

    def colour(self, key, method):
        if method or key in self.methods.colour:
            return self.methods.colour.get(key, "#999999")
        return self.colours[self.others.setdefault(key, len(self.others)) % len(self.colours)]

    def marker(self, key, method):
        if method:
            return self.methods.marker.get(key, "circle")
        return MARKERS[self.others.setdefault(key, len(self.others)) % len(MARKERS)]

    def line(self, line):
        fixed = {Mark.GUIDE: GUIDE_STYLE, Mark.STAR: STAR_STYLE, Mark.FRONT: FRONT_STYLE}.get(line.mark)
        if fixed:
            return fixed
        colour, marker = self.colour(line.key, line.method), self.marker(line.key, line.method)
        dash = "dash" if line.dashed else "solid"
        if line.mark == Mark.LINE:
            return Style(colour, None, dash)
        if line.mark == Mark.POINTS:
            return Style(colour, marker, None, size=4 if line.method else 3)
        return Style(colour, marker, dash)

    def resolve(self, panels):
        for p in panels:
            for i, ref in enumerate(p.references):
                ref["style"] = reference_style(i, bool(ref["label"]))
            for c in p.contours:
                c.style = Style(self.colour(c.key, False), None, "solid", width=1.5)
            for line in p.lines:
                line.style = self.line(line)
            for f in p.failed:
                f.style = Style(self.colour(f.key, f.method), "x", None, size=7)


def specs(directory):
    """{stem: spec} of the report's figures"""
    path = os.path.join(directory, "figures.json")
    return json.load(open(path)) if os.path.exists(path) else {}


def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def shown(text):
    """a cell as a title or legend shows it: a number by :g, text as it is"""
    v = number(text)
    return f"{v:g}" if math.isfinite(v) else text


class Tables:
    """the study's CSVs, each read once"""

    def __init__(self, directory):
        self.directory, self.cache = directory, {}

    def __call__(self, stem):
        if stem not in self.cache:
            with open(os.path.join(self.directory, stem + ".csv"), newline="") as f:
                self.cache[stem] = list(csv.DictReader(f))
        return self.cache[stem]


TRANSFORMS = {"": lambda y: y, "abs": abs, "minus_one": lambda y: y - 1}


def kept(row, layer, facet):
    return (all(row.get(c) in values for c, values in layer["where"].items())
            and all(row[c] == v for c, v in facet.items() if c in row))


def layer_lines(rows, layer, panel):
    """the layer's lines (or contours) and failed points"""
    def usable(v, log):
        return math.isfinite(v) and (v > 0 or not log)
    ok = [r for r in rows if r.get("status", "ok") == "ok" and all(math.isfinite(number(r[c])) for c in layer["complete"])]
    failed = [r for r in rows if r.get("status", "ok") != "ok"] if layer["failures"] else []
    keys = [layer["series"]] + layer["split"] if layer["series"] else layer["split"]

    def key_of(r):
        return tuple(r[c] for c in keys)
    method = layer["series"] == "method"

    def name_of(values):
        series = values[0] if layer["series"] else ""
        if series in layer["names"]:
            return layer["names"][series]
        splits = dict(zip(layer["split"], map(shown, values[1:] if layer["series"] else values)))
        return layer["label"].replace("{}", "{_series}").format(_series=series, **splits)

    def style_key(values, name):
        return values[0] if method else name
    def grouped(rows):
        """{key: its rows}, in the order the keys first come"""
        out = {}
        for r in rows:
            out.setdefault(key_of(r), []).append(r)
        return out
    mark = Mark(layer["mark"])
    if mark == Mark.CONTOUR:
        out = []
        for values, mine in grouped(ok).items():
            xs = sorted({number(r[layer["x"]]) for r in mine})
            ys = sorted({number(r[layer["y"]]) for r in mine})
            at = {(number(r[layer["x"]]), number(r[layer["y"]])): number(r[layer["z"]]) for r in mine}
            name = name_of(values)
            out.append(Contour(name, layer["z"], xs, ys, [[at.get((x, y), math.nan) for x in xs] for y in ys]))
        return [], out, []
    transform, floor = TRANSFORMS[layer["y_of"]], layer["floor"]
    lines, seen_series = [], set()
    for values, mine in grouped(ok).items():
        points = {}
        for r in mine:
            x, y = number(r[layer["x"]]), transform(number(r[layer["y"]]))
            if floor > 0 and math.isfinite(y):
                y = max(y, floor)
            if usable(x, panel["log_x"]) and usable(y, panel["log_y"]):
                points.setdefault((x, y), [f"{heading} {shown(r[c])}" for c, heading in layer["hover"] if r.get(c, "") not in ("", "nan")])
        if not points:
            continue
        series = values[0] if layer["series"] else None
        dashed = layer["dashed"] or (layer["split_dashed"] and series in seen_series)
        seen_series.add(series)
        name = name_of(values)
        ordered = sorted(points)
        lines.append(Line(name, style_key(values, name), method, mark, dashed,
                          [p[0] for p in ordered], [p[1] for p in ordered], [points[p] for p in ordered]))
    fails = []
    for values, mine in grouped(failed).items():
        xs = [x for x in (number(r[layer["x"]]) for r in mine) if usable(x, panel["log_x"])]
        if xs:
            name = name_of(values)
            fails.append(Failed(name, style_key(values, name), method, xs))
    return lines, [], fails


def guide(panel, lines):
    """y ~ x^slope through the highest point at the panel's least x, over the panel's x values"""
    points = [(x, y) for line in lines for x, y in zip(line.x, line.y)]
    if not points or not panel["guide_slope"]:
        return []
    x0 = min(x for x, _ in points)
    y0 = max(y for x, y in points if x == x0)
    xs = sorted({x for x, _ in points})
    return [Line(panel["guide_label"], panel["guide_label"], False, Mark.GUIDE, False, xs, [y0 * (x / x0) ** panel["guide_slope"] for x in xs])]


def panels(directory, spec, methods=None):
    """[Panel] in the figure's order: its panels, once per facet value where it has a facet, each line's style
    resolved (by `methods`, else the directory's method table)"""
    tables = Tables(directory)
    facets = [{}]
    if spec["facet"]:
        first = spec["panels"][0]["layers"][0]
        rows = [r for r in tables(first["table"]) if kept(r, first, {})]
        facets = [dict(zip(spec["facet"], values)) for values in dict.fromkeys(tuple(r[c] for c in spec["facet"]) for r in rows)]
    out = []
    for facet in facets:
        for panel in spec["panels"]:
            lines, contours, failed = [], [], []
            for layer in panel["layers"]:
                more = layer_lines([r for r in tables(layer["table"]) if kept(r, layer, facet)], layer, panel)
                lines += more[0]
                contours += more[1]
                failed += more[2]
            title = (panel["title"] or spec["title"]).format(**{c: shown(v) for c, v in facet.items()})
            top = max([y for line in lines for y in line.y] + [1.0]) * (10 if panel["log_y"] else 1.1)
            out.append(Panel(title, panel["x_label"], panel["y_label"], panel["log_x"], panel["log_y"], panel["symlog_x"], panel["equal_aspect"],
                             lines + guide(panel, lines), contours, failed, panel["lines"], top if failed else math.nan))
    Styler(methods or Methods(directory), out).resolve(out)
    return out


def problems(directory, stem, spec):
    """what keeps the figure from being drawn as declared, a line each: a table it names missing, a column its
    table lacks (the tables' headers alone are read)"""
    out = []
    for panel in spec["panels"]:
        for layer in panel["layers"]:
            if not os.path.exists(os.path.join(directory, layer["table"] + ".csv")):
                out.append(f"{stem}: no table {layer['table']}.csv")
                continue
            with open(os.path.join(directory, layer["table"] + ".csv"), newline="") as f:
                header = next(csv.reader(f), [])
            named = [layer["x"], layer["y"], layer["z"], layer["series"], *layer["split"], *layer["where"], *layer["complete"],
                     *(c for c, _ in layer["hover"])]
            out += [f"{stem}: {layer['table']}.csv has no column '{c}'" for c in dict.fromkeys(named) if c and c not in header]
    if spec["facet"]:
        first = spec["panels"][0]["layers"][0]
        with open(os.path.join(directory, first["table"] + ".csv"), newline="") as f:
            header = next(csv.reader(f), [])
        out += [f"{stem}: facet column '{c}' is not in {first['table']}.csv" for c in spec["facet"] if c not in header]
    return out


def empty(stem, drawn):
    """a line for each of the figure's panels (as panels() reads them) with nothing to draw"""
    return [f"{stem}: panel '{p.title}' has nothing to draw" for p in drawn if not p.lines and not p.contours]
