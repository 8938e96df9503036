#!/usr/bin/python3
"""Open a written report's index.html in headless Chromium: every image decoded (none broken), and a screenshot
that shows the figures.

    check_browser.py DIR

The page is copied with a probe script added that, once the page has loaded, counts the images the browser
decoded (complete, with a natural width) and writes the count into the page, read back from Chromium's
--dump-dom. The screenshot of the top of the page must hold the figures' colours: at least MIN_COLOURED of its
pixels saturated (text and tables are grey). Exit 0 when both hold, 1 when not, 77 (CTest's skip) when no
Chromium is installed, saying how to install it.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

MIN_COLOURED = 0.002  # of the screenshot's pixels: one figure's lines and markers cover more than 0.5% of its own area
PROBE = """<script>
window.addEventListener('load', () => {
  const images = [...document.images];
  const drawn = images.filter(i => i.complete && i.naturalWidth > 0).length;
  const out = document.createElement('pre');
  out.id = 'stepwise-probe';
  out.textContent = `decoded ${drawn} of ${images.length}`;
  document.body.appendChild(out);
});
</script>
"""


def chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def main():
    directory = sys.argv[1]
    browser = chromium()
    if not browser:
        print("check_browser: skipped: no Chromium here (Debian's chromium package: apt-get install chromium)")
        sys.exit(77)
    flags = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--allow-file-access-from-files", "--hide-scrollbars"]
    problems = []
    with tempfile.TemporaryDirectory() as work:
        page_dir = os.path.join(work, "report")
        shutil.copytree(directory, page_dir)
        with open(os.path.join(page_dir, "index.html")) as f:
            page = f.read()
        with open(os.path.join(page_dir, "probe.html"), "w") as f:
            f.write(page.replace("</body>", PROBE + "</body>"))
        url = "file://" + os.path.join(page_dir, "probe.html")
        dom = subprocess.run(flags + ["--virtual-time-budget=20000", "--dump-dom", url], capture_output=True, text=True, timeout=300).stdout
        found = re.search(r'id="stepwise-probe">decoded (\d+) of (\d+)<', dom)
        if not found:
            problems.append("the probe did not run: Chromium did not load the page")
        else:
            drawn, total = int(found.group(1)), int(found.group(2))
            if total == 0 or drawn != total:
                problems.append(f"{total - drawn} of {total} images broken")
            print(f"check_browser: {drawn} of {total} images decoded")

        shot = os.path.join(work, "shot.png")
        subprocess.run(flags + ["--window-size=1280,5000", f"--screenshot={shot}", "file://" + os.path.join(page_dir, "index.html")],
                       capture_output=True, timeout=300)
        if not os.path.isfile(shot):
            problems.append("Chromium wrote no screenshot")
        else:
            import matplotlib.image
            import numpy as np

            pixels = matplotlib.image.imread(shot)[..., :3]
            saturation = pixels.max(axis=2) - pixels.min(axis=2)
            coloured = float((saturation > 0.25).mean())
            print(f"check_browser: {100 * coloured:.2f}% of the screenshot's pixels coloured")
            if coloured < MIN_COLOURED:
                problems.append(f"the screenshot shows no figures ({100 * coloured:.3f}% coloured pixels)")
    for p in problems:
        print(p)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
