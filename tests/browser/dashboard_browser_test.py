#!/usr/bin/env python3
"""The dashboard in a real browser: headless Chromium (Debian's chromium + chromium-driver)
driven by Selenium loads every page from a running `enavi serve` on loopback, over a database
seeded by seed_dashboard_db, and checks that

  - every chart drew (each svg.chart holds marks: paths, dots, boxes),
  - the compare page colours exactly the planted regression (tx2 x s1) as a regression and a
    click on it overlays both flights; in exact mode it says a difference over few seeds can be a
    draw and links the paired test, which finds the same regression,
  - the job named <img src=x onerror=alert(1)> shows as that text (no element, no alert),
  - the bird's-eye PNG loaded,
  - `enavi status --label` and GET /api/jobs?label= filter by label,
  - `enavi dashboard --db` serves the same pages read-only (POST: 405).

ENAVI_SCREENSHOT_DIR=DIR saves a screenshot of each page there (docs/img for docs/dashboard.md).
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
import urllib.request

BUILD, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
ENAVI = os.path.join(BUILD, "bin", "enavi")
SEED = os.path.join(BUILD, "tests", "seed_dashboard_db")
HOSTILE = "<img src=x onerror=alert(1)>"


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
    return proc, open(ready).read().strip()


class DashboardBrowserTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service

        cls.tmp = tempfile.mkdtemp(prefix="enavi-browser-")
        db = os.path.join(cls.tmp, "farm.db")
        cls.ids = json.loads(subprocess.check_output([SEED, db], text=True))
        # A private DDS domain and partition: the server must not meet other tests' workers.
        cls.server, cls.url = start(
            [ENAVI, "serve", "--db", db, "--http", "127.0.0.1:0", "--domain", str(100 + os.getpid() % 100),
             "--partition", "browser-%d" % os.getpid()], cls.tmp, "serve")
        options = webdriver.ChromeOptions()
        for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                    "--window-size=1300,1000", "--user-data-dir=" + os.path.join(cls.tmp, "chrome")):
            options.add_argument(arg)
        options.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
        service = Service(shutil.which("chromedriver") or "/usr/bin/chromedriver")
        cls.driver = webdriver.Chrome(service=service, options=options)
        cls.driver.set_page_load_timeout(20)
        cls.shots = os.environ.get("ENAVI_SCREENSHOT_DIR")

    @classmethod
    def tearDownClass(cls):
        cls.driver.quit()
        cls.server.terminate()
        cls.server.wait(10)
        shutil.rmtree(cls.tmp, ignore_errors=True)

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
        if shot and self.shots:
            self.driver.save_screenshot(os.path.join(self.shots, shot))

    def assert_charts_drew(self, at_least):
        charts = self.driver.execute_script(
            "return [...document.querySelectorAll('svg.chart')].map(s => ["
            "s.querySelector('text') ? s.querySelector('text').textContent : '',"
            "s.querySelectorAll('.mark').length, s.getBoundingClientRect().width])")
        self.assertGreaterEqual(len(charts), at_least, charts)
        for title, marks, width in charts:
            self.assertGreater(marks, 0, "chart '%s' drew nothing" % title)
            self.assertGreater(width, 0, "chart '%s' has no size" % title)

    def test_jobs_page_lists_jobs_labels_and_escapes_the_hostile_name(self):
        self.open("#/jobs", "dashboard-jobs.png")
        names = [e.text for e in self.driver.find_elements("css selector", "td.job-name")]
        self.assertIn("nightly-1", names)
        self.assertIn(HOSTILE, names)  # the characters, as text
        self.assertEqual(self.driver.execute_script("return document.querySelectorAll('img[src=x]').length"), 0)
        labels = [e.text for e in self.driver.find_elements("css selector", "span.label")]
        self.assertIn("suite=nightly", labels)
        self.assertIn("workers", self.driver.page_source.lower())
        # An alert would have been raised by now and fail any further command.
        self.assertEqual(self.driver.title, "E-Navi Farm")

    def test_job_page_draws_a_chart_per_metric_and_lists_the_failure(self):
        self.open("#/job/" + self.ids["base"], "dashboard-job.png")
        self.assert_charts_drew(5)
        reasons = [e.text for e in self.driver.find_elements("css selector", "td.reason")]
        self.assertTrue(any("exited with code 3" in r for r in reasons), reasons)
        self.assertIn("1–23 of 23", self.driver.find_element("id", "results").text)

    def test_hostile_job_page_shows_the_name_as_text(self):
        self.open("#/job/" + self.ids["hostile"])
        self.assertEqual(self.driver.find_element("css selector", "h1 .job-name").text, HOSTILE)
        self.assertEqual(self.driver.execute_script("return document.querySelectorAll('img[src=x]').length"), 0)

    def test_episode_page_draws_time_series_and_the_birds_eye_view(self):
        self.open("#/episode/%s-00000" % self.ids["base"])
        from selenium.webdriver.support.ui import WebDriverWait
        WebDriverWait(self.driver, 15).until(lambda d: d.execute_script(
            "const i = document.querySelector('img.topdown'); return i && i.complete && i.naturalWidth > 0"))
        if self.shots:
            self.driver.save_screenshot(os.path.join(self.shots, "dashboard-episode.png"))
        self.assert_charts_drew(5)
        events = self.driver.execute_script("return document.querySelectorAll('svg.chart .event').length")
        self.assertGreater(events, 0, "events are not on the time axis")

    def test_compare_page_highlights_the_planted_regression_and_overlays_flights(self):
        self.open("#/compare?base=%s&candidate=%s" % (self.ids["base"], self.ids["candidate"]))
        cells = self.driver.execute_script(
            "return [...document.querySelectorAll('td.cell')].map(c => [c.dataset.board, c.dataset.scenario, c.dataset.verdict])")
        self.assertEqual(len(cells), 4, cells)
        for board, scenario, verdict in cells:
            expected = "regression" if (board, scenario) == ("tx2", "s1") else "same"
            self.assertEqual(verdict, expected, (board, scenario))
        # The planted cell also flew on another cost model: the page says so above the matrix.
        row = self.driver.find_element("css selector", "#provenance tr[data-name='cost_model_sha256']").text
        self.assertIn("1 of 8", row)
        self.assertIn("fake-revision-2", row)
        self.assertIn("re-pricing", row)
        self.driver.find_element("css selector", "td.cell.regression").click()
        from selenium.webdriver.support.ui import WebDriverWait
        WebDriverWait(self.driver, 15).until(
            lambda d: d.execute_script("return document.querySelectorAll('#detail svg.chart').length") == 2)
        detail = self.driver.find_element("id", "detail").text
        self.assertIn("flight_time_s", detail)
        self.assertIn("regression", detail)
        self.assert_charts_drew(2)
        if self.shots:
            self.driver.save_screenshot(os.path.join(self.shots, "dashboard-compare.png"))

    def test_compare_page_says_what_exact_mode_cannot_tell_and_links_the_paired_test(self):
        self.open("#/compare?base=%s&candidate=%s" % (self.ids["base"], self.ids["candidate"]))
        note = self.driver.find_element("id", "mode-note").text
        self.assertIn("exact mode", note)
        self.assertIn("with 2-3 seeds", note)  # pi4b s3 enavi seed 2 failed in both jobs
        self.assertIn("draw", note)
        self.driver.find_element("css selector", "#mode-note a").click()
        from selenium.webdriver.support.ui import WebDriverWait
        WebDriverWait(self.driver, 15).until(lambda d: d.execute_script(
            "return location.hash.includes('mode=paired') && document.body.dataset.ready === location.hash"))
        self.assertTrue(self.driver.find_element("css selector", "p.verdict").text.startswith("paired mode: 1 regressions"))
        self.assertIn("2-3 seed pairs per cell", self.driver.find_element("id", "mode-note").text)
        self.assertEqual(self.driver.execute_script("return document.querySelector('select[name=mode]').value"), "paired")
        verdicts = self.driver.execute_script(
            "return [...document.querySelectorAll('td.cell')].map(c => [c.dataset.board, c.dataset.scenario, c.dataset.verdict])")
        self.assertEqual(len(verdicts), 4, verdicts)
        for board, scenario, verdict in verdicts:
            self.assertEqual(verdict, "regression" if (board, scenario) == ("tx2", "s1") else "same", (board, scenario))
        # The mode survives a new pick in the form.
        self.driver.find_element("css selector", "form.inline button").click()
        WebDriverWait(self.driver, 15).until(lambda d: d.execute_script("return document.body.dataset.ready === location.hash"))
        self.assertIn("mode=paired", self.driver.execute_script("return location.hash"))

    def test_compare_by_label_series_takes_its_last_two_jobs(self):
        self.open("#/compare?label=suite%3Dnightly")
        self.assertEqual(len(self.driver.find_elements("css selector", "td.cell.regression")), 1)

    def test_trend_page_draws_the_label_series_per_board(self):
        self.open("#/trend?label=suite%3Dnightly&metric=flight_time_s", "dashboard-trend.png")
        self.assert_charts_drew(1)
        legend = self.driver.execute_script(
            "return [...document.querySelectorAll('svg.chart text')].map(t => t.textContent)")
        self.assertIn("tx2", legend)
        self.assertIn("pi4b", legend)
        # One method at a time (the first, baseline), each mean with its 95 % interval over seeds:
        # a bar per job and board.
        self.assertEqual(self.driver.execute_script("return document.querySelector('select[name=method]').value"),
                         "baseline")
        self.assertEqual(self.driver.execute_script("return document.querySelectorAll('svg.chart .ci').length"), 4)
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
        from selenium.webdriver.support.ui import WebDriverWait
        WebDriverWait(self.driver, 15).until(lambda d: d.execute_script(
            "return location.hash.includes('method=enavi') && document.body.dataset.ready === location.hash"))
        self.assertIn("enavi", self.driver.find_element("css selector", "svg.chart text").text)

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


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]], verbosity=2)
