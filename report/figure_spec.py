"""A declared figure's data (report/studies.hpp's FigureSpec, written into figures.json by stem): its panels and
lines, read from its table once for both of its drawers, plot.py's PNG and interactive.py's plotly figure.

A row counts where its `status` (if the table has one) is ok, the spec's `complete` columns are finite numbers,
and its x and y are finite (and positive on a log axis); a line's points are sorted by x."""
import csv
import json
import math
import os
from dataclasses import dataclass


@dataclass
class Line:
    name: str          # the legend's
    series: str        # the series column's value ("" without one): a method, coloured by its group
    points_only: bool
    x: list
    y: list


def specs(directory):
    """{stem: spec} of the report's declared figures"""
    path = os.path.join(directory, "figures.json")
    return json.load(open(path)) if os.path.exists(path) else {}


def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def panels(directory, spec):
    """[(facet value or "", [Line])] in the table's order"""
    with open(os.path.join(directory, spec["table"] + ".csv"), newline="") as f:
        rows = [r for r in csv.DictReader(f) if r.get("status", "ok") == "ok" and all(math.isfinite(number(r[c])) for c in spec["complete"])]
    def usable(v, log):
        return math.isfinite(v) and (v > 0 or not log)
    out = []
    for facet in dict.fromkeys(r[spec["facet"]] for r in rows) if spec["facet"] else [""]:
        mine = [r for r in rows if not spec["facet"] or r[spec["facet"]] == facet]
        lines = []
        for curve in spec["y"]:
            for series in dict.fromkeys(r[spec["series"]] for r in mine) if spec["series"] else [""]:
                points = sorted((number(r[spec["x"]]), number(r[curve["column"]])) for r in mine if not spec["series"] or r[spec["series"]] == series)
                points = [(x, y) for x, y in points if usable(x, spec["log_x"]) and usable(y, spec["log_y"])]
                if not points:
                    continue
                shown = spec["series_label"].replace("{}", series) if series and spec["series_label"] else series
                name = " ".join(part for part in (shown, curve["label"]) if part) or curve["column"]
                lines.append(Line(name, series, curve["points_only"], [p[0] for p in points], [p[1] for p in points]))
        out.append((facet, lines))
    return out
