#!/usr/bin/env python3
"""The dashboard in a real browser: headless Chromium (Debian's chromium + chromium-driver)
driven by Selenium loads every page from a running `enavi serve` on loopback, over a database
seeded by seed_dashboard_db, and checks that

  - every chart (Chart.js, read through its own API) laid out each of its series' points inside
    its plot area, painted them in the series' colour, and keeps its legend of swatches off the
    plot area (the highest point of a spread chart is not on the legend row),
  - the job page has a spread chart per judged metric with every method's mean, box and whisker
    per board x scenario; hovering a group lists every method's numbers,
  - the episode page's time series zoom together on a drag and back on a double-click, hover
    shows the values at that time, and events are drawn on the time axis,
  - two flights overlay on one set of charts: chosen on the episode page (the other method's
    flight) or ticked in a job's episode list, and from a compare cell (before vs after),
  - the trend draws a 95 % bar per job and board for the chosen method, and a series of one job
    still draws its point,
  - nothing is drawn outside the values a metric can take: no mean ± std box or interval of a
    non-negative metric below 0, an outcome (success) on a 0..1 axis,
  - the compare page lists how the two jobs' specs differ before the metrics, colours exactly the
    planted regression (tx2 x s1) and a click on it overlays both flights; in exact mode it says a
    difference over few seeds can be a draw and links the paired test, which finds the same
    regression; with one seed pair paired mode says it cannot judge and links exact mode,
  - a user's ROS stack as a method shows by its name in legends, tables and the overlay, and a
    job whose ROS episodes no connected worker can run says so on the jobs list and its page,
  - the job named <img src=x onerror=alert(1)> shows as that text (no element, no alert),
  - the bird's-eye PNG loaded,
  - `enavi status --label` and GET /api/jobs?label= filter by label,
  - `enavi dashboard --db` serves the same pages read-only (POST: 405).

ENAVI_SCREENSHOT_DIR=DIR saves a screenshot of each page there (docs/img for docs/dashboard.md);
with ENAVI_SCREENSHOT_DB=FILE as well, they are taken of that database (real flights) instead,
by RealFlightScreenshots, which checks the same of its charts.
Usage: dashboard_browser_test.py BUILD_DIR SOURCE_DIR
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest
import urllib.error
import urllib.parse
import urllib.request

BUILD, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
ENAVI = os.path.join(BUILD, "bin", "enavi")
SEED = os.path.join(BUILD, "tests", "seed_dashboard_db")
HOSTILE = "<img src=x onerror=alert(1)>"
SHOTS = os.environ.get("ENAVI_SCREENSHOT_DIR")
SHOT_DB = os.environ.get("ENAVI_SCREENSHOT_DB")

# What every chart on the page drew, read through Chart.js: per dataset its points' pixel
# positions against the plot area, and how many of a sample of them have a pixel of the
# dataset's colour within 3 px (the canvas was painted there, not only laid out); the legend's
# boxes and items.
CHARTS_JS = r"""
const hex = c => { const m = /^#([0-9a-f]{6})/i.exec(c || ''); if (!m) return null;
                   const v = parseInt(m[1], 16); return [v >> 16, (v >> 8) & 255, v & 255]; };
return [...document.querySelectorAll(arguments[0] || 'canvas.chart')].map(canvas => {
  const chart = Chart.getChart(canvas);
  if (!chart) return {title: canvas.className, missing: true};
  const a = chart.chartArea, dpr = chart.currentDevicePixelRatio, ctx = canvas.getContext('2d');
  const painted = (x, y, rgb) => {
    const r = 3, px = ctx.getImageData(Math.round((x - r) * dpr), Math.round((y - r) * dpr),
                                       Math.ceil(2 * r * dpr) + 1, Math.ceil(2 * r * dpr) + 1).data;
    for (let i = 0; i < px.length; i += 4) {
      if (px[i + 3] > 150 && Math.abs(px[i] - rgb[0]) + Math.abs(px[i + 1] - rgb[1]) + Math.abs(px[i + 2] - rgb[2]) < 60) return true;
    }
    return false;
  };
  const datasets = chart.data.datasets.map((ds, i) => {
    const meta = chart.getDatasetMeta(i);
    const els = meta.data.filter(e => !e.skip).map(e => e.getProps(['x', 'y', 'base', 'options'], true));
    const inside = els.filter(p => Number.isFinite(p.x) && Number.isFinite(p.y) &&
        p.x >= a.left - 1 && p.x <= a.right + 1 && p.y >= a.top - 1 && p.y <= a.bottom + 1 &&
        (p.base === undefined || (p.base >= a.top - 1 && p.base <= a.bottom + 1)));
    // The topmost pixel a point can reach (its radius) or a bar's upper end.
    const top = Math.min(...els.map(p => p.base === undefined ? p.y - ((p.options && p.options.radius) || 0) : Math.min(p.y, p.base)));
    const rgb = hex(ds.type === 'scatter' || ds.role === 'mean' ? ds.backgroundColor : ds.borderColor || ds.backgroundColor);
    const step = Math.max(1, Math.floor(inside.length / 20));
    const sample = inside.filter((p, k) => k % step === 0);
    // The lowest and highest values drawn (a bar's ends, a point's y).
    const ys = ds.data.flatMap(v => v === null || typeof v !== 'object' ? [v] : Array.isArray(v.y) ? v.y : [v.y])
                      .filter(Number.isFinite);
    return {label: ds.label, role: ds.role || '', visible: chart.isDatasetVisible(i), n: els.length,
            inside: inside.length, top, sampled: sample.length, low: Math.min(...ys), high: Math.max(...ys),
            painted: rgb ? sample.filter(p => painted(p.x, p.y, rgb)).length : -1};
  });
  return {title: chart.options.plugins.title.text, kind: canvas.classList[1],
          area: {left: a.left, top: a.top, right: a.right, bottom: a.bottom},
          legend: (chart.legend.legendHitBoxes || []).map(b => ({left: b.left, top: b.top, right: b.left + b.width,
                                                                 bottom: b.top + b.height})),
          legendItems: (chart.legend.legendItems || []).map(i => i.text),
          xRange: [chart.scales.x.min, chart.scales.x.max],
          yRange: [chart.scales.y.min, chart.scales.y.max], yTicks: chart.scales.y.ticks.map(t => t.value), datasets};
});
"""


def start(args, tmp, name):
    ready = os.path.join(tmp, name + ".ready")
    log = open(os.path.join(tmp, name + ".log"), "w")
    proc = subprocess.Popen(args + ["--ready-file", ready], stdout=log, stderr=subprocess.STDOUT)
    deadline = time.time() + 20
    while not os.path.exists(ready):
        if proc.poll() is not None or time.time() > deadline:
            proc.kill()
            raise RuntimeError(name + " did not start: " + open(log.name).read())
        time.sleep(0.05)
    with open(ready) as f:
        return proc, f.read().strip()


def chromium(tmp):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1300,1000", "--force-device-scale-factor=1",
                "--user-data-dir=" + os.path.join(tmp, "chrome")):
        options.add_argument(arg)
    options.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
    service = Service(shutil.which("chromedriver") or "/usr/bin/chromedriver")
    driver = webdriver.Chrome(service=service, options=options)
    driver.set_page_load_timeout(20)
    return driver


class PageChecks:
    """Opening routes and checking what their charts drew; the test classes share it."""

    def open(self, route, shot=None):
        """Loads a route and waits until the page says it is ready (or failed)."""
        from selenium.webdriver.support.ui import WebDriverWait
        self.driver.get(self.url + "/" + route)
        # The page marks itself ready with the route it rendered (a new hash on the same document
        # re-renders without a reload).
        WebDriverWait(self.driver, 15).until(lambda d: d.execute_script(
            "return document.body.dataset.ready === location.hash || document.body.dataset.ready === 'error'"))
        ready = self.driver.execute_script("return document.body.dataset.ready")
        main = self.driver.find_element("id", "main").text
        self.assertNotEqual(ready, "error", main)
        if shot:
            self.screenshot(shot)

    def wait_ready(self, predicate_js="return true"):
        from selenium.webdriver.support.ui import WebDriverWait
        WebDriverWait(self.driver, 15).until(lambda d: d.execute_script(
            "return document.body.dataset.ready === location.hash && (() => {" + predicate_js + "})()"))

    def screenshot(self, name, max_height=2000):
        """The whole page (up to max_height px), as docs/dashboard.md shows it."""
        if not SHOTS or not name:
            return
        height = self.driver.execute_script("return document.documentElement.scrollHeight")
        self.driver.set_window_size(1300, min(max(height, 1000), max_height) + 140)  # + the window's frame
        try:
            self.driver.execute_script("window.scrollTo(0, 0)")
            self.driver.save_screenshot(os.path.join(SHOTS, name))
        finally:
            self.driver.set_window_size(1300, 1000)

    def charts(self, selector="canvas.chart"):
        return self.driver.execute_script(CHARTS_JS, selector)

    def assert_charts_drew(self, at_least, selector="canvas.chart"):
        """Every chart laid out all its points inside its plot area and painted some of them in
        their colours; legends sit off the plot area, and no point reaches up into them."""
        charts = self.charts(selector)
        self.assertGreaterEqual(len(charts), at_least, [c.get("title") for c in charts])
        for c in charts:
            self.assertNotIn("missing", c, "no chart on canvas %s" % c["title"])
            title, area = c["title"], c["area"]
            self.assertGreater(area["right"] - area["left"], 100, title)
            self.assertGreater(area["bottom"] - area["top"], 50, title)
            with_data = [d for d in c["datasets"] if d["n"] and d["visible"]]
            self.assertTrue(with_data, "chart '%s' has no data" % title)
            for d in with_data:
                self.assertEqual(d["inside"], d["n"], "chart '%s', %s: points outside the plot area" % (title, d["label"]))
            self.assertTrue(any(d["painted"] > 0 for d in with_data), "chart '%s' painted none of its points" % title)
            self.assertTrue(c["legendItems"], "chart '%s' has no legend" % title)
            for box in c["legend"]:
                overlaps = (box["left"] < area["right"] and box["right"] > area["left"] and
                            box["top"] < area["bottom"] and box["bottom"] > area["top"])
                self.assertFalse(overlaps, "chart '%s': legend box %s on the plot area %s" % (title, box, area))
            legend_bottom = max(b["bottom"] for b in c["legend"])
            for d in with_data:
                self.assertGreaterEqual(d["top"], legend_bottom, "chart '%s', %s reaches the legend" % (title, d["label"]))
        return charts

    def assert_within_metric_bounds(self, charts):
        """A chart of a metric (its title's first word) with a range in /api/info draws nothing
        outside the values the metric can take: no mean ± std box or interval of a non-negative
        metric below 0, an outcome's axis 0..1 (a small pad, no tick outside). Returns the
        number of charts checked."""
        with urllib.request.urlopen(self.url + "/api/info") as r:
            rules = json.load(r)["metric_rules"]
        checked = 0
        for c in charts:
            rule = rules.get(c["title"].split(" ")[0])
            if not rule or rule["range"] == "any":
                continue
            checked += 1
            lo, hi = (0.0, 1.0) if rule["range"] == "outcome" else (0.0, float("inf"))
            for d in c["datasets"]:
                if d["n"]:
                    self.assertGreaterEqual(d["low"], lo, "chart '%s', %s below the metric's floor" % (c["title"], d["label"]))
                    self.assertLessEqual(d["high"], hi, "chart '%s', %s above the metric's ceiling" % (c["title"], d["label"]))
            self.assertTrue(all(lo <= t <= hi for t in c["yTicks"]), (c["title"], c["yTicks"]))
            self.assertGreaterEqual(c["yRange"][0], lo - 0.1 * max(1.0, c["yRange"][1] - lo), (c["title"], c["yRange"]))
            if c["yRange"][0] < lo:  # an axis padded below the floor labels the floor, not the padded end
                self.assertIn(lo, c["yTicks"], (c["title"], c["yTicks"]))
            if rule["range"] == "outcome":
                self.assertTrue(-0.1 <= c["yRange"][0] < 0 and 1 < c["yRange"][1] <= 1.1, (c["title"], c["yRange"]))
                self.assertIn(1, c["yTicks"], (c["title"], c["yTicks"]))
        return checked

    def assert_each_painted(self, chart, roles):
        """Every visible dataset of these roles painted its own points (none hidden under another)."""
        for d in chart["datasets"]:
            if d["role"] in roles and d["n"] and d["visible"]:
                self.assertGreater(d["painted"], 0, "chart '%s': %s not painted" % (chart["title"], d["label"]))

    def canvas_point(self, canvas, x, y):
        """Moves the mouse to canvas pixel (x, y)."""
        from selenium.webdriver.common.action_chains import ActionChains
        rect = self.driver.execute_script("const r = arguments[0].getBoundingClientRect(); return [r.width, r.height]", canvas)
        ActionChains(self.driver).move_to_element(canvas).move_by_offset(int(x - rect[0] / 2), int(y - rect[1] / 2)).perform()

    def tooltip(self, index):
        return self.driver.execute_script(
            "const ch = Chart.getChart(document.querySelectorAll('canvas.chart')[arguments[0]]);"
            "return ch.tooltip.opacity > 0 ? [ch.tooltip.title.join(' '),"
            " ch.tooltip.body.flatMap(b => b.lines)] : null", index)


class DashboardBrowserTest(PageChecks, unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="enavi-browser-")
        db = os.path.join(cls.tmp, "farm.db")
        cls.ids = json.loads(subprocess.check_output([SEED, db], text=True))
        # A private DDS domain and partition: the server must not meet other tests' workers.
        cls.server, cls.url = start(
            [ENAVI, "serve", "--db", db, "--http", "127.0.0.1:0", "--domain", str(100 + os.getpid() % 100),
             "--partition", "browser-%d" % os.getpid()], cls.tmp, "serve")
        cls.driver = chromium(cls.tmp)

    @classmethod
    def tearDownClass(cls):
        cls.driver.quit()
        cls.server.terminate()
        cls.server.wait(10)
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def shot(self, name):
        return None if SHOT_DB else name  # RealFlightScreenshots takes them of real flights

    def test_the_charting_library_is_served_by_the_binary(self):
        with urllib.request.urlopen(self.url + "/static/chart.min.js") as r:
            self.assertIn("Chart.js v3.", r.read(400).decode())
        with urllib.request.urlopen(self.url + "/") as r:
            page = r.read().decode()
        # The page loads it from the binary, never from elsewhere.
        self.assertIn('<script src="/static/chart.min.js">', page)
        self.assertNotRegex(page, r'(src|href)="(https?:)?//')

    def test_jobs_page_lists_jobs_labels_and_escapes_the_hostile_name(self):
        self.open("#/jobs", self.shot("dashboard-jobs.png"))
        names = [e.text for e in self.driver.find_elements("css selector", "td.job-name")]
        self.assertIn("nightly-1", names)
        self.assertIn(HOSTILE, names)  # the characters, as text
        self.assertEqual(self.driver.execute_script("return document.querySelectorAll('img[src=x]').length"), 0)
        labels = [e.text for e in self.driver.find_elements("css selector", "span.label")]
        self.assertIn("suite=nightly", labels)
        self.assertIn("workers", self.driver.page_source.lower())
        # An alert would have been raised by now and fail any further command.
        self.assertEqual(self.driver.title, "E-Navi Farm")

    def test_job_page_draws_the_spread_over_seeds_of_every_method_per_metric(self):
        self.open("#/job/" + self.ids["base"], self.shot("dashboard-job.png"))
        charts = self.assert_charts_drew(5)
        titles = [c["title"] for c in charts]
        self.assertTrue(any(t.startswith("flight_time_s") for t in titles), titles)
        for c in charts:
            self.assertEqual(c["legendItems"], ["baseline", "enavi"], c["title"])  # one swatch per method
            for d in c["datasets"]:
                # 2 boards x 2 scenarios, each method's whisker, box and mean in every group.
                self.assertEqual(d["n"], 4, (c["title"], d["label"]))
            self.assert_each_painted(c, {"mean"})
        self.assertEqual(self.assert_within_metric_bounds(charts), len(charts))
        # Hovering a group lists each method's numbers there.
        flight = titles.index(next(t for t in titles if t.startswith("flight_time_s")))
        canvas = self.driver.find_elements("css selector", "canvas.chart")[flight]
        area = charts[flight]["area"]
        self.driver.execute_script("arguments[0].scrollIntoView()", canvas)
        self.canvas_point(canvas, area["left"] + (area["right"] - area["left"]) / 8, (area["top"] + area["bottom"]) / 2)
        tip = self.tooltip(flight)
        self.assertIsNotNone(tip, "no tooltip on hover")
        self.assertEqual(tip[0], "pi4b s1")
        self.assertEqual(len(tip[1]), 2, tip)
        self.assertTrue(tip[1][0].startswith("baseline: mean 42.20"), tip)
        self.assertIn("n 3", tip[1][0])
        reasons = [e.text for e in self.driver.find_elements("css selector", "td.reason")]
        self.assertTrue(any("exited with code 3" in r for r in reasons), reasons)
        self.assertIn("1–23 of 23", self.driver.find_element("id", "results").text)

    def test_two_episodes_ticked_on_the_job_page_open_as_an_overlay(self):
        self.open("#/job/" + self.ids["base"])
        base = self.ids["base"]
        for episode in (base + "-00000", base + "-00001", base + "-00003"):  # the third tick drops the first
            self.driver.find_element("css selector", "input.pick[data-episode='%s']" % episode).click()
        ticked = self.driver.execute_script("return [...document.querySelectorAll('input.pick:checked')].map(i => i.dataset.episode)")
        self.assertEqual(ticked, [base + "-00001", base + "-00003"])
        self.driver.find_element("css selector", "#overlay-pick a").click()
        self.wait_ready("return document.body.dataset.page === 'overlay'")
        self.assertIn("a=%s-00001&b=%s-00003" % (base, base), self.driver.execute_script("return location.hash"))
        self.assert_charts_drew(8)

    def test_a_ros_method_shows_by_its_name(self):
        """A user's ROS stack (docs/ros.md) is a method like ours on every page: legends, tables,
        the overlay's choice and names."""
        ros = self.ids["ros"]
        self.open("#/job/" + ros)
        charts = self.assert_charts_drew(5)
        for c in charts:
            self.assertEqual(c["legendItems"], ["enavi", "myplanner"], c["title"])
            self.assert_each_painted(c, {"mean"})
        methods = self.driver.execute_script(
            "return [...document.querySelectorAll('#main > table:first-of-type tbody tr')].map(r => r.children[2].textContent)")
        self.assertEqual(methods, ["enavi", "myplanner"])
        episodes = [e for e in json.load(urllib.request.urlopen(self.url + "/api/jobs/%s/episodes" % ros))]
        first = next(e["id"] for e in episodes if e["method"] == "myplanner" and e["seed"] == 1)
        self.open("#/episode/" + first)
        offered = self.driver.execute_script("return document.querySelector('#overlay-with select').selectedOptions[0].text")
        self.assertTrue(offered.startswith("enavi seed 1"), offered)
        self.driver.find_element("css selector", "#overlay-with button").click()
        self.wait_ready("return document.body.dataset.page === 'overlay'")
        charts = self.assert_charts_drew(8)
        self.assertEqual(charts[0]["legendItems"], ["A: myplanner", "B: enavi"])

    def test_a_job_no_connected_worker_can_run_says_why(self):
        """A ROS method's episodes wait for a worker that offers ros: the jobs list and the job's
        page say so, as `enavi status` does."""
        db = os.path.join(self.tmp, "pending.db")
        ros = json.loads(subprocess.check_output([SEED, db, "--pending-ros"], text=True))["ros"]
        proc, url = start([ENAVI, "serve", "--db", db, "--http", "127.0.0.1:0", "--domain", str(100 + (os.getpid() + 2) % 100),
                           "--partition", "browser-pending-%d" % os.getpid()], self.tmp, "serve-pending")
        try:
            self.driver.get(url + "/#/jobs")
            self.wait_ready("return document.querySelector('tr.job .waiting') !== null")
            row = self.driver.execute_script("return document.querySelector('tr.job[data-id=\"%s\"]').textContent" % ros)
            self.assertIn("waiting: 2 episode(s) need a worker with ros, and no connected worker has it", row)
            self.driver.get(url + "/#/job/" + ros)
            self.wait_ready("return document.getElementById('waiting') !== null")
            self.assertIn("2 episode(s) need a worker with ros",
                          self.driver.execute_script("return document.getElementById('waiting').textContent"))
        finally:
            proc.terminate()
            proc.wait(10)
        # A finished job waits for nothing.
        self.open("#/job/" + self.ids["ros"])
        self.assertEqual(self.driver.find_elements("id", "waiting"), [])

    def test_hostile_job_page_shows_the_name_as_text(self):
        self.open("#/job/" + self.ids["hostile"])
        self.assertEqual(self.driver.find_element("css selector", "h1 .job-name").text, HOSTILE)
        self.assertEqual(self.driver.execute_script("return document.querySelectorAll('img[src=x]').length"), 0)

    def test_episode_page_draws_time_series_that_zoom_together_and_show_values(self):
        from selenium.webdriver.common.action_chains import ActionChains
        from selenium.webdriver.support.ui import WebDriverWait
        self.open("#/episode/%s-00000" % self.ids["base"])
        WebDriverWait(self.driver, 15).until(lambda d: d.execute_script(
            "const i = document.querySelector('img.topdown'); return i && i.complete && i.naturalWidth > 0"))
        self.screenshot(self.shot("dashboard-episode.png"))
        charts = self.assert_charts_drew(5)
        self.assertEqual([c["title"] for c in charts],
                         ["speed (m/s)", "navigation CPU (% of a core)", "eci", "task frequencies (Hz)", "map resolution (m)"])
        for c in charts:
            series = [d for d in c["datasets"] if d["role"] == "series"]
            self.assertTrue(all(d["n"] == 50 for d in series), c)  # the synthetic flight's 50 samples
            # The replan event at 1 s: a dashed line from the bottom to the top of the plot.
            events = [d for d in c["datasets"] if d["role"] == "event"]
            self.assertEqual([(d["label"], d["n"]) for d in events], [("replan", 2)], c["title"])
        self.assertEqual(charts[3]["legendItems"], ["f_per", "f_col", "f_dif", "replan"])
        full = charts[0]["xRange"]
        # Drag across the middle of the speed chart: it and the flight's other charts zoom to it.
        canvas = self.driver.find_elements("css selector", "canvas.chart")[0]
        area = charts[0]["area"]
        y = (area["top"] + area["bottom"]) / 2
        x0 = area["left"] + 0.25 * (area["right"] - area["left"])
        x1 = area["left"] + 0.5 * (area["right"] - area["left"])
        self.driver.execute_script("arguments[0].scrollIntoView()", canvas)
        self.canvas_point(canvas, x0, y)
        ActionChains(self.driver).click_and_hold().pause(0.1).move_by_offset(int(x1 - x0), 0).pause(0.1).release().perform()
        zoomed = self.charts()
        lo, hi = zoomed[0]["xRange"]
        self.assertGreater(lo, full[0])
        self.assertLess(hi, full[1])
        self.assertLess(hi - lo, 0.4 * (full[1] - full[0]))
        for c in zoomed[1:]:
            self.assertEqual(c["xRange"], [lo, hi], c["title"])
        # Hover: the speed at the time under the cursor.
        self.canvas_point(canvas, (area["left"] + area["right"]) / 2, y)
        tip = self.tooltip(0)
        self.assertIsNotNone(tip, "no tooltip on hover")
        self.assertTrue(tip[0].startswith("t = "), tip)
        t = float(tip[0].split()[2])
        self.assertTrue(lo <= t <= hi, (t, lo, hi))
        self.assertRegex(tip[1][0], r"^\|v\|: [0-9.]+ m/s$")
        # A double-click goes back to the whole flight, on every chart.
        ActionChains(self.driver).pause(0.1).double_click().pause(0.1).perform()
        for c in self.charts():
            self.assertEqual(c["xRange"], full, c["title"])

    def test_a_flight_in_wind_with_noisy_odometry_charts_both_and_a_still_one_neither(self):
        self.open("#/episode/%s-00000" % self.ids["windy"])
        charts = self.assert_charts_drew(7)
        titles = [c["title"] for c in charts]
        self.assertEqual(titles[5:], ["wind speed at the vehicle (m/s)", "odometry error (m)"])
        for c in charts[5:]:
            series = [d for d in c["datasets"] if d["role"] == "series"]
            self.assertEqual([d["n"] for d in series], [50], c)
        self.open("#/episode/%s-00000" % self.ids["oneseed_base"])
        self.assertEqual(len(self.assert_charts_drew(5)), 5)

    def test_overlay_of_the_other_method_chosen_on_the_episode_page(self):
        base = self.ids["base"]
        self.open("#/episode/%s-00000" % base)
        # tx2 s1 seed 1: the other method's flight of the same seed is offered first.
        chosen = self.driver.execute_script("return document.querySelector('#overlay-with select').value")
        self.assertEqual(chosen, base + "-00003")
        self.driver.find_element("css selector", "#overlay-with button").click()
        self.wait_ready("return document.body.dataset.page === 'overlay'")
        self.assertEqual(self.driver.execute_script("return location.hash"),
                         "#/overlay?a=%s-00000&b=%s-00003" % (base, base))
        charts = self.assert_charts_drew(8)
        self.assertEqual(charts[0]["kind"], "paths")
        for c in charts:
            self.assertEqual(c["legendItems"], ["A: baseline", "B: enavi"], c["title"])
            self.assertEqual([d["n"] for d in c["datasets"]], [50, 50], c["title"])
        speed = next(c for c in charts if c["title"] == "speed (m/s)")
        self.assert_each_painted(speed, {"series"})  # E-Navi flew faster: both lines show
        # Hover lists both flights at that time.
        index = charts.index(speed)
        canvas = self.driver.find_elements("css selector", "canvas.chart")[index]
        area = speed["area"]
        self.driver.execute_script("arguments[0].scrollIntoView()", canvas)
        self.canvas_point(canvas, area["left"] + 0.3 * (area["right"] - area["left"]), (area["top"] + area["bottom"]) / 2)
        tip = self.tooltip(index)
        self.assertIsNotNone(tip, "no tooltip on hover")
        self.assertEqual([line.split(":")[0] for line in tip[1]], ["A", "B"], tip)

    def test_overlay_before_and_after_from_a_compare_pair(self):
        base, cand = self.ids["base"], self.ids["candidate"]
        self.open("#/overlay?a=%s-00000&b=%s-00000" % (base, cand), self.shot("dashboard-overlay.png"))
        charts = self.assert_charts_drew(8)
        # Names say what differs: the job (the same board, world, method and seed).
        self.assertEqual(charts[0]["legendItems"], ["A: " + base, "B: " + cand])
        rows = [r.text for r in self.driver.find_elements("css selector", "#main table tbody tr")]
        self.assertIn("36.10", rows[0])
        self.assertIn("48.13", rows[1])  # planner.v_max 1.5: slower
        speed = next(c for c in charts if c["title"] == "speed (m/s)")
        self.assert_each_painted(speed, {"series"})
        # The flight after the change is longer: its time axis reaches further.
        self.assertGreater(speed["xRange"][1], 48)

    def test_compare_page_lists_how_the_jobs_differ_before_the_metrics(self):
        self.open("#/compare?base=%s&candidate=%s" % (self.ids["base"], self.ids["candidate"]))
        rows = self.driver.execute_script(
            "return [...document.querySelectorAll('#spec-changes tbody tr')].map(r => [...r.children].map(c => c.textContent))")
        self.assertIn(["overrides.planner.v_max", "spec", "1 of 8", "(default)", "1.5"], rows)
        self.assertIn(["label.branch", "label", "whole job", "main", "feature"], rows)
        # Before the verdict and the matrix.
        order = self.driver.execute_script(
            "const a = document.getElementById('spec-changes'), b = document.querySelector('p.verdict');"
            "return !!(a.compareDocumentPosition(b) & Node.DOCUMENT_POSITION_FOLLOWING)")
        self.assertTrue(order)
        # The same job on both sides: nothing differs, and the page says so.
        self.open("#/compare?base=%s&candidate=%s" % (self.ids["base"], self.ids["base"]))
        self.assertIn("the two jobs' specs, labels and server builds are the same",
                      self.driver.find_element("id", "spec-changes").text)

    def test_compare_page_highlights_the_planted_regression_and_overlays_flights(self):
        self.open("#/compare?base=%s&candidate=%s" % (self.ids["base"], self.ids["candidate"]))
        cells = self.driver.execute_script(
            "return [...document.querySelectorAll('td.cell')].map(c => [c.dataset.board, c.dataset.scenario, c.dataset.verdict])")
        self.assertEqual(len(cells), 4, cells)
        for board, scenario, verdict in cells:
            expected = "regression" if (board, scenario) == ("tx2", "s1") else "same"
            self.assertEqual(verdict, expected, (board, scenario))
        self.assertEqual(self.driver.find_element("css selector", "p.verdict").get_attribute("data-verdict"), "regression")
        # The planted cell also flew on another cost model: the page says so above the matrix.
        row = self.driver.find_element("css selector", "#provenance tr[data-name='cost_model_sha256']").text
        self.assertIn("1 of 8", row)
        self.assertIn("fake-revision-2", row)
        self.assertIn("re-pricing", row)
        self.driver.find_element("css selector", "td.cell.regression").click()
        from selenium.webdriver.support.ui import WebDriverWait
        WebDriverWait(self.driver, 15).until(
            lambda d: d.execute_script("return document.querySelectorAll('#detail canvas.chart').length") == 2)
        detail = self.driver.find_element("id", "detail").text
        self.assertIn("flight_time_s", detail)
        self.assertIn("regression", detail)
        charts = self.assert_charts_drew(2, "#detail canvas.chart")
        self.assertEqual([c["kind"] for c in charts], ["paths", "timeseries"])
        self.assert_each_painted(charts[1], {"series"})
        self.screenshot(self.shot("dashboard-compare.png"))
        # Each seed pair links its overlay.
        links = self.driver.execute_script("return [...document.querySelectorAll('#detail p.pairs a')].map(a => a.hash)")
        self.assertIn("#/overlay?a=%s-00000&b=%s-00000" % (self.ids["base"], self.ids["candidate"]), links)

    def test_compare_page_says_what_exact_mode_cannot_tell_and_links_the_paired_test(self):
        self.open("#/compare?base=%s&candidate=%s" % (self.ids["base"], self.ids["candidate"]))
        note = self.driver.find_element("id", "mode-note").text
        self.assertIn("exact mode", note)
        self.assertIn("with 2-3 seeds", note)  # pi4b s3 enavi seed 2 failed in both jobs
        self.assertIn("draw", note)
        self.assertIn("0 of the 1 regressions with a paired 95 % interval", note)
        self.driver.find_element("css selector", "#mode-note a").click()
        self.wait_ready("return location.hash.includes('mode=paired')")
        self.assertIn("paired mode: 1 regressions", self.driver.find_element("css selector", "p.verdict").text)
        self.assertIn("2-3 seed pairs per cell", self.driver.find_element("id", "mode-note").text)
        self.assertEqual(self.driver.execute_script("return document.querySelector('select[name=mode]').value"), "paired")
        verdicts = self.driver.execute_script(
            "return [...document.querySelectorAll('td.cell')].map(c => [c.dataset.board, c.dataset.scenario, c.dataset.verdict])")
        self.assertEqual(len(verdicts), 4, verdicts)
        for board, scenario, verdict in verdicts:
            self.assertEqual(verdict, "regression" if (board, scenario) == ("tx2", "s1") else "same", (board, scenario))
        # The mode survives a new pick in the form.
        self.driver.find_element("css selector", "form.inline button").click()
        self.wait_ready()
        self.assertIn("mode=paired", self.driver.execute_script("return location.hash"))

    def test_compare_with_one_seed_pair_cannot_judge_in_paired_mode(self):
        base, cand = self.ids["oneseed_base"], self.ids["oneseed_candidate"]
        self.open("#/compare?base=%s&candidate=%s&mode=paired" % (base, cand))
        verdict = self.driver.find_element("css selector", "p.verdict")
        self.assertEqual(verdict.get_attribute("data-verdict"), "cannot_judge")
        self.assertTrue(verdict.text.startswith("CANNOT JUDGE"), verdict.text)
        note = self.driver.find_element("id", "cannot-judge").text
        self.assertIn("1 metric(s) in 1 cell(s) got worse beyond their threshold", note)
        self.assertIn("paired mode needs 2 or more seed pairs per cell", note)
        cells = self.driver.execute_script("return [...document.querySelectorAll('td.cell')].map(c => c.dataset.verdict)")
        self.assertEqual(cells, ["undecided"])
        # The override that made it is listed first.
        self.assertIn("overrides.planner.v_max", self.driver.find_element("id", "spec-changes").text)
        # Both jobs are on the virtual clock with the cost model: exact mode applies, and is linked.
        self.driver.find_element("css selector", "#cannot-judge a").click()
        self.wait_ready("return location.hash.includes('mode=exact')")
        self.assertEqual(self.driver.find_element("css selector", "p.verdict").get_attribute("data-verdict"), "regression")
        note = self.driver.find_element("id", "mode-note").text
        self.assertIn("1 of the 1 are in cells of one seed pair: no interval", note)
        self.assertNotIn("have a paired 95 % interval that includes 0", note)

    def test_compare_by_label_series_takes_its_last_two_jobs(self):
        self.open("#/compare?label=suite%3Dnightly")
        self.assertEqual(len(self.driver.find_elements("css selector", "td.cell.regression")), 1)

    def test_trend_page_draws_the_label_series_per_board(self):
        self.open("#/trend?label=suite%3Dnightly&metric=flight_time_s", self.shot("dashboard-trend.png"))
        charts = self.assert_charts_drew(1)
        self.assertEqual(charts[0]["legendItems"], ["pi4b", "tx2"])
        self.assert_each_painted(charts[0], {"mean"})
        # One method at a time (the first, baseline), each mean with its 95 % interval over seeds:
        # a bar per job and board.
        self.assertEqual(self.driver.execute_script("return document.querySelector('select[name=method]').value"),
                         "baseline")
        self.assertEqual(sorted((d["role"], d["n"]) for d in charts[0]["datasets"]),
                         [("ci", 2), ("ci", 2), ("mean", 2), ("mean", 2)])
        self.assertIn("95 % interval", self.driver.find_element("id", "trend-note").text)
        cells = self.driver.execute_script("return [...document.querySelectorAll('tbody td.num')].map(t => t.textContent)")
        self.assertEqual(sum("±" in c for c in cells), 4, cells)
        # The planted regression (tx2 s1 baseline slower in the second job) moves tx2's mean.
        tx2 = self.driver.execute_script(
            "return [...document.querySelectorAll('tbody tr')].map(r => r.children[5].textContent)")
        first, second = (float(t.split(" ")[0]) for t in tx2)
        self.assertGreater(second, first)
        self.driver.execute_script("document.querySelector('select[name=method]').value = 'enavi'")
        self.driver.find_element("css selector", "form.inline button").click()
        self.wait_ready("return location.hash.includes('method=enavi')")
        self.assertIn("enavi", self.charts()[0]["title"])

    def test_spread_and_interval_stop_at_the_metrics_bounds(self):
        # crashes-1: one of 7 flights collides with 400 deadline misses. Its mean ± std of success
        # passes 1, of collided and deadline_misses 0; the charts stop them at the bounds.
        crashes = self.ids["crashes"]
        with urllib.request.urlopen(self.url + "/api/jobs/%s/summary?limit=1000" % crashes) as r:
            st = json.load(r)["cells"][0]["metrics"]
        self.assertGreater(st["success"]["mean"] + st["success"]["std"], 1, st["success"])
        for m in ("collided", "deadline_misses"):
            self.assertLess(st[m]["mean"] - st[m]["std"], 0, st[m])
        self.open("#/job/" + crashes)
        charts = self.assert_charts_drew(5)
        self.assertEqual(self.assert_within_metric_bounds(charts), len(charts))
        boxes = {c["title"].split(" ")[0]: next(d for d in c["datasets"] if d["role"] == "box") for c in charts}
        self.assertEqual(boxes["success"]["high"], 1.0)
        self.assertEqual(boxes["collided"]["low"], 0.0)
        self.assertEqual(boxes["deadline_misses"]["low"], 0.0)
        # The success rate's 95 % interval over the 7 seeds reaches past 1 too.
        with urllib.request.urlopen(self.url + "/api/trend?label=suite%3Dcrashes&metric=success") as r:
            point = json.load(r)["points"][0]
        self.assertGreater(point["mean"] + point["ci95"], 1, point)
        self.open("#/trend?label=suite%3Dcrashes&metric=success")
        charts = self.assert_charts_drew(1)
        self.assertEqual(self.assert_within_metric_bounds(charts), 1)
        self.assertEqual(next(d for d in charts[0]["datasets"] if d["role"] == "ci")["high"], 1.0)

    def test_trend_of_one_job_draws_its_point(self):
        self.open("#/trend?label=suite%3Dhostile&metric=flight_time_s")
        charts = self.assert_charts_drew(1)
        means = [d for d in charts[0]["datasets"] if d["role"] == "mean"]
        self.assertEqual([(d["label"], d["n"], d["inside"]) for d in means], [("x86", 1, 1)])
        self.assert_each_painted(charts[0], {"mean"})
        # One seed: no interval, and the tooltip says so.
        self.assertEqual([d["n"] for d in charts[0]["datasets"] if d["role"] == "ci"], [0])
        area = charts[0]["area"]
        canvas = self.driver.find_element("css selector", "canvas.chart")
        self.canvas_point(canvas, (area["left"] + area["right"]) / 2, (area["top"] + area["bottom"]) / 2)
        tip = self.tooltip(0)
        self.assertIsNotNone(tip, "no tooltip on hover")
        self.assertIn(HOSTILE, tip[0])  # the job's name, drawn as text on the canvas
        self.assertEqual(len(tip[1]), 1, tip)
        self.assertIn("one seed: no interval", tip[1][0])

    def test_label_filters_in_the_api_and_the_cli(self):
        with urllib.request.urlopen(self.url + "/api/jobs?label=suite=nightly") as r:
            self.assertEqual(sorted(j["name"] for j in json.load(r)), ["nightly-1", "nightly-2"])
        with urllib.request.urlopen(self.url + "/api/jobs?label=suite=nightly&label=branch=feature") as r:
            self.assertEqual([j["name"] for j in json.load(r)], ["nightly-2"])
        out = subprocess.run([ENAVI, "status", "--label", "suite=hostile", "--server", self.url],
                             capture_output=True, text=True, check=True).stdout
        self.assertIn(HOSTILE, out)
        self.assertNotIn("nightly", out)
        bad = subprocess.run([ENAVI, "status", "--label", "Suite=x y", "--server", self.url],
                             capture_output=True, text=True)
        self.assertEqual(bad.returncode, 2, bad.stderr)
        self.assertIn("--label", bad.stderr)

    def test_read_only_dashboard_serves_pages_and_refuses_writes(self):
        db = os.path.join(self.tmp, "copy.db")
        shutil.copy(os.path.join(self.tmp, "farm.db"), db)
        proc, url = start([ENAVI, "dashboard", "--db", db, "--http", "127.0.0.1:0"], self.tmp, "dashboard")
        try:
            with urllib.request.urlopen(url + "/") as r:
                self.assertIn("/static/app.js", r.read().decode())
            with urllib.request.urlopen(url + "/api/health") as r:
                self.assertTrue(json.load(r)["read_only"])
            with urllib.request.urlopen(url + "/api/workers") as r:
                self.assertEqual([w["alive"] for w in json.load(r)], [False])
            with self.assertRaises(urllib.error.HTTPError) as refused:
                urllib.request.urlopen(urllib.request.Request(url + "/api/jobs", data=b"x", method="POST"))
            self.assertEqual(refused.exception.code, 405)
        finally:
            proc.terminate()
            proc.wait(10)

    def test_eval_dashboard_serves_the_embedded_farm_until_ctrl_c(self):
        import re
        import signal
        proc = subprocess.Popen(
            [ENAVI, "eval", "--boards", "tx2", "--scenarios", "s1", "--seeds", "2", "--workers", "1",
             "--episode-cmd", os.path.join(BUILD, "tests", "fake_episode"), "--dashboard",
             "--domain", str(100 + (os.getpid() + 1) % 100)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            url, lines = None, []
            deadline = time.time() + 60
            while time.time() < deadline:
                line = proc.stderr.readline()
                if not line:
                    break
                lines.append(line)
                m = re.match(r"dashboard: (http://\S+)/", line)
                if m:
                    url = m.group(1)
                if "keeps serving until Ctrl-C" in line:
                    break
            self.assertIsNotNone(url, "".join(lines))
            with urllib.request.urlopen(url + "/api/jobs") as r:
                jobs = json.load(r)
            self.assertEqual([(j["state"], j["done"]) for j in jobs], [("done", 4)], jobs)
            with urllib.request.urlopen(url + "/") as r:
                self.assertIn("/static/app.js", r.read().decode())
            proc.send_signal(signal.SIGINT)
            out, _ = proc.communicate(timeout=30)
            self.assertEqual(proc.returncode, 0)
            self.assertIn("tx2", out)  # the table was printed before serving on
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


@unittest.skipUnless(SHOTS and SHOT_DB, "screenshots of real flights: ENAVI_SCREENSHOT_DIR and ENAVI_SCREENSHOT_DB")
class RealFlightScreenshots(PageChecks, unittest.TestCase):
    """docs/dashboard.md's screenshots, of a database of real flights served by `enavi dashboard`
    (read-only): the jobs page, the oldest job and its first episode, an overlay of that job's
    first two flights of one board, world and seed by different methods, the oldest two jobs
    compared in paired mode with their worst cell opened, and the oldest job's first label as a
    trend. Each page's charts are checked as the seeded database's are."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="enavi-shots-")
        db = os.path.join(cls.tmp, "shots.db")
        shutil.copy(SHOT_DB, db)
        cls.server, cls.url = start([ENAVI, "dashboard", "--db", db, "--http", "127.0.0.1:0"], cls.tmp, "dashboard")
        cls.driver = chromium(cls.tmp)

    @classmethod
    def tearDownClass(cls):
        cls.driver.quit()
        cls.server.terminate()
        cls.server.wait(10)
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def get(self, path):
        with urllib.request.urlopen(self.url + path) as r:
            return json.load(r)

    def test_screenshots(self):
        from selenium.webdriver.support.ui import WebDriverWait
        jobs = self.get("/api/jobs")
        self.assertGreaterEqual(len(jobs), 2, "the database needs two jobs to compare")
        first = jobs[0]["id"]
        self.open("#/jobs", "dashboard-jobs.png")
        self.open("#/job/" + first, "dashboard-job.png")
        self.assertEqual(self.assert_within_metric_bounds(self.assert_charts_drew(5)), len(self.charts()))

        episodes = [e for e in self.get("/api/jobs/%s/episodes" % first) if e["state"] == "done"]
        self.open("#/episode/" + episodes[0]["id"])
        WebDriverWait(self.driver, 30).until(lambda d: d.execute_script(
            "const i = document.querySelector('img.topdown'); return i && i.complete && i.naturalWidth > 0"))
        self.assert_charts_drew(5)
        self.screenshot("dashboard-episode.png")

        a = episodes[0]
        b = next(e for e in episodes if (e["board"], e["world"], e["seed"]) == (a["board"], a["world"], a["seed"])
                 and e["method"] != a["method"])
        self.open("#/overlay?a=%s&b=%s" % (a["id"], b["id"]), "dashboard-overlay.png")
        self.assert_charts_drew(8)

        self.open("#/compare?base=%s&candidate=%s&mode=paired" % (first, jobs[1]["id"]))
        worst = self.driver.execute_script(
            "const rank = ['regression', 'undecided', 'improvement', 'change'];"
            "const cells = [...document.querySelectorAll('td.cell')];"
            "for (const v of rank) { const c = cells.find(c => c.dataset.verdict === v); if (c) return c.dataset.verdict; }"
            "return cells.length ? cells[0].dataset.verdict : null")
        self.driver.find_element("css selector", "td.cell[data-verdict='%s']" % worst).click()
        WebDriverWait(self.driver, 30).until(
            lambda d: d.execute_script("return document.querySelectorAll('#detail canvas.chart').length") == 2)
        self.assert_charts_drew(2, "#detail canvas.chart")
        self.screenshot("dashboard-compare.png", max_height=4000)  # the cell's metrics, then both flights

        label = sorted(jobs[0]["labels"].items())[0]
        self.open("#/trend?label=%s&metric=flight_time_s" % urllib.parse.quote("%s=%s" % label), "dashboard-trend.png")
        self.assertEqual(self.assert_within_metric_bounds(self.assert_charts_drew(1)), 1)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]], verbosity=2)
