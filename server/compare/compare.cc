#include "server/compare/compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "api/provenance.h"
#include "api/result_metrics.h"

namespace enavi::server {
namespace {

using CellKey = std::tuple<std::string, std::string, std::string>;  // board, world, method

struct Side {
  std::vector<CellKey> order;  // cells in first-seen (episode) order
  std::map<CellKey, std::map<std::uint64_t, const nlohmann::json*>> cells;
  std::map<CellKey, std::string> scenario;
  bool exact_clock = true;  // every record on the virtual clock with the cost model
};

std::string Field(const nlohmann::json& r, const char* key) {
  const auto it = r.find(key);
  if (it == r.end() || !it->is_string()) {
    throw std::invalid_argument(std::string("compare: a result has no '") + key + "'");
  }
  return it->get<std::string>();
}

Side Index(const nlohmann::json& results) {
  Side side;
  if (!results.is_array()) throw std::invalid_argument("compare: expected a list of results");
  for (const auto& r : results) {
    if (!r.contains("seed") || !r["seed"].is_number_unsigned()) {
      throw std::invalid_argument("compare: a result has no seed");
    }
    const std::string world = r.contains("world") ? Field(r, "world") : Field(r, "scenario");
    const CellKey key{Field(r, "board"), world, Field(r, "method")};
    if (!side.cells.count(key)) side.order.push_back(key);
    side.cells[key][r["seed"].get<std::uint64_t>()] = &r;
    side.scenario[key] = r.value("scenario", world);
    side.exact_clock = side.exact_clock && r.value("clock", "virtual") == "virtual" &&
                       r.value("cost", "model") == "model";
  }
  return side;
}

std::string EpisodeOf(const nlohmann::json& r) { return r.value("episode_id", std::string()); }

// A result's provenance notes, without their prefix.
std::map<std::string, std::string> ProvenanceOf(const nlohmann::json& r) {
  const std::string prefix = api::kProvenanceNotePrefix;
  std::map<std::string, std::string> out;
  const auto notes = r.find("notes");
  if (notes == r.end() || !notes->is_object()) return out;
  for (const auto& [key, value] : notes->items()) {
    if (key.rfind(prefix, 0) == 0 && value.is_string()) out[key.substr(prefix.size())] = value.get<std::string>();
  }
  return out;
}

// What a provenance difference does to the comparison, for the notes that change what a flight
// measures besides the code.
std::string ProvenanceMeaning(const std::string& name) {
  if (name == "cost_model_sha256")
    return "the cost model's prices or pricing rule differ: on the virtual clock, CPU and timing deltas include "
           "the re-pricing, not only the code's";
  if (name == "calibration_id") return "the reference costs were fitted by another calibration";
  if (name == "policy_sha256") return "E-Navi flew another policy";
  if (name == "ray_kernels")
    return "flown on hosts with other Embree ray kernels: depth images, and so flights, can differ with no "
           "change of code";
  return "";
}

struct ProvenanceTally {
  std::set<std::string> base, candidate;
  int cells = 0;
};

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

void Judge(const MetricRule& rule, bool exact, const std::vector<double>& base,
           const std::vector<double>& cand, MetricChange* m) {
  m->direction = rule.direction;
  m->pairs = static_cast<int>(base.size());
  m->base_mean = Mean(base);
  m->candidate_mean = Mean(cand);
  m->delta = m->candidate_mean - m->base_mean;
  m->threshold = std::max(rule.abs, rule.rel * std::abs(m->base_mean));
  std::vector<double> d(base.size());
  for (std::size_t i = 0; i < base.size(); ++i) {
    d[i] = cand[i] - base[i];
    if (cand[i] != base[i]) ++m->changed_pairs;
  }
  m->ci_low = m->ci_high = m->delta;
  if (m->changed_pairs == 0) {
    m->verdict = "same";
    return;
  }
  // The paired t interval, in both modes: exact mode judges by the delta but reports whether the
  // seeds' draw alone could give it.
  const int n = static_cast<int>(d.size());
  if (n >= 2) {
    double ss = 0;
    for (double x : d) ss += (x - m->delta) * (x - m->delta);
    const double se = std::sqrt(ss / (n - 1)) / std::sqrt(static_cast<double>(n));
    const double half = StudentT975(n - 1) * se;
    m->ci_low = m->delta - half;
    m->ci_high = m->delta + half;
  }
  const bool includes_zero = n >= 2 && m->ci_low <= 0 && m->ci_high >= 0;
  if (!exact) {
    if (n < 2) {
      m->verdict = "too_few_pairs";
      return;
    }
    if (includes_zero) {
      m->verdict = "insignificant";
      return;
    }
  }
  if (rule.direction == Direction::kNone || std::abs(m->delta) <= m->threshold) {
    m->verdict = "change";
    return;
  }
  const bool worse = rule.direction == Direction::kLower ? m->delta > 0 : m->delta < 0;
  m->verdict = worse ? "regression" : "improvement";
  m->within_draw = exact && includes_zero;
}

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
  if (!exact && m.verdict != "too_few_pairs") {
    s += " 95% CI [" + Num(m.ci_low) + ", " + Num(m.ci_high) + "]";
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

}  // namespace

void AddTrendIntervals(nlohmann::json* trend) {
  for (nlohmann::json& p : (*trend)["points"]) {
    p["ci95"] = p["seed_std"].is_null()
                    ? nlohmann::json(nullptr)
                    : nlohmann::json(StudentT975(p["df"].get<int>()) * p["seed_std"].get<double>() /
                                     std::sqrt(p["n"].get<double>()));
  }
}

double StudentT975(int df) {
  // Two-sided 95 % critical values of Student's t (any statistics table, e.g. NIST/SEMATECH
  // e-Handbook 1.3.6.7.2); between tabulated df the next smaller df is used (conservative).
  static const double kTable[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306,
                                  2.262,  2.228, 2.201, 2.179, 2.160, 2.145, 2.131, 2.120,
                                  2.110,  2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064,
                                  2.060,  2.056, 2.052, 2.048, 2.045, 2.042};
  if (df < 1) throw std::invalid_argument("StudentT975: df must be >= 1");
  if (df <= 30) return kTable[df - 1];
  if (df < 40) return 2.042;
  if (df < 60) return 2.021;
  if (df < 120) return 2.000;
  return 1.980;
}

CompareReport Compare(const nlohmann::json& base, const nlohmann::json& candidate,
                      const CompareOptions& options, const std::string& base_name,
                      const std::string& candidate_name) {
  const Side b = Index(base), c = Index(candidate);
  CompareReport report;
  report.base = base_name;
  report.candidate = candidate_name;
  report.base_results = static_cast<int>(base.size());
  report.candidate_results = static_cast<int>(candidate.size());
  if (options.mode == "auto") {
    report.mode = b.exact_clock && c.exact_clock ? "exact" : "paired";
  } else if (options.mode == "exact" || options.mode == "paired") {
    report.mode = options.mode;
  } else {
    throw std::invalid_argument("mode: '" + options.mode + "': expected auto, exact or paired");
  }
  const bool exact = report.mode == "exact";

  std::map<std::string, ProvenanceTally> provenance;
  auto unpaired = [&](const std::string& side, const CellKey& key, const std::string& scenario,
                      std::uint64_t seed, const nlohmann::json& r) {
    report.unpaired.push_back({side, std::get<0>(key), scenario, std::get<2>(key), EpisodeOf(r), seed});
  };
  for (const CellKey& key : b.order) {
    const auto& base_seeds = b.cells.at(key);
    const auto cand_it = c.cells.find(key);
    CellChange cell;
    cell.board = std::get<0>(key);
    cell.scenario = b.scenario.at(key);
    cell.method = std::get<2>(key);
    std::vector<std::pair<const nlohmann::json*, const nlohmann::json*>> pairs;
    for (const auto& [seed, r] : base_seeds) {
      if (cand_it == c.cells.end() || !cand_it->second.count(seed)) {
        unpaired("base", key, cell.scenario, seed, *r);
        continue;
      }
      pairs.emplace_back(r, cand_it->second.at(seed));
      cell.seeds.push_back(seed);
      cell.base_episodes.push_back(EpisodeOf(*r));
      cell.candidate_episodes.push_back(EpisodeOf(*cand_it->second.at(seed)));
    }
    if (cand_it != c.cells.end()) {
      for (const auto& [seed, r] : cand_it->second) {
        if (!base_seeds.count(seed)) unpaired("candidate", key, cell.scenario, seed, *r);
      }
    }
    if (pairs.empty()) continue;
    cell.pairs = static_cast<int>(pairs.size());

    std::set<std::string> differing;
    for (const auto& [br, cr] : pairs) {
      std::map<std::string, std::string> bp = ProvenanceOf(*br), cp = ProvenanceOf(*cr);
      for (const auto& kv : cp) bp.emplace(kv.first, "(none)");
      for (const auto& kv : bp) cp.emplace(kv.first, "(none)");
      for (const auto& [name, value] : bp) {
        provenance[name].base.insert(value);
        provenance[name].candidate.insert(cp[name]);
        if (value != cp[name]) differing.insert(name);
      }
    }
    for (const std::string& name : differing) ++provenance[name].cells;

    std::vector<std::map<std::string, double>> bm, cm;
    std::set<std::string> names;
    for (const auto& [br, cr] : pairs) {
      bm.push_back(api::ResultMetrics(*br));
      cm.push_back(api::ResultMetrics(*cr));
      for (const auto& kv : bm.back()) names.insert(kv.first);
      for (const auto& kv : cm.back()) names.insert(kv.first);
    }
    // A trigger that never fired is left out of a record's count map: compare it as 0.
    for (const std::string& name : names) {
      if (!api::AbsentMeansZero(name)) continue;
      for (auto* side : {&bm, &cm})
        for (auto& metrics : *side) metrics.emplace(name, 0.0);
    }
    for (const std::string& name : names) {
      const auto rule_it = options.rules.find(name);
      const MetricRule rule = rule_it == options.rules.end() ? MetricRule{} : rule_it->second;
      std::vector<double> bv, cv;
      for (std::size_t i = 0; i < pairs.size(); ++i) {
        if (!bm[i].count(name) || !cm[i].count(name)) continue;
        if (rule.success_only && (bm[i]["success"] != 1.0 || cm[i]["success"] != 1.0)) continue;
        bv.push_back(bm[i][name]);
        cv.push_back(cm[i][name]);
      }
      if (bv.empty()) continue;
      MetricChange m;
      m.name = name;
      Judge(rule, exact, bv, cv, &m);
      if (m.verdict == "regression") ++cell.regressions;
      if (m.verdict == "regression" && m.within_draw) ++report.regressions_within_draw;
      if (m.verdict == "improvement") ++cell.improvements;
      if (m.verdict != "same") ++report.changed_metrics;
      cell.metrics.push_back(std::move(m));
    }
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      ChangedEpisode e{cell.seeds[i], cell.base_episodes[i], cell.candidate_episodes[i], {}};
      for (const std::string& name : names) {
        const auto bi = bm[i].find(name), ci = cm[i].find(name);
        const bool in_base = bi != bm[i].end(), in_candidate = ci != cm[i].end();
        // In neither record of this pair (another pair has it): nothing changed here.
        if (in_base != in_candidate || (in_base && bi->second != ci->second)) e.metrics.push_back(name);
      }
      if (!e.metrics.empty()) cell.changed.push_back(std::move(e));
    }
    report.regressions += cell.regressions;
    report.improvements += cell.improvements;
    report.cells.push_back(std::move(cell));
  }
  for (const CellKey& key : c.order) {
    if (b.cells.count(key)) continue;
    for (const auto& [seed, r] : c.cells.at(key)) unpaired("candidate", key, c.scenario.at(key), seed, *r);
  }
  for (const auto& [name, tally] : provenance) {
    if (tally.cells == 0) continue;
    report.provenance.push_back({name, tally.cells, {tally.base.begin(), tally.base.end()},
                                 {tally.candidate.begin(), tally.candidate.end()}, ProvenanceMeaning(name)});
  }
  return report;
}

nlohmann::json CompareJson(const CompareReport& r) {
  nlohmann::json cells = nlohmann::json::array();
  for (const CellChange& c : r.cells) {
    nlohmann::json metrics = nlohmann::json::array();
    for (const MetricChange& m : c.metrics) {
      metrics.push_back({{"name", m.name}, {"direction", DirectionName(m.direction)},
                         {"pairs", m.pairs}, {"base_mean", m.base_mean},
                         {"candidate_mean", m.candidate_mean}, {"delta", m.delta},
                         {"ci_low", m.ci_low}, {"ci_high", m.ci_high}, {"within_draw", m.within_draw},
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
                     {"improvements", c.improvements}});
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
  return {{"base", r.base}, {"candidate", r.candidate}, {"mode", r.mode}, {"provenance", provenance},
          {"base_results", r.base_results}, {"candidate_results", r.candidate_results},
          {"regressions", r.regressions}, {"improvements", r.improvements},
          {"changed_metrics", r.changed_metrics}, {"regressions_within_draw", r.regressions_within_draw},
          {"no_change", r.no_change()},
          {"cells", cells}, {"unpaired", unpaired}};
}

std::string CompareTable(const CompareReport& r) {
  const bool exact = r.mode == "exact";
  std::ostringstream out;
  out << "enavi compare: base " << r.base << " (" << r.base_results << " results) vs candidate "
      << r.candidate << " (" << r.candidate_results << " results), "
      << (exact ? "exact deltas (virtual clock, cost model: any difference is real)"
                : "paired t-test over seeds, 95% confidence intervals")
      << "\n";
  if (!r.provenance.empty()) {
    // A few values each: a job holds one cost model digest per board and cost family.
    auto values = [](const std::vector<std::string>& v) {
      std::string out;
      for (std::size_t i = 0; i < v.size() && i < 3; ++i) out += (i ? ", " : "") + v[i];
      return v.size() > 3 ? out + " (+" + std::to_string(v.size() - 3) + " more)" : out;
    };
    out << "\nprovenance that differs between paired episodes (result notes provenance.*):\n";
    for (const ProvenanceChange& p : r.provenance) {
      out << "  " << p.name << " in " << p.cells << " of " << r.cells.size() << " cells: " << values(p.base_values)
          << " -> " << values(p.candidate_values) << "\n";
      if (!p.meaning.empty()) out << "    " << p.meaning << "\n";
    }
  }
  // Worst first: regressions, improvements, then changes of judged and of unjudged metrics.
  auto rank = [](const MetricChange& m) {
    if (m.verdict == "regression") return 0;
    if (m.verdict == "improvement") return 1;
    return m.direction == Direction::kNone ? 3 : 2;
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
  } else {
    out << "no regression: " << r.changed_metrics << " metric(s) changed, " << r.improvements
        << " improved" << (r.unpaired.empty() ? "" : ", " + std::to_string(r.unpaired.size()) + " unpaired") << "\n";
  }
  return out.str();
}

std::string CompareJunit(const CompareReport& r) {
  const bool exact = r.mode == "exact";
  std::ostringstream body;
  int tests = 0, failures = 0, skipped = 0;
  for (const CellChange& c : r.cells) {
    int t = 0, f = 0;
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
      }
      cases << "</testcase>\n";
    }
    body << "  <testsuite name=\"" << Xml(CellName(c)) << "\" tests=\"" << t << "\" failures=\""
         << f << "\" errors=\"0\" skipped=\"0\" time=\"0\">\n"
         << cases.str() << "  </testsuite>\n";
    tests += t;
    failures += f;
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
      << "\" failures=\"" << failures << "\" errors=\"0\" skipped=\"" << skipped
      << "\" time=\"0\">\n"
      << body.str() << "</testsuites>\n";
  return out.str();
}

}  // namespace enavi::server
