#!/usr/bin/python3
"""The report's side-by-side videos against the run's own CSVs (side_by_side.csv, side_by_side_frames.csv):
each MP4's size and frame count read back from the video; every panel of a frame at the same simulated time
(a diverged panel held at its last reached one); at t = 0 every panel shows the same picture, seen by the
same camera (pixel offsets 0 in the CSV, and the decoded panels equal below their labels to the encoder's
noise), while the labels differ; at the end a panel the CSV puts many pixels off the reference looks different
from it; each label says its row's method, step, CPU time and offset as the CSV has them.

usage: check_side_by_side.py REPORT_DIR TOLERANCES_HPP"""
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import check_report  # noqa: E402  (the digits-shown rule the report's own check holds numbers to)


def tolerance(text, name):
    m = re.search(rf"{name}\s*=\s*([0-9.eE+-]+)", text)
    assert m, f"{name} not in verification/tolerances.hpp"
    return float(m.group(1))


def frames_of(video, width, height):
    """every frame of the MP4, decoded by ffmpeg, as (frames, height, width, 3) 8-bit RGB"""
    raw = subprocess.run(["ffmpeg", "-v", "error", "-i", video, "-f", "rawvideo", "-pix_fmt", "rgb24", "-"], check=True,
                         stdout=subprocess.PIPE).stdout
    return np.frombuffer(raw, np.uint8).reshape(-1, height, width, 3).astype(np.int16)


def probe(video):
    """the MP4's codec, width, height and frame count, as ffprobe reads them"""
    out = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                          "stream=codec_name,width,height,nb_read_frames", "-of", "csv=p=0", video], check=True,
                         stdout=subprocess.PIPE, text=True).stdout.strip()
    codec, width, height, frames = out.split(",")
    return codec, int(width), int(height), int(frames)


def main():
    report, tolerances = sys.argv[1], open(sys.argv[2]).read()
    if not os.path.exists(os.path.join(report, "side_by_side.csv")) and not shutil.which("ffmpeg"):
        print("check_side_by_side: skipped: ffmpeg is not installed, and the report filmed nothing without it")
        return 77
    noise_levels, noise_share = tolerance(tolerances, "video_noise_levels"), tolerance(tolerances, "video_noise_share")

    def apart(a, b):
        """the share of the pixels of two decoded pictures further apart than the encoder's noise"""
        return (np.abs(a - b).max(axis=2) > noise_levels).mean()

    problems = []
    panels = list(csv.DictReader(open(os.path.join(report, "side_by_side.csv"))))
    frames = list(csv.DictReader(open(os.path.join(report, "side_by_side_frames.csv"))))
    scenes = sorted({p["clip"] for p in panels})
    # a quick report films one clip, the full report every one (report/side_by_side.cpp)
    quick = "--quick" in json.load(open(os.path.join(report, "provenance.json")))["command"]
    assert scenes == (["pendulum"] if quick else ["flag", "flag-continuum", "pendulum", "water-drop"]), scenes
    shots = []
    for scene in scenes:
        rows = [p for p in panels if p["clip"] == scene]
        video = os.path.join(report, rows[0]["video"])
        codec, width, height, count = probe(video)
        want = (int(rows[0]["width"]), int(rows[0]["height"]), int(rows[0]["frames"]))
        if (codec, width, height, count) != ("h264", *want):
            problems.append(f"{video}: {codec} {width} x {height}, {count} frames; the CSV says h264 {want}")
            continue
        # 640 x 360 panels, two a row
        expected = (1280, 360 * ((len(rows) + 1) // 2))
        if (width, height) != expected:
            problems.append(f"{video}: {width} x {height}, not {expected[0]} x {expected[1]} ({len(rows)} panels of 640 x 360, two a row)")
        # the same simulated time in every panel of a frame, the reference's; a panel that stopped holds its last
        by_frame = {}
        for f in (f for f in frames if f["clip"] == scene):
            by_frame.setdefault(int(f["frame"]), []).append(f)
        if sorted(by_frame) != list(range(count)):
            problems.append(f"{scene}: side_by_side_frames.csv has frames {min(by_frame)}..{max(by_frame)}, the video {count}")
        for n, shown in by_frame.items():
            t = float(shown[0]["t"])
            for f in shown:
                row = rows[int(f["panel"])]
                ok = row["status"] == "ok"
                expected = t if ok or t <= float(row["t_last"]) + 1e-12 else float(row["t_last"])
                if abs(float(f["shown_t"]) - expected) > 1e-9 * max(1.0, t):
                    problems.append(f"{scene} frame {n}: panel {f['panel']} ({f['method']}) shows t = {f['shown_t']}, not {expected}")
                if n == 0 and float(f["pixel_error"]) != 0:
                    problems.append(f"{scene}: at t = 0 panel {f['panel']} is {f['pixel_error']} px from the reference: not the same start")
        # the labels say the rows' numbers
        for k, row in enumerate(rows):
            label = row["label"]
            if not label.startswith(f"{row['method']}  {row['setting']}"):
                problems.append(f"{scene} panel {k}: label '{label}' does not open with its method and step")
            # the label's numbers are the row's to the digits shown (check_report's rule for every number the report shows)
            m = re.search(r"CPU ([0-9.]+) (s|ms|us)", label)
            unit = {"s": 1, "ms": 1e-3, "us": 1e-6}[m.group(2)] if m else math.nan
            if not (m and check_report.matches(float(m.group(1)), check_report.shown_precision(m.group(1)), [float(row["cpu_seconds"]) / unit])):
                problems.append(f"{scene} panel {k}: label '{label}' against cpu_seconds {row['cpu_seconds']}")
            error = float(row["pixel_error"])
            reference = k + 1 == len(rows)
            if row["status"] != "ok":
                if f"{row['status']} at t {float(row['t_last']):.2f} s" not in label:
                    problems.append(f"{scene} panel {k}: label '{label}' does not say {row['status']} at t_last {row['t_last']}")
            elif not reference:
                m = re.search(r"off by ([0-9.]+) px", label)
                said = (check_report.matches(float(m.group(1)), check_report.shown_precision(m.group(1)), [error]) if m
                        else "under 0.1 px" in label and error < 0.1)
                if not said:
                    problems.append(f"{scene} panel {k}: label '{label}' against pixel_error {error}")
        shots.append((scene, rows, video, width, height))

    for scene, rows, video, width, height in shots:
        pictures = frames_of(video, width, height)
        columns = width // 640
        def panel(picture, k, below=70):
            y, x = k // columns * 360, k % columns * 640
            return picture[y + below:y + 358, x + 4:x + 636]
        def label(picture, k):
            y, x = k // columns * 360, k % columns * 640
            return picture[y + 4:y + 60, x + 4:x + 300]
        reference = len(rows) - 1
        first, last = pictures[0], pictures[-1]
        for k in range(len(rows) - 1):
            scene_gap = apart(panel(first, k), panel(first, reference))
            if scene_gap > noise_share:
                problems.append(f"{scene}: at t = 0 panel {k} differs from the reference in {scene_gap:.2e} of its pixels "
                                f"(the same picture: {noise_share})")
            label_gap = apart(label(first, k), label(first, reference))
            if label_gap <= noise_share:
                problems.append(f"{scene}: panel {k}'s label looks like the reference's ({label_gap:.2e} of its pixels apart)")
            # a panel far off the reference (or diverged) at the end looks it
            error = float(rows[k]["pixel_error"])
            if (rows[k]["status"] != "ok" or error > 10) and apart(panel(last, k), panel(last, reference)) <= noise_share:
                problems.append(f"{scene}: panel {k} is {error} px off (status {rows[k]['status']}) but its last frame looks like the reference's")
        print(f"check_side_by_side: {scene}: {len(pictures)} frames of {width} x {height}, {len(rows)} panels")
    for p in problems:
        print("check_side_by_side:", p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
