"""A figure's data, as its spec declares it (report/studies.hpp's FigureSpec, written into figures.json by stem):
its panels, each with its lines, contours, failed points and reference lines, read from the study's tables once
for both of its drawers, plot.py's PNG and interactive.py's plotly figure.

A row counts where its `status` (if the table has one) is ok, its layer's `where` and the panel's facet keep it,
its `complete` columns are finite numbers, and its x and y are finite (and positive on a log axis) after the
layer's transform and floor; a line's points are sorted by x, each (x, y) once. A layer with `failures` keeps its
rows whose status is not ok apart: their x, drawn as crosses at the panel's top."""
import csv
import json
import math
import os
from dataclasses import dataclass, field


@dataclass
class Line:
    name: str          # the legend's
    key: str           # what styles it: a method (coloured by its group, marked by itself), else its name
    method: bool       # its series is a method
    mark: str          # "line", "points", "line+points", "star", "front", "guide"
    dashed: bool
    x: list
    y: list
    hover: list = field(default_factory=list)  # a point's other values, as "heading value" lines


@dataclass
class Contour:
    name: str
    key: str           # what styles it: its z column (a method's name, the method's colour)
    x: list            # the grid's columns
    y: list            # and rows
    z: list            # z[row][column]; the contour drawn is its level 1


@dataclass
class Failed:
    name: str
    key: str
    method: bool
    x: list


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
    if layer["mark"] == "contour":
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
        dashed = "dashed" in layer["mark"] or (layer["split_dashed"] and series in seen_series)
        seen_series.add(series)
        name = name_of(values)
        ordered = sorted(points)
        lines.append(Line(name, style_key(values, name), method, layer["mark"].replace("dashed", "line"), dashed,
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
    return [Line(panel["guide_label"], panel["guide_label"], False, "guide", False, xs, [y0 * (x / x0) ** panel["guide_slope"] for x in xs])]


def panels(directory, spec):
    """[Panel] in the figure's order: its panels, once per facet value where it has a facet"""
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
            out.append(Panel(title, panel["x_label"], panel["y_label"], panel["log_x"], panel["log_y"], panel["symlog_x"], panel["equal_aspect"],
                             lines + guide(panel, lines), contours, failed, panel["lines"]))
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
