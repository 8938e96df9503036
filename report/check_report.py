#!/usr/bin/python3
"""Check a written report: every figure and table there and non-empty, and the tables' numbers the CSVs' numbers.

    check_report.py DIR

- every image report.md shows is a PNG (or an animation's GIF) in DIR of at least MIN_PNG_BYTES, and index.html shows the same images;
- every CSV a section links exists, with a header and at least one row;
- every number in a section's Markdown tables is a value of that section's CSVs as shown: within half a unit
  of its last digit (the table rounds, the CSV keeps 17 digits). A number typed in, computed only for the
  table, or left from another run, fails;
- the report opens with its findings ("In short"), each linking to the section that holds its evidence, and
  every number written with a decimal point or an exponent in a finding is a value of that section's CSVs as
  shown (whole numbers are counts);
- index.html's table of contents links every section;
- every figure (figures.csv) is declared in figures.json, names tables and columns the report has, and draws
  something in each of its panels (report/figure_spec.py's problems() and empty()).
Prints each problem on a line and exits 1 if there is any.
"""
import bisect
import csv
import math
import os
import re
import sys

import figure_spec  # report/figure_spec.py, beside this script
from timed_tables import tolerance  # report/timed_tables.py: verification/tolerances.hpp's constants

MIN_PNG_BYTES = 5000  # a drawn figure with axes, labels and lines; an empty canvas at 100 dpi is ~3 kB
MIN_GIF_BYTES = 1000  # an animation of a small particle on a plain ground is ~3 kB; one empty frame ~0.1 kB
NUMBER = re.compile(r"(?<![\w.\-+])[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?(?![\w.])")


def sections(md):
    """(title, text) per '## ' section."""
    parts = re.split(r"^## ", md, flags=re.M)
    return [(p.splitlines()[0], p) for p in parts[1:]]


def table_cells(text):
    """The cells of every table row of the text, header and separator rows left out."""
    cells = []
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if not line.startswith("|") or set(line) <= set("|-: "):
            continue
        if i + 1 < len(lines) and lines[i + 1].startswith("|") and set(lines[i + 1]) <= set("|-: "):
            continue  # a header
        cells.extend(c.strip() for c in line.strip().strip("|").split("|"))
    return cells


def csv_values(directory, names):
    values = []
    for name in names:
        with open(os.path.join(directory, name), newline="") as f:
            for row in csv.reader(f):
                for cell in row:
                    try:
                        values.append(float(cell))
                    except ValueError:
                        values.extend(float(m) for m in NUMBER.findall(cell))
    return sorted(v for v in values if math.isfinite(v))


def shown_precision(token):
    """Half a unit in the last digit shown."""
    mantissa, _, exponent = token.lower().partition("e")
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 0.5 * 10 ** (-decimals + (int(exponent) if exponent else 0))


def matches(value, half_unit, candidates):
    """Some candidate (sorted) within half_unit of value."""
    i = bisect.bisect_left(candidates, value - half_unit * (1 + 1e-9))
    return i < len(candidates) and candidates[i] <= value + half_unit * (1 + 1e-9)


# the tables held-out checks read, as the studies' contracts give them: their columns in order, and what each must hold
TABLE_CONTRACTS = {
    "cloth_solvers.csv": ["model", "method", "dt", "iterations", "substeps", "start", "threads", "cpu_per_simulated_second", "potential_gap",
                          "pixels_off", "pixels_off_true_motion", "status"],
    "continuum_cloth_bending.csv": ["side", "nodes", "E", "nu", "thickness", "density", "length", "tip_deflection", "analytic"],
    "continuum_cloth_clamped.csv": ["model", "side", "nodes", "drop", "bottom_width", "middle_width"],
    "continuum_cloth_newton.csv": ["model", "nu", "dt", "status", "t_stop", "newton_iterations_mean", "line_search_halvings_mean",
                                   "cpu_per_simulated_second", "pixels_vs_converged"],
    "constraints_compliant_rod.csv": ["compliance", "method", "iterations", "off_backward_euler", "off_true_motion", "cpu_seconds", "status"],
}


def table_contracts(directory):
    problems = []
    for name, columns in TABLE_CONTRACTS.items():
        path = os.path.join(directory, name)
        if not os.path.isfile(path):
            problems.append(f"{name}: missing")
            continue
        rows = list(csv.DictReader(open(path)))
        header = next(csv.reader(open(path)), [])
        if header != columns:
            problems.append(f"{name}: columns {header}, not {columns}")
            continue
        if not rows:
            problems.append(f"{name}: no rows")
    solvers = os.path.join(directory, "cloth_solvers.csv")
    if os.path.isfile(solvers):
        rows = list(csv.DictReader(open(solvers)))
        for method in ("vbd", "vbd-chebyshev", "xpbd", "implicit-euler-newton", "implicit-euler", "fast-mass-spring"):
            if not any(r["method"] == method for r in rows):
                problems.append(f"cloth_solvers.csv: no {method} row")
        # vbd's G is never raised by a sweep, nor by a Chebyshev extrapolation: more sweeps from the same start leave
        # it no higher, on each model at 1/60 s (to G's round-off: 1e-11 of its 2.5 J, well below 1e-9 J)
        for model in {r["model"] for r in rows}:
            for method in ("vbd", "vbd-chebyshev"):
                for start in ("adaptive", "inertial"):
                    gaps = sorted((int(r["iterations"]), float(r["potential_gap"])) for r in rows
                                  if r["model"] == model and r["method"] == method and r["start"] == start and abs(float(r["dt"]) - 1 / 60) < 1e-12)
                    if any(b[1] > a[1] + 1e-9 for a, b in zip(gaps, gaps[1:])):
                        problems.append(f"cloth_solvers.csv: {model}: {method}'s potential gap from the {start} start grows with its sweeps: {gaps}")
    problems += compliant_rod(directory)
    return problems


def compliant_rod(directory):
    """the pendulum on a compliant rod at 1/60 s frames: vbd and xpbd at 10 iterations a frame are backward Euler's
    converged steps (within compliant_rod_converged), and symplectic Euler does not survive the stiff rod, whose
    omega h = 17 is past its stability limit omega h = 2"""
    path = os.path.join(directory, "constraints_compliant_rod.csv")
    if not os.path.isfile(path):
        return []
    rows, problems, bound = list(csv.DictReader(open(path))), [], tolerance("compliant_rod_converged")
    for r in rows:
        if r["method"] in ("vbd", "xpbd") and r["iterations"] == "10" and not float(r["off_backward_euler"]) <= bound:
            problems.append(f"constraints_compliant_rod.csv: {r['method']} at 10 iterations is {r['off_backward_euler']} m from backward Euler "
                            f"(compliance {r['compliance']}), past {bound}")
        if r["method"] == "symplectic-euler" and float(r["compliance"]) < 1e-5 and r["status"] == "ok":
            problems.append("constraints_compliant_rod.csv: symplectic Euler ran the stiff rod past its stability limit")
    return problems


def main():
    directory = sys.argv[1]
    problems = []
    md = open(os.path.join(directory, "report.md")).read()
    page = open(os.path.join(directory, "index.html")).read()
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md)
    if not images:
        problems.append("report.md shows no figures")
    for image in images:
        path = os.path.join(directory, image)
        if not os.path.isfile(path):
            problems.append(f"{image}: missing")
            continue
        with open(path, "rb") as f:
            head = f.read(8)
        if image.endswith(".gif"):
            if not head.startswith(b"GIF89a") or os.path.getsize(path) < MIN_GIF_BYTES:
                problems.append(f"{image}: not a drawn GIF ({os.path.getsize(path)} bytes)")
        elif head != b"\x89PNG\r\n\x1a\n" or os.path.getsize(path) < MIN_PNG_BYTES:
            problems.append(f"{image}: not a drawn PNG ({os.path.getsize(path)} bytes)")
        if f'src="{image}"' not in page and not (f'href="{image}"' in page and f'id="figure-{image[:-4]}"' in page):
            problems.append(f"{image}: not shown by index.html (nor an interactive figure linking it)")
    # every figure declared (figures.json), its tables and columns there, each of its panels drawing something
    specs = figure_spec.specs(directory)
    with open(os.path.join(directory, "figures.csv"), newline="") as f:
        for row in csv.DictReader(f):
            stem = row["stem"]
            if stem not in specs:
                problems.append(f"{stem}: no spec in figures.json")
            else:
                problems += figure_spec.problems(directory, stem, specs[stem]) or figure_spec.empty(stem, figure_spec.panels(directory, specs[stem]))
    if page.count("<table>") != md.count("\n|---"):
        problems.append(f"index.html has {page.count('<table>')} tables, report.md {md.count(chr(10) + '|---')}")

    checked = 0
    parts = sections(md)
    if not parts or parts[0][0] != "In short":
        problems.append("report.md does not open with its findings (## In short)")
    findings = [line for line in (parts[0][1].splitlines() if parts else []) if line.startswith("- ")]
    if len(findings) < 4:
        problems.append(f"In short: {len(findings)} findings, expected one from each of the work-precision, stability, energy, adequacy and advice studies")
    anchored = re.findall(r'<a id="([\w-]+)"></a>\s*\n\s*## ([^\n]+)', md)
    section_of = {anchor: title for anchor, title in anchored}
    section_text = dict(parts)
    for line in findings:
        m = re.search(r"\(\[the evidence\]\(#([\w-]+)\)\)$", line)
        if not m or m.group(1) not in section_of:
            problems.append(f"In short: a finding links no section of the report: {line[:80]}")
            continue
        links = re.findall(r"\[[^\]]+\.csv\]\(([^)]+\.csv)\)", section_text[section_of[m.group(1)]])
        values = csv_values(directory, [l for l in links if os.path.isfile(os.path.join(directory, l))])
        for token in NUMBER.findall(line[:m.start()]):
            if "." not in token and "e" not in token.lower():
                continue
            checked += 1
            if not matches(float(token), shown_precision(token), values):
                problems.append(f"In short: {token} in the finding on '{section_of[m.group(1)]}' is in none of its CSVs")
    nav = re.search(r"<nav.*?</nav>", page, re.S)
    for title, _ in parts:
        if not nav or f">{title.replace('&', '&amp;')}</a>" not in nav.group(0):
            problems.append(f"index.html's contents do not link the section '{title}'")
    for title, text in parts[1:]:
        links = re.findall(r"\[[^\]]+\.csv\]\(([^)]+\.csv)\)", text)
        if not links:
            problems.append(f"section '{title}': links no CSV")
            continue
        for link in links:
            path = os.path.join(directory, link)
            if not os.path.isfile(path) or sum(1 for _ in open(path)) < 2:
                problems.append(f"section '{title}': {link} missing or empty")
        values = csv_values(directory, links)
        for cell in table_cells(text):
            for token in NUMBER.findall(cell):
                value, half = float(token), shown_precision(token)
                checked += 1
                if not matches(value, half, values):
                    problems.append(f"section '{title}': table value {token} (cell '{cell}') is in none of {', '.join(links)}")
    problems += table_contracts(directory)
    for p in problems:
        print(p)
    print(f"check_report: {len(images)} figures, {checked} table numbers checked, {len(problems)} problems")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
