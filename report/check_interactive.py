#!/usr/bin/python3
"""The report's index.html in a real browser: headless Chromium driven by Selenium (Debian's python3-selenium and
chromium-driver).

    check_interactive.py DIR [SHOTS_DIR]

- the page loads (plotly.js with it) without console errors; its load time is printed, a figure for
  docs/performance.md, and bounded only against a hang (LOAD_HANG, far above any machine's load time);
- every figure draws when scrolled to: its plot holds a trace for each line its spec gives (report/figure_spec.py);
- a group's button above a figure shows or hides every trace of the group, the next click the other;
- a method's legend entry hides its traces, the next click shows them;
- a link of the table of contents scrolls its section to the top of the window;
- the first finding's first number with a decimal point equals a value of the CSVs of the section it links.
Screenshots (the top of the page, a figure after the clicks) go to SHOTS_DIR (default DIR). Exit 0 when all
hold, 1 when not, 77 (CTest's skip) where Chromium, its driver or Selenium is missing, saying which.
"""
import csv
import os
import re
import shutil
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import check_report  # noqa: E402  (the CSV values and the half-unit rule, as the report's own check reads them)
import figure_spec  # noqa: E402  (the declared figures and their lines, as plot.py and interactive.py read them)

# a hang, not a speed: the load takes 1-4 s on 2 cores depending on the machine and Chromium's build, so a time is
# reported, never asserted; only a page that has not loaded in a minute is a failure
LOAD_HANG = 60.0


def skip(why):
    print(f"check_interactive: skipped: {why}")
    sys.exit(77)


def main():
    directory = os.path.abspath(sys.argv[1])
    shots = os.path.abspath(sys.argv[2]) if len(sys.argv) > 2 else directory
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.options import Options
        from selenium.webdriver.chrome.service import Service
        from selenium.webdriver.common.action_chains import ActionChains
        from selenium.webdriver.common.by import By
    except ImportError:
        skip("python3-selenium is not installed (apt-get install python3-selenium chromium-driver)")
    driver_path = shutil.which("chromedriver")
    if not driver_path or not (shutil.which("chromium") or shutil.which("chromium-browser")):
        skip("chromium or chromium-driver is not installed (apt-get install chromium chromium-driver)")
    options = Options()
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1400,1000", "--disable-dev-shm-usage"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    problems = []
    browser = webdriver.Chrome(service=Service(driver_path), options=options)
    try:
        browser.get("file://" + os.path.join(directory, "index.html"))
        # interactive: plotly.js parsed and the page's load event over (a figure is drawn as it comes near the window)
        loaded = browser.execute_script("const n = performance.getEntriesByType('navigation')[0]; return n.loadEventEnd / 1000")
        print(f"check_interactive: the page loaded, plotly.js with it, {loaded:.2f} s after navigation")
        if loaded > LOAD_HANG:
            problems.append(f"the page took {loaded:.2f} s to load: hung (over {LOAD_HANG:.0f} s)")
        os.makedirs(shots, exist_ok=True)
        browser.save_screenshot(os.path.join(shots, "browser_top.png"))

        # each figure, scrolled to: drawn, with a trace for every method of its CSV
        figures = browser.find_elements(By.CSS_SELECTOR, "div.lazy-plot")
        declared = figure_spec.specs(directory)
        if not declared:
            problems.append("figures.json declares no figure")
        if not figures:
            problems.append("index.html has no interactive figures")
        for div in figures:
            stem = div.get_attribute("id").removeprefix("figure-")
            browser.execute_script("arguments[0].scrollIntoView()", div)
            deadline = time.monotonic() + 10
            while not browser.execute_script("return !!(arguments[0]._fullData && arguments[0].querySelector('.main-svg'))", div):
                if time.monotonic() > deadline:
                    problems.append(f"{stem}: not drawn 10 s after it was scrolled to")
                    break
                time.sleep(0.05)
            else:
                if stem not in declared:
                    problems.append(f"{stem}: an interactive figure figures.json does not declare")
                    continue
                # a trace for each of its lines, as figure_spec reads them
                methods = {line.name for p in figure_spec.panels(directory, declared[stem]) for line in p.lines}
                names = set(browser.execute_script("return arguments[0]._fullData.map(t => t.name)", div))
                if methods - names:
                    problems.append(f"{stem}: no trace for {sorted(methods - names)[:5]}")
        print(f"check_interactive: {len(figures)} figures drawn when scrolled to")
        for entry in browser.get_log("browser"):
            if entry["level"] == "SEVERE":
                problems.append(f"console: {entry['message'][:200]}")

        # in the first figure: a group's button shows or hides the whole group, the next click the other; a method's legend entry hides it,
        # then shows it again
        if figures:
            first = figures[0]
            browser.execute_script("arguments[0].scrollIntoView()", first)
            time.sleep(0.3)

            def visible(indices):
                return browser.execute_script("return arguments[1].map(i => arguments[0]._fullData[i].visible)", first, indices)
            button = first.find_elements(By.CSS_SELECTOR, ".updatemenu-button")[0]
            group, indices = browser.execute_script("const b = arguments[0].layout.updatemenus[0].buttons[0]; "
                                                    "return [b.label.replace(/ \\(\\d+\\)$/, ''), b.args[1]]", first)
            if not indices:
                problems.append(f"the '{group}' button names no traces")
            states = [visible(indices)]
            for _ in range(2):
                ActionChains(browser).move_to_element(button).click().perform()
                time.sleep(0.5)
                states.append(visible(indices))
            whole = lambda state, v: all(x == v for x in state)  # noqa: E731
            if not ((whole(states[1], True) and whole(states[2], "legendonly")) or (whole(states[1], "legendonly") and whole(states[2], True))):
                problems.append(f"the '{group}' button: visible {states[0]} -> {states[1]} -> {states[2]}")
            else:
                print(f"check_interactive: the '{group}' button showed or hid its {len(states[1])} traces at once, both ways")
            browser.execute_script("arguments[0].scrollIntoView()", first)
            browser.save_screenshot(os.path.join(shots, "browser_figure.png"))
            names = browser.execute_script("return arguments[0]._fullData.map(t => [t.name, t.visible])", first)
            entries = first.find_elements(By.CSS_SELECTOR, ".legend .traces")
            entry = next((e for e in entries if any(e.text.strip() == n and v is True for n, v in names if n != "Pareto front")), None)
            if entry is None:
                problems.append("the first figure's legend shows no visible method")
            else:
                name = entry.text.strip()
                shown = []
                for _ in range(2):
                    ActionChains(browser).move_to_element(entry.find_element(By.CSS_SELECTOR, ".legendtoggle")).click().perform()
                    time.sleep(0.6)  # plotly waits out a double click's interval before it toggles
                    shown.append(browser.execute_script("return arguments[0]._fullData.find(t => t.name === arguments[1]).visible", first, name))
                if shown != ["legendonly", True]:
                    problems.append(f"the legend's entry '{name}' clicked twice: visible {shown}")
                else:
                    print(f"check_interactive: the legend's entry '{name}' hid its method and showed it again")

        # the side-by-side videos play in the page: Chromium decodes each one's first frame at its size (the CSV's)
        sizes = {}
        if os.path.exists(os.path.join(directory, "side_by_side.csv")):
            for row in csv.DictReader(open(os.path.join(directory, "side_by_side.csv"))):
                sizes[row["video"]] = [int(row["width"]), int(row["height"])]
        for video in browser.find_elements(By.TAG_NAME, "video"):
            source = video.get_attribute("src")
            browser.execute_script("arguments[0].scrollIntoView(); arguments[0].preload = 'auto'; arguments[0].load()", video)
            deadline = time.monotonic() + 10
            while browser.execute_script("return arguments[0].readyState < 2 && !arguments[0].error", video) and time.monotonic() < deadline:
                time.sleep(0.05)
            state = browser.execute_script("return [arguments[0].readyState, arguments[0].videoWidth, arguments[0].videoHeight, "
                                           "arguments[0].error && arguments[0].error.code]", video)
            size = next((v for k, v in sizes.items() if source.endswith(k)), None)
            if state[0] < 2 or state[1:] != [*(size or [-1, -1]), None]:
                problems.append(f"{source}: not playable in the page (readyState, width, height, error: {state})")
        if videos := browser.find_elements(By.TAG_NAME, "video"):
            browser.save_screenshot(os.path.join(shots, "browser_video.png"))
            print(f"check_interactive: {len(videos)} side-by-side videos decoded in the page at their sizes")

        # a table-of-contents link brings its section to the top
        link = browser.find_elements(By.CSS_SELECTOR, "nav a[href^='#']")[3]
        target = link.get_attribute("href").split("#", 1)[1]
        link.click()
        time.sleep(0.3)
        top = browser.execute_script("return document.getElementById(arguments[0]).getBoundingClientRect().top", target)
        if abs(top) > 5:
            problems.append(f"the contents' link to #{target} left its heading {top:.0f} px from the top")

        # the first finding's number, in the browser, against its section's CSVs
        finding = browser.find_element(By.CSS_SELECTOR, "#in-short ~ ul li, h2#in-short + ul li")
        number = re.search(r"\d+\.\d+(?:e[-+]?\d+)?", finding.text)
        anchor = finding.find_element(By.CSS_SELECTOR, "a[href^='#']").get_attribute("href").split("#", 1)[1]
        md = open(os.path.join(directory, "report.md")).read()
        section = md.split(f'<a id="{anchor}"></a>', 1)[1].split('<a id="', 1)[0]
        values = check_report.csv_values(directory, re.findall(r"\(([\w\-]+\.csv)\)", section))
        if not number:
            problems.append(f"the first finding shows no number: {finding.text[:100]}")
        else:
            token = number.group(0)
            if not check_report.matches(float(token), check_report.shown_precision(token), values):
                problems.append(f"the first finding's {token} is in none of #{anchor}'s CSVs")
            else:
                print(f"check_interactive: the first finding's {token} is a value of #{anchor}'s CSVs")
    finally:
        browser.quit()
    for p in problems:
        print("FAIL:", p)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
