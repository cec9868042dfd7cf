#!/usr/bin/env python3
"""`enavi compare` end to end on a seeded database (seed_dashboard_db): the planted regression
exits 3 and names its cell and metric; the same job twice exits 0 with "no change"; the JUnit
output passes a JUnit XML schema (xmllint, libxml2-utils); JSON parses and matches the table;
bad input exits 2 naming the file, field and reason; `enavi trend` prints each job and method
with its interval, the same from the database and through a server.
Usage: compare_cli_test.py BUILD_DIR SOURCE_DIR
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

BUILD, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
ENAVI = os.path.join(BUILD, "bin", "enavi")
SCHEMA = os.path.join(SOURCE, "tests", "browser", "junit.xsd")


class CompareCliTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="enavi-compare-")
        cls.db = os.path.join(cls.tmp, "farm.db")
        cls.ids = json.loads(subprocess.check_output([os.path.join(BUILD, "tests", "seed_dashboard_db"), cls.db],
                                                     text=True))
        cls.base = cls.db + ":" + cls.ids["base"]
        cls.candidate = cls.db + ":" + cls.ids["candidate"]

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def compare(self, *args):
        return subprocess.run([ENAVI, "compare", *args], capture_output=True, text=True, timeout=60)

    def test_planted_regression_exits_3_and_names_cell_and_metric(self):
        r = self.compare(self.base, self.candidate)
        self.assertEqual(r.returncode, 3, r.stdout + r.stderr)
        self.assertIn("tx2/s1/baseline", r.stdout)
        self.assertRegex(r.stdout, r"REGRESSION\s+flight_time_s 36.2 -> 48.2667 \(\+12.0667, \+33.3%\)")
        self.assertIn("REGRESSION: 1 metric(s) in 1 cell(s) got worse", r.stdout)
        # That cell also flew on another cost model (planted): named above the cells, and in the verdict.
        self.assertIn("cost_model_sha256 in 1 of 8 cells: (none) -> fake-revision-2", r.stdout)
        self.assertIn("(with another cost model: see provenance above)", r.stdout)
        # Exact mode lists the changed episodes, and only cells that changed are printed.
        self.assertIn("changed episodes: seed 1", r.stdout)
        self.assertNotIn("pi4b/", r.stdout)

    def test_same_job_twice_exits_0_no_change(self):
        r = self.compare(self.base, self.base)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("no change", r.stdout)

    def test_reverse_direction_is_an_improvement_not_a_regression(self):
        r = self.compare(self.candidate, self.base)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertRegex(r.stdout, r"IMPROVEMENT\s+flight_time_s")

    def test_junit_output_passes_the_junit_schema(self):
        r = self.compare(self.base, self.candidate, "--format", "junit")
        self.assertEqual(r.returncode, 3, r.stderr)
        report = os.path.join(self.tmp, "compare.xml")
        with open(report, "w") as f:
            f.write(r.stdout)
        check = subprocess.run(["xmllint", "--noout", "--schema", SCHEMA, report], capture_output=True, text=True)
        self.assertEqual(check.returncode, 0, check.stderr)
        self.assertIn('failures="1"', r.stdout)
        self.assertIn('<failure message="flight_time_s regressed" type="regression">', r.stdout)
        # The schema check can fail: a report without the required attributes does not pass.
        broken = os.path.join(self.tmp, "broken.xml")
        with open(broken, "w") as f:
            f.write(re.sub(r'(<testsuite name="[^"]*") tests="\d+"', r"\1", r.stdout, count=1))
        self.assertNotEqual(subprocess.run(["xmllint", "--noout", "--schema", SCHEMA, broken],
                                           capture_output=True).returncode, 0)

    def test_json_output_carries_every_cell_and_exact_deltas(self):
        r = self.compare(self.base, self.candidate, "--format", "json")
        report = json.loads(r.stdout)
        self.assertEqual(report["mode"], "exact")
        self.assertEqual(report["regressions"], 1)
        self.assertEqual(len(report["cells"]), 8)
        cell = next(c for c in report["cells"] if (c["board"], c["scenario"], c["method"]) == ("tx2", "s1", "baseline"))
        ft = next(m for m in cell["metrics"] if m["name"] == "flight_time_s")
        self.assertAlmostEqual(ft["delta"], 36.2 / 3, places=9)
        self.assertEqual(ft["changed_pairs"], 3)
        self.assertEqual(ft["verdict"], "regression")
        # Deterministic: the same comparison twice gives the same bytes.
        self.assertEqual(r.stdout, self.compare(self.base, self.candidate, "--format", "json").stdout)

    def test_threshold_file_changes_the_verdict(self):
        loose = os.path.join(self.tmp, "loose.yaml")
        with open(loose, "w") as f:
            f.write("metrics:\n  flight_time_s: {rel: 0.5}\n")
        r = self.compare(self.base, self.candidate, "--thresholds", loose)
        self.assertEqual(r.returncode, 0, r.stdout)
        self.assertRegex(r.stdout, r"CHANGE\s+flight_time_s")

    def test_bad_input_exits_2_naming_file_field_and_reason(self):
        bad = os.path.join(self.tmp, "bad.yaml")
        with open(bad, "w") as f:
            f.write("metrics:\n  flight_time_s:\n    rel: -1\n")
        r = self.compare(self.base, self.candidate, "--thresholds", bad)
        self.assertEqual(r.returncode, 2)
        self.assertIn(bad + ":3: metrics.flight_time_s.rel: must be >= 0.0 (got -1)", r.stderr)
        r = self.compare(self.db, self.base)
        self.assertEqual(r.returncode, 2)
        self.assertIn("holds 8 jobs; name one as", r.stderr)  # seed_dashboard_db's eight
        r = self.compare(self.db + ":jnope", self.base)
        self.assertEqual(r.returncode, 2)
        self.assertIn("has no job 'jnope'", r.stderr)

    def trend(self, *args):
        return subprocess.run([ENAVI, "trend", *args], capture_output=True, text=True, timeout=60)

    def test_trend_prints_each_job_and_method_with_its_interval_from_the_database_and_the_server(self):
        r = self.trend("--label", "suite=nightly", "--db", self.db)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        rows = [line.split() for line in r.stdout.splitlines() if line[:1].isdigit()]
        # 2 jobs x 2 methods, tx2 and pi4b columns, each a mean ± its interval.
        self.assertEqual([(row[0], row[3]) for row in rows],
                         [("1", "baseline"), ("1", "enavi"), ("2", "baseline"), ("2", "enavi")], r.stdout)
        for row in rows:
            self.assertEqual(row[4:].count("±"), 2, row)
        # The planted regression: tx2 baseline slower in the second job (tx2 is the last column).
        self.assertGreater(float(rows[2][-3]), float(rows[0][-3]))
        only = self.trend("--label", "suite=nightly", "--db", self.db, "--method", "enavi", "--format", "json")
        self.assertEqual(only.returncode, 0, only.stderr)
        points = json.loads(only.stdout)["points"]
        self.assertTrue(all(p["ci95"] is not None and p["ci95"] > 0 for p in points), points)
        # The same through a server (the read-only dashboard of the same database).
        ready = os.path.join(self.tmp, "trend.ready")
        server = subprocess.Popen([ENAVI, "dashboard", "--db", self.db, "--http", "127.0.0.1:0", "--ready-file", ready],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            for _ in range(200):
                if os.path.exists(ready) and open(ready).read().strip():
                    break
                time.sleep(0.05)
            via = self.trend("--label", "suite=nightly", "--server", open(ready).read().strip())
            self.assertEqual(via.returncode, 0, via.stderr)
            self.assertEqual(via.stdout, r.stdout)
        finally:
            server.terminate()
            server.wait(10)

    def test_trend_bad_input_exits_2_naming_the_flag(self):
        for args, message in ((["--label", "nolabel", "--db", self.db], "--label: 'nolabel': expected key=value"),
                              (["--label", "suite=nightly", "--db", self.db, "--metric", "a'b"], "metric: 'a'b'"),
                              (["--label", "suite=nightly", "--db", self.db + ".missing"], "no such database file")):
            r = self.trend(*args)
            self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
            self.assertIn(message, r.stderr)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]], verbosity=2)
