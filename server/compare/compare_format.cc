// The compare report's three forms: JSON (the API's and the dashboard's), a table for people and
// JUnit XML for CI servers. Each lists how the jobs differ before any metric.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "server/compare/compare.h"

namespace enavi::server {
namespace {

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string Xml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        // XML 1.0 forbids most control characters even as references.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') {
          out += '?';
        } else {
          out += c;
        }
    }
  }
  return out;
}

std::string CellName(const CellChange& c) { return c.board + "/" + c.scenario + "/" + c.method; }

std::string Describe(const MetricChange& m, bool exact) {
  std::string s = m.name + " " + Num(m.base_mean) + " -> " + Num(m.candidate_mean) + " (" +
                  (m.delta >= 0 ? "+" : "") + Num(m.delta);
  if (m.base_mean != 0) {
    char pct[32];
    std::snprintf(pct, sizeof pct, ", %+.1f%%", 100.0 * m.delta / std::abs(m.base_mean));
    s += pct;
  }
  s += ")";
  if (!exact && m.has_interval) {
    s += " 95% CI [" + Num(m.ci_low) + ", " + Num(m.ci_high) + "]";
  } else if (!exact && m.direction != Direction::kNone) {
    s += " no 95% CI from " + std::to_string(m.pairs) + " pair";
  }
  if (m.within_draw) s += " within the seeds' draw (paired 95% CI [" + Num(m.ci_low) + ", " + Num(m.ci_high) + "])";
  if (m.direction == Direction::kNone) {
    s += ", not judged";
  } else {
    s += ", threshold " + Num(m.threshold) + ", " + DirectionName(m.direction) + " is better";
  }
  s += ", " + std::to_string(m.pairs) + " pairs";
  return s;
}

// "a, b, c (+N more)": a few values each (a job holds one cost model digest per board and cost family).
std::string Values(const std::vector<std::string>& v) {
  std::string out;
  for (std::size_t i = 0; i < v.size() && i < 3; ++i) out += (i ? ", " : "") + v[i];
  return v.size() > 3 ? out + " (+" + std::to_string(v.size() - 3) + " more)" : out;
}

// One line of how the jobs differ: "overrides.planner.v_max in 2 of 4 cells: (default) -> 1".
std::string SpecChangeText(const SpecChange& s, int cells) {
  std::string where = s.kind == "spec" ? " in " + std::to_string(s.cells) + " of " + std::to_string(cells) + " cells" : "";
  return s.name + where + ": " + Values(s.base_values) + " -> " + Values(s.candidate_values);
}

// The job as the header names it: "a.db:j1 ('eval', 4 results)".
std::string JobText(const std::string& name, const std::string& job_name, int results) {
  return name + " (" + (job_name.empty() ? "" : "'" + job_name + "', ") + std::to_string(results) + " results)";
}

}  // namespace

nlohmann::json CompareJson(const CompareReport& r) {
  nlohmann::json cells = nlohmann::json::array();
  for (const CellChange& c : r.cells) {
    nlohmann::json metrics = nlohmann::json::array();
    for (const MetricChange& m : c.metrics) {
      metrics.push_back({{"name", m.name}, {"direction", DirectionName(m.direction)},
                         {"pairs", m.pairs}, {"base_mean", m.base_mean},
                         {"candidate_mean", m.candidate_mean}, {"delta", m.delta},
                         {"ci_low", m.ci_low}, {"ci_high", m.ci_high}, {"has_interval", m.has_interval}, {"undecided", m.undecided},
                         {"within_draw", m.within_draw},
                         {"threshold", m.threshold},
                         {"changed_pairs", m.changed_pairs}, {"verdict", m.verdict}});
    }
    nlohmann::json changed = nlohmann::json::array();
    for (const ChangedEpisode& e : c.changed) {
      changed.push_back({{"seed", e.seed}, {"base_episode", e.base_episode},
                         {"candidate_episode", e.candidate_episode}, {"metrics", e.metrics}});
    }
    cells.push_back({{"board", c.board}, {"scenario", c.scenario}, {"method", c.method},
                     {"pairs", c.pairs}, {"seeds", c.seeds}, {"base_episodes", c.base_episodes},
                     {"candidate_episodes", c.candidate_episodes}, {"metrics", metrics},
                     {"changed_episodes", changed}, {"regressions", c.regressions},
                     {"improvements", c.improvements}, {"undecided", c.undecided}});
  }
  nlohmann::json unpaired = nlohmann::json::array();
  for (const Unpaired& u : r.unpaired) {
    unpaired.push_back({{"side", u.side}, {"board", u.board}, {"scenario", u.scenario},
                        {"method", u.method}, {"seed", u.seed}, {"episode_id", u.episode_id}});
  }
  nlohmann::json provenance = nlohmann::json::array();
  for (const ProvenanceChange& p : r.provenance) {
    provenance.push_back({{"name", p.name}, {"cells", p.cells}, {"base_values", p.base_values},
                          {"candidate_values", p.candidate_values}, {"meaning", p.meaning}});
  }
  nlohmann::json spec_changes = nlohmann::json::array();
  for (const SpecChange& s : r.spec_changes) {
    spec_changes.push_back({{"name", s.name}, {"kind", s.kind}, {"cells", s.cells},
                            {"base_values", s.base_values}, {"candidate_values", s.candidate_values}});
  }
  return {{"base", r.base}, {"candidate", r.candidate},
          {"base_job_name", r.base_job_name}, {"candidate_job_name", r.candidate_job_name},
          {"mode", r.mode}, {"exact_applies", r.exact_applies}, {"verdict", r.verdict()},
          {"specs_compared", r.specs_compared}, {"spec_cells", r.spec_cells}, {"jobs_compared", r.jobs_compared},
          {"spec_changes", spec_changes}, {"provenance", provenance},
          {"base_results", r.base_results}, {"candidate_results", r.candidate_results},
          {"regressions", r.regressions}, {"improvements", r.improvements},
          {"changed_metrics", r.changed_metrics}, {"regressions_within_draw", r.regressions_within_draw},
          {"regressions_without_interval", r.regressions_without_interval},
          {"undecided", r.undecided}, {"undecided_cells", r.undecided_cells},
          {"no_change", r.no_change()},
          {"cells", cells}, {"unpaired", unpaired}};
}

std::string CompareTable(const CompareReport& r) {
  const bool exact = r.mode == "exact";
  std::ostringstream out;
  out << "enavi compare: base " << JobText(r.base, r.base_job_name, r.base_results) << " vs candidate "
      << JobText(r.candidate, r.candidate_job_name, r.candidate_results) << ", "
      << (exact ? "exact deltas (virtual clock, cost model: any difference is real)"
                : "paired t-test over seeds, 95% confidence intervals")
      << "\n";
  // How the jobs differ comes before any metric: an override explains a change it caused.
  if (r.specs_compared || r.jobs_compared) {
    const std::string what = std::string(r.specs_compared ? "specs" : "") +
                             (r.specs_compared && r.jobs_compared ? ", " : "") +
                             (r.jobs_compared ? "labels and server builds" : "");
    if (r.spec_changes.empty()) {
      out << "\nthe two jobs' " << what << " are the same\n";
    } else {
      out << "\nhow the jobs differ (" << what << "):\n";
      for (const SpecChange& s : r.spec_changes) out << "  " << SpecChangeText(s, r.spec_cells) << "\n";
    }
  }
  if (!r.provenance.empty()) {
    out << "\nprovenance that differs between paired episodes (result notes provenance.*):\n";
    for (const ProvenanceChange& p : r.provenance) {
      out << "  " << p.name << " in " << p.cells << " of " << r.cells.size() << " cells: " << Values(p.base_values)
          << " -> " << Values(p.candidate_values) << "\n";
      if (!p.meaning.empty()) out << "    " << p.meaning << "\n";
    }
  }
  // Worst first: regressions, those the mode cannot judge, improvements, then changes of judged
  // and of unjudged metrics.
  auto rank = [](const MetricChange& m) {
    if (m.verdict == "regression") return 0;
    if (m.undecided) return 1;
    if (m.verdict == "improvement") return 2;
    return m.direction == Direction::kNone ? 4 : 3;
  };
  for (const CellChange& c : r.cells) {
    bool header = false;
    std::vector<const MetricChange*> shown;
    for (const MetricChange& m : c.metrics) {
      if (m.verdict != "same") shown.push_back(&m);
    }
    std::stable_sort(shown.begin(), shown.end(),
                     [&](const MetricChange* a, const MetricChange* b) { return rank(*a) < rank(*b); });
    for (const MetricChange* mp : shown) {
      const MetricChange& m = *mp;
      if (!header) {
        out << "\n" << CellName(c) << " (" << c.pairs << " pairs)\n";
        header = true;
      }
      std::string tag = m.verdict;
      std::transform(tag.begin(), tag.end(), tag.begin(), ::toupper);
      char col[24];
      std::snprintf(col, sizeof col, "  %-14s ", tag.c_str());
      out << col << Describe(m, exact) << "\n";
    }
    if (exact && !c.changed.empty()) {
      out << "  changed episodes:";
      for (const ChangedEpisode& e : c.changed) {
        out << " seed " << e.seed << " (" << e.base_episode << " -> " << e.candidate_episode << ")";
      }
      out << "\n";
    }
  }
  if (!r.unpaired.empty()) {
    out << "\nunpaired (in one job only):\n";
    for (const Unpaired& u : r.unpaired) {
      out << "  " << u.side << " only: " << u.board << "/" << u.scenario << "/" << u.method
          << " seed " << u.seed << (u.episode_id.empty() ? "" : " (" + u.episode_id + ")") << "\n";
    }
  }
  out << "\n";
  if (r.no_change()) {
    out << "no change: every metric of every paired episode is identical\n";
  } else if (r.regressions > 0) {
    int cells = 0;
    for (const CellChange& c : r.cells) cells += c.regressions > 0 ? 1 : 0;
    out << "REGRESSION: " << r.regressions << " metric(s) in " << cells << " cell(s) got worse";
    out << (r.improvements ? ", " + std::to_string(r.improvements) + " improved" : "");
    const bool repriced = std::any_of(r.provenance.begin(), r.provenance.end(),
                                      [](const ProvenanceChange& p) { return p.name == "cost_model_sha256"; });
    out << (repriced ? " (with another cost model: see provenance above)" : "") << "\n";
    if (r.regressions_within_draw > 0) {
      out << "  " << r.regressions_within_draw << " of the " << r.regressions
          << " are within the seeds' draw: their paired 95% CI includes 0 (--mode paired calls them insignificant)\n";
    }
    if (r.regressions_without_interval > 0) {
      out << "  " << r.regressions_without_interval << " of the " << r.regressions
          << " are in cells of one seed pair: no interval, so whether the seeds' draw alone gives them cannot be "
             "told (fly 2 or more seeds)\n";
    }
    if (r.undecided > 0) {
      out << "  " << r.undecided << " more metric(s) in " << r.undecided_cells
          << " cell(s) got worse beyond their threshold but cannot be judged: one seed pair, no interval\n";
    }
  } else if (r.undecided > 0) {
    out << "CANNOT JUDGE: " << r.undecided << " metric(s) in " << r.undecided_cells
        << " cell(s) got worse beyond their threshold, but " << r.mode
        << " mode needs 2 or more seed pairs per cell for a 95% interval and these cells have 1: fly 2 or more seeds";
    out << (r.exact_applies && !exact ? ", or compare with --mode exact (both jobs are on the virtual clock with the "
                                        "cost model, so any difference is real)"
                                      : "")
        << "\n";
  } else {
    out << "no regression: " << r.changed_metrics << " metric(s) changed, " << r.improvements
        << " improved" << (r.unpaired.empty() ? "" : ", " + std::to_string(r.unpaired.size()) + " unpaired") << "\n";
  }
  return out.str();
}

std::string CompareJunit(const CompareReport& r) {
  const bool exact = r.mode == "exact";
  std::ostringstream body;
  int tests = 0, failures = 0, errors = 0, skipped = 0;
  // How the jobs differ, first: a suite of no testcases whose properties name each setting.
  if (!r.spec_changes.empty()) {
    body << "  <testsuite name=\"how the jobs differ\" tests=\"0\" failures=\"0\" errors=\"0\" skipped=\"0\" "
            "time=\"0\">\n    <properties>\n";
    for (const SpecChange& s : r.spec_changes) {
      const std::string where = s.kind == "spec" ? " (in " + std::to_string(s.cells) + " of " +
                                                       std::to_string(r.spec_cells) + " cells)" : "";
      body << "      <property name=\"" << Xml(s.name) << "\" value=\""
           << Xml(Values(s.base_values) + " -> " + Values(s.candidate_values) + where) << "\"/>\n";
    }
    body << "    </properties>\n  </testsuite>\n";
  }
  for (const CellChange& c : r.cells) {
    int t = 0, f = 0, e = 0;
    std::ostringstream cases;
    const std::string classname = c.board + "." + c.scenario + "." + c.method;
    for (const MetricChange& m : c.metrics) {
      if (m.direction == Direction::kNone) continue;
      ++t;
      cases << "    <testcase classname=\"" << Xml(classname) << "\" name=\"" << Xml(m.name)
            << "\" time=\"0\">";
      if (m.verdict == "regression") {
        ++f;
        cases << "\n      <failure message=\"" << Xml(m.name + " regressed") << "\" type=\"regression\">"
              << Xml(Describe(m, exact)) << "</failure>\n    ";
      } else if (m.undecided) {
        // Fails closed: a change the mode cannot judge is an error of the gate, not a pass.
        ++e;
        cases << "\n      <error message=\"" << Xml(m.name + " cannot be judged: one seed pair, no interval")
              << "\" type=\"cannot_judge\">" << Xml(Describe(m, exact)) << "</error>\n    ";
      }
      cases << "</testcase>\n";
    }
    body << "  <testsuite name=\"" << Xml(CellName(c)) << "\" tests=\"" << t << "\" failures=\""
         << f << "\" errors=\"" << e << "\" skipped=\"0\" time=\"0\">\n"
         << cases.str() << "  </testsuite>\n";
    tests += t;
    failures += f;
    errors += e;
  }
  if (!r.unpaired.empty()) {
    body << "  <testsuite name=\"unpaired\" tests=\"" << r.unpaired.size()
         << "\" failures=\"0\" errors=\"0\" skipped=\"" << r.unpaired.size() << "\" time=\"0\">\n";
    for (const Unpaired& u : r.unpaired) {
      body << "    <testcase classname=\"" << Xml(u.board + "." + u.scenario + "." + u.method)
           << "\" name=\"seed " << u.seed << "\" time=\"0\">\n      <skipped message=\""
           << Xml("in the " + u.side + " job only") << "\"/>\n    </testcase>\n";
    }
    body << "  </testsuite>\n";
    tests += static_cast<int>(r.unpaired.size());
    skipped += static_cast<int>(r.unpaired.size());
  }
  std::ostringstream out;
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites name=\""
      << Xml("enavi compare " + r.base + " " + r.candidate) << "\" tests=\"" << tests
      << "\" failures=\"" << failures << "\" errors=\"" << errors << "\" skipped=\"" << skipped
      << "\" time=\"0\">\n"
      << body.str() << "</testsuites>\n";
  return out.str();
}

}  // namespace enavi::server
