#include "server/compare/compare.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
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

bool Worse(Direction direction, double delta) {
  return direction == Direction::kLower ? delta > 0 : direction == Direction::kHigher && delta < 0;
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
    m->has_interval = true;
  }
  const bool beyond = rule.direction != Direction::kNone && std::abs(m->delta) > m->threshold;
  const bool includes_zero = m->has_interval && m->ci_low <= 0 && m->ci_high >= 0;
  if (!exact) {
    // Within the threshold a change is no regression whatever its interval; beyond it, paired
    // mode needs the interval to tell a change from the draw, and one pair has none.
    if (n < 2 && beyond) {
      m->verdict = "too_few_pairs";
      return;
    }
    if (includes_zero) {
      m->verdict = "insignificant";
      return;
    }
  }
  if (!beyond) {
    m->verdict = "change";
    return;
  }
  m->verdict = Worse(rule.direction, m->delta) ? "regression" : "improvement";
  m->within_draw = exact && includes_zero;
}

// A spec's settings as name -> value text, nested maps flattened with '.' (overrides.NAME,
// world_params.KEY); the pairing keys are left out.
std::map<std::string, std::string> SpecSettings(const nlohmann::json& spec) {
  std::map<std::string, std::string> out;
  for (const auto& [key, value] : spec.items()) {
    if (key == "board" || key == "world" || key == "method" || key == "seed") continue;
    if (value.is_object()) {
      for (const auto& [k, v] : value.items()) out[key + "." + k] = v.is_string() ? v.get<std::string>() : v.dump();
    } else {
      out[key] = value.is_string() ? value.get<std::string>() : value.dump();
    }
  }
  return out;
}

// Values of the names in either map, "(absent)" where a map lacks one, tallied per name; true
// for each name whose two values differ.
std::set<std::string> TallyDifferences(std::map<std::string, std::string> base,
                                       std::map<std::string, std::string> candidate, const std::string& absent,
                                       std::map<std::string, ProvenanceTally>* tally) {
  for (const auto& kv : candidate) base.emplace(kv.first, absent);
  for (const auto& kv : base) candidate.emplace(kv.first, absent);
  std::set<std::string> differing;
  for (const auto& [name, value] : base) {
    (*tally)[name].base.insert(value);
    (*tally)[name].candidate.insert(candidate[name]);
    if (value != candidate[name]) differing.insert(name);
  }
  return differing;
}

// The episodes' specs, paired as their results are (board, world, method, seed), so a job whose
// episodes all failed still shows how it was asked to fly; a setting counts in each cell with a
// pair whose values differ.
void AddSpecChanges(const std::map<std::string, nlohmann::json>& base,
                    const std::map<std::string, nlohmann::json>& candidate, CompareReport* report) {
  using Cells = std::map<CellKey, std::map<std::uint64_t, const nlohmann::json*>>;
  auto index = [](const std::map<std::string, nlohmann::json>& specs) {
    Cells cells;
    for (const auto& [id, spec] : specs) {
      cells[{spec.value("board", ""), spec.value("world", ""), spec.value("method", "")}]
           [spec.value("seed", std::uint64_t{0})] = &spec;
    }
    return cells;
  };
  const Cells b = index(base), c = index(candidate);
  std::map<std::string, ProvenanceTally> tally;
  for (const auto& [key, seeds] : b) {
    const auto other = c.find(key);
    if (other == c.end()) continue;
    ++report->spec_cells;
    std::set<std::string> differing;
    for (const auto& [seed, spec] : seeds) {
      const auto pair = other->second.find(seed);
      if (pair == other->second.end()) continue;
      for (const std::string& name : TallyDifferences(SpecSettings(*spec), SpecSettings(*pair->second), "(default)", &tally))
        differing.insert(name);
    }
    for (const std::string& name : differing) ++tally[name].cells;
  }
  for (const auto& [name, t] : tally) {
    if (t.cells > 0) report->spec_changes.push_back({name, "spec", t.cells, {t.base.begin(), t.base.end()}, {t.candidate.begin(), t.candidate.end()}});
  }
}

// The jobs' labels and the server build that took them (job provenance), when both are known.
void AddJobChanges(const CompareInput& base, const CompareInput& candidate, CompareReport* report) {
  auto prefixed = [](const std::map<std::string, std::string>& m, const std::string& prefix,
                     std::initializer_list<const char*> only) {
    std::map<std::string, std::string> out;
    for (const auto& [k, v] : m) {
      if (only.size() == 0 || std::find(only.begin(), only.end(), k) != only.end()) out[prefix + k] = v;
    }
    return out;
  };
  // Clock, cost and policy are in the episodes' specs; the build is the server's version and commit.
  for (const auto& [kind, b, c] :
       {std::tuple{"label", prefixed(base.labels, "label.", {}), prefixed(candidate.labels, "label.", {})},
        std::tuple{"build", prefixed(base.provenance, "build.", {"enavi_version", "git_commit"}),
                   prefixed(candidate.provenance, "build.", {"enavi_version", "git_commit"})}}) {
    std::map<std::string, ProvenanceTally> tally;
    for (const std::string& name : TallyDifferences(b, c, "(none)", &tally)) {
      const ProvenanceTally& t = tally[name];
      report->spec_changes.push_back({name, kind, 0, {t.base.begin(), t.base.end()}, {t.candidate.begin(), t.candidate.end()}});
    }
  }
}

}  // namespace

std::string CompareReport::verdict() const {
  if (regressions > 0) return "regression";
  if (undecided > 0) return "cannot_judge";
  return no_change() ? "no_change" : "no_regression";
}

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
  CompareInput b, c;
  b.name = base_name;
  b.results = base;
  c.name = candidate_name;
  c.results = candidate;
  return Compare(b, c, options);
}

CompareReport Compare(const CompareInput& base_input, const CompareInput& candidate_input,
                      const CompareOptions& options) {
  const nlohmann::json& base = base_input.results;
  const nlohmann::json& candidate = candidate_input.results;
  const Side b = Index(base), c = Index(candidate);
  CompareReport report;
  report.base = base_input.name;
  report.candidate = candidate_input.name;
  report.base_job_name = base_input.job_name;
  report.candidate_job_name = candidate_input.job_name;
  report.base_results = static_cast<int>(base.size());
  report.candidate_results = static_cast<int>(candidate.size());
  report.exact_applies = b.exact_clock && c.exact_clock;
  if (options.mode == "auto") {
    report.mode = report.exact_applies ? "exact" : "paired";
  } else if (options.mode == "exact" || options.mode == "paired") {
    report.mode = options.mode;
  } else {
    throw std::invalid_argument("mode: '" + options.mode + "': expected auto, exact or paired");
  }
  const bool exact = report.mode == "exact";
  report.specs_compared = !base_input.specs.empty() && !candidate_input.specs.empty();
  report.jobs_compared = base_input.job_known && candidate_input.job_known;
  if (report.specs_compared) AddSpecChanges(base_input.specs, candidate_input.specs, &report);
  if (report.jobs_compared) AddJobChanges(base_input, candidate_input, &report);

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
      for (const std::string& name : TallyDifferences(ProvenanceOf(*br), ProvenanceOf(*cr), "(none)", &provenance))
        differing.insert(name);
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
      if (m.verdict == "regression" && !m.has_interval) ++report.regressions_without_interval;
      m.undecided = m.verdict == "too_few_pairs" && Worse(m.direction, m.delta);
      if (m.undecided) ++cell.undecided;
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
    report.undecided += cell.undecided;
    report.undecided_cells += cell.undecided > 0 ? 1 : 0;
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

}  // namespace enavi::server
