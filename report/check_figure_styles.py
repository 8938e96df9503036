#!/usr/bin/python3
"""A method looks the same in a figure's PNG and in its twin to explore, and each method has a look of its own.

    check_figure_styles.py DIR

DIR is a report (its figures.json, figures.csv, methods.csv and CSVs). For every figure that draws methods' lines,
its styles are resolved once (report/figure_spec.py); the figure is drawn by plot.py into a PNG (in a temporary
folder) and built by interactive.py as a plotly figure. Checked:
- every method in the method table has a colour and marker pair of its own;
- in the PNG, each method line with filled markers shows pixels of exactly its resolved colour (a marker's inside
  is drawn without antialiasing);
- in the plotly figure, each method's traces carry exactly that colour on their line and markers, and the same
  marker; a failed run's crosses the method's colour too.
Exit 0 when all hold, 1 naming the figure and method otherwise, 77 (skipped) without python3-plotly.
"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import figure_spec  # noqa: E402
import interactive  # noqa: E402
import plot  # noqa: E402

import matplotlib.image  # noqa: E402


def png_colours(path):
    """the exact RGB colours of a PNG's opaque pixels, as "#RRGGBB"""
    pixels = matplotlib.image.imread(path)
    opaque = pixels[pixels[..., 3] == 1.0][:, :3] if pixels.shape[-1] == 4 else pixels.reshape(-1, 3)
    codes = {tuple(int(round(255 * c)) for c in rgb) for rgb in {tuple(p) for p in opaque.tolist()}}
    return {"#{:02X}{:02X}{:02X}".format(*c) for c in codes}


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    directory = sys.argv[1]
    if not interactive.available():
        print("check_figure_styles.py: python3-plotly is not installed: skipped")
        return 77
    methods = figure_spec.Methods(directory)
    problems = []
    looks = {(methods.colour[m], methods.marker[m]) for m in methods.group}
    if len(looks) != len(methods.group):
        problems.append(f"{len(methods.group)} methods share {len(looks)} colour and marker pairs")
    specs = figure_spec.specs(directory)
    checked = 0
    with tempfile.TemporaryDirectory() as out:
        for stem, spec in specs.items():
            panels = figure_spec.panels(directory, spec, methods)
            lines = [line for p in panels for line in p.lines if line.method and line.mark != figure_spec.Mark.STAR]
            if not lines:
                continue
            checked += 1
            plot.draw_figure(out, stem, panels)
            seen = png_colours(os.path.join(out, stem + ".png"))
            fig, _ = interactive.figure(methods, spec, panels)
            traces = {}
            for trace in fig.data:
                traces.setdefault(trace.name, []).append(trace)
            for line in lines:
                colour = methods.colour[line.key]
                if line.style.colour != colour:
                    problems.append(f"{stem}: {line.name} resolved to {line.style.colour}, its method's colour is {colour}")
                if line.style.marker and not line.style.marker.endswith("-open") and colour not in seen:
                    problems.append(f"{stem}.png: no pixel of {line.name}'s colour {colour}")
                for trace in traces.get(line.name, []):
                    if trace.type != "scatter":
                        continue
                    if trace.line.color != colour or trace.marker.color != colour:
                        problems.append(f"{stem} to explore: {line.name} drawn in {trace.line.color} / {trace.marker.color}, not {colour}")
                    if line.style.marker and trace.marker.symbol not in (line.style.marker, "x"):
                        problems.append(f"{stem} to explore: {line.name}'s marker {trace.marker.symbol}, not {line.style.marker}")
                if line.name not in traces:
                    problems.append(f"{stem} to explore: no trace for {line.name}")
    for p in problems[:20]:
        print(p, file=sys.stderr)
    print(f"{checked} figures with methods' lines checked, {len(methods.group)} methods: "
          f"{'each its own colour and marker, alike in the PNG and its twin' if not problems else f'{len(problems)} problems'}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
