#include "server/eval/tables.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <tuple>
#include <vector>

#include "api/fixed.h"
#include "server/compare/compare.h"
#include "server/eval/paper_reference.h"

namespace enavi::server {
namespace {

// A result's scenario as the tables name it: a custom world by its file.
std::string ScenarioName(const nlohmann::json& r) {
  return r.value("scenario", "") == "custom" ? r.value("world", "") : r.value("scenario", "");
}

// The cells of a table by scenario and method, in the order first seen.
template <typename Cell>
struct ScenarioMethodCells {
  std::vector<std::pair<std::string, std::string>> order;
  std::map<std::pair<std::string, std::string>, Cell> cells;

  Cell& Of(const nlohmann::json& r) {
    const auto [it, added] = cells.try_emplace({ScenarioName(r), r.value("method", "")});
    if (added) order.push_back(it->first);
    return it->second;
  }
};

using api::Fixed;

// Characters on a terminal, not bytes: UTF-8 continuation bytes take no column ("±").
std::size_t Columns(const std::string& s) {
  return static_cast<std::size_t>(std::count_if(s.begin(), s.end(), [](char c) { return (c & 0xC0) != 0x80; }));
}

// Left-aligned first `left` columns, the rest right-aligned.
std::string Render(const std::vector<std::vector<std::string>>& rows, std::size_t left) {
  std::vector<std::size_t> width;
  for (const auto& r : rows) {
    if (width.size() < r.size()) width.resize(r.size(), 0);
    for (std::size_t i = 0; i < r.size(); ++i) width[i] = std::max(width[i], Columns(r[i]));
  }
  std::ostringstream os;
  for (const auto& r : rows) {
    std::string line;
    for (std::size_t i = 0; i < r.size(); ++i) {
      const std::string pad(width[i] - Columns(r[i]), ' ');
      if (i > 0) line += "  ";
      line += i < left ? r[i] + pad : pad + r[i];
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    os << line << "\n";
  }
  return os.str();
}

std::string Str(const nlohmann::json& j) {
  if (j.is_string()) return j.get<std::string>();
  if (j.is_boolean()) return j.get<bool>() ? "true" : "false";
  if (j.is_number_integer()) return std::to_string(j.get<std::int64_t>());
  if (j.is_number_unsigned()) return std::to_string(j.get<std::uint64_t>());
  if (j.is_number_float()) {
    std::ostringstream os;
    os.precision(10);
    os << j.get<double>();
    return os.str();
  }
  if (j.is_null()) return "";
  return j.dump();
}

void Flatten(const nlohmann::json& j, const std::string& prefix,
             std::vector<std::pair<std::string, std::string>>* out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object() && !it->empty()) {
      Flatten(*it, key, out);
    } else {
      out->emplace_back(key, Str(*it));
    }
  }
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

struct Mean {
  double sum = 0, sum_sq = 0;
  int n = 0;
  void Add(double v) {
    sum += v;
    sum_sq += v * v;
    ++n;
  }
  double value() const { return n > 0 ? sum / n : std::nan(""); }
  /// Sample variance of the values (NaN with fewer than two).
  double variance() const {
    return n > 1 ? std::max(0.0, (sum_sq - sum * sum / n) / (n - 1)) : std::nan("");
  }
  std::string Text(int digits) const { return n > 0 ? Fixed(value(), digits) : "-"; }
};

}  // namespace

std::string ResultsTable(const nlohmann::json& results) {
  std::vector<std::vector<std::string>> rows = {
      {"episode", "board", "scenario", "method", "seed", "success", "end", "flight s", "path m",
       "nav cpu %", "vel std", "miss %", "e-stops"}};
  for (const auto& r : results) {
    rows.push_back({r.value("episode_id", ""), r.value("board", ""), r.value("scenario", ""),
                    r.value("method", ""), Str(r.value("seed", nlohmann::json())),
                    r.value("success", false) ? "yes" : "no", r.value("end_reason", ""),
                    Fixed(r.value("flight_time_s", 0.0), 2), Fixed(r.value("path_length_m", 0.0), 2),
                    Fixed(r.value("nav_cpu_util_pct", 0.0), 1),
                    Fixed(r.value("velocity_std_mps", 0.0), 3),
                    Fixed(100.0 * r.value("deadline_miss_ratio", 0.0), 1),
                    Str(r.value("emergency_stops", nlohmann::json(0)))});
  }
  return Render(rows, 7);
}

std::string ResultsCsv(const nlohmann::json& results) {
  // Columns: the union of every flattened key, in first-seen order.
  std::vector<std::string> columns;
  std::set<std::string> known;
  std::vector<std::map<std::string, std::string>> rows;
  for (const auto& r : results) {
    std::vector<std::pair<std::string, std::string>> flat;
    Flatten(r, "", &flat);
    std::map<std::string, std::string> row;
    for (auto& [k, v] : flat) {
      if (known.insert(k).second) columns.push_back(k);
      row[k] = v;
    }
    rows.push_back(std::move(row));
  }
  std::ostringstream os;
  for (std::size_t i = 0; i < columns.size(); ++i) os << (i ? "," : "") << CsvField(columns[i]);
  os << "\n";
  for (const auto& row : rows) {
    for (std::size_t i = 0; i < columns.size(); ++i) {
      auto it = row.find(columns[i]);
      os << (i ? "," : "") << (it == row.end() ? "" : CsvField(it->second));
    }
    os << "\n";
  }
  return os.str();
}

std::string PaperTable(const nlohmann::json& results) {
  struct Cell {
    Mean cpu, flight, path;
  };
  struct Row {
    std::map<std::string, Cell> by_scenario;
    Mean success, vel_std, cpu_all, flight_all, estops, collisions;
  };
  std::vector<std::string> boards, methods, scenarios;
  auto note = [](std::vector<std::string>* list, const std::string& v) {
    if (std::find(list->begin(), list->end(), v) == list->end()) list->push_back(v);
  };
  std::map<std::pair<std::string, std::string>, Row> table;
  for (const auto& r : results) {
    const std::string board = r.value("board", ""), method = r.value("method", "");
    const std::string scenario = ScenarioName(r);
    note(&boards, board);
    note(&methods, method);
    note(&scenarios, scenario);
    Row& row = table[{board, method}];
    Cell& cell = row.by_scenario[scenario];
    const bool ok = r.value("success", false);
    cell.cpu.Add(r.value("nav_cpu_util_pct", 0.0));
    row.cpu_all.Add(r.value("nav_cpu_util_pct", 0.0));
    if (ok) {
      cell.flight.Add(r.value("flight_time_s", 0.0));
      cell.path.Add(r.value("path_length_m", 0.0));
      row.flight_all.Add(r.value("flight_time_s", 0.0));
    }
    row.success.Add(ok ? 1.0 : 0.0);
    row.vel_std.Add(r.value("velocity_std_mps", 0.0));
    row.estops.Add(r.value("emergency_stops", 0.0));
    row.collisions.Add(r.value("collided", false) ? 1.0 : 0.0);
  }
  if (table.empty()) return "no results\n";

  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> head1 = {"", ""}, head2 = {"board", "method"};
  for (const auto& s : scenarios) {
    head1.insert(head1.end(), {s, "", ""});
    head2.insert(head2.end(), {"cpu %", "time s", "path m"});
  }
  head1.insert(head1.end(), {"all", "", "", ""});
  head2.insert(head2.end(), {"success", "collided", "vel std", "e-stops"});
  rows.push_back(head1);
  rows.push_back(head2);
  for (const auto& b : boards) {
    for (const auto& m : methods) {
      auto it = table.find({b, m});
      if (it == table.end()) continue;
      const Row& row = it->second;
      std::vector<std::string> line = {b, m};
      for (const auto& s : scenarios) {
        auto c = row.by_scenario.find(s);
        if (c == row.by_scenario.end()) {
          line.insert(line.end(), {"-", "-", "-"});
        } else {
          line.insert(line.end(), {c->second.cpu.Text(1), c->second.flight.Text(1),
                                   c->second.path.Text(1)});
        }
      }
      line.push_back(Fixed(100.0 * row.success.value(), 0) + "%");
      line.push_back(Fixed(row.collisions.sum, 0));
      line.push_back(row.vel_std.Text(3));
      line.push_back(row.estops.Text(1));
      rows.push_back(line);
    }
  }
  std::string out = Render(rows, 2);

  // E-Navi vs baseline: relative reduction of the scenario-averaged means.
  std::vector<std::vector<std::string>> red = {{"board", "cpu % reduction", "flight time reduction"}};
  for (const auto& b : boards) {
    auto base = table.find({b, "baseline"});
    auto enavi = table.find({b, "enavi"});
    if (base == table.end() || enavi == table.end()) continue;
    auto reduction = [](const Mean& before, const Mean& after) -> std::string {
      if (before.n == 0 || after.n == 0 || before.value() == 0) return "-";
      return Fixed(100.0 * (before.value() - after.value()) / before.value(), 1) + "%";
    };
    red.push_back({b, reduction(base->second.cpu_all, enavi->second.cpu_all),
                   reduction(base->second.flight_all, enavi->second.flight_all)});
  }
  if (red.size() > 1) out += "\nE-Navi vs baseline\n" + Render(red, 1);

  // The gap split: runtime (baseline = Ego-Planner's node -> fixed = our stack at the same rates)
  // plus configuration (fixed -> enavi), in points of CPU and seconds of flight; they add up.
  std::vector<std::vector<std::string>> split = {{"board", "cpu gap", "= runtime", "+ configuration", "time gap s",
                                                  "= runtime", "+ configuration"}};
  for (const auto& b : boards) {
    auto base = table.find({b, "baseline"}), fixed = table.find({b, "fixed"}), enavi = table.find({b, "enavi"});
    if (base == table.end() || fixed == table.end() || enavi == table.end()) continue;
    auto diff = [](const Mean& a, const Mean& c, int digits) -> std::string {
      if (a.n == 0 || c.n == 0) return "-";
      return Fixed(a.value() - c.value(), digits);
    };
    const Row &B = base->second, &F = fixed->second, &E = enavi->second;
    split.push_back({b, diff(B.cpu_all, E.cpu_all, 1), diff(B.cpu_all, F.cpu_all, 1), diff(F.cpu_all, E.cpu_all, 1),
                     diff(B.flight_all, E.flight_all, 2), diff(B.flight_all, F.flight_all, 2),
                     diff(F.flight_all, E.flight_all, 2)});
  }
  if (split.size() > 1) out += "\nbaseline - enavi, split into runtime (baseline - fixed) and configuration (fixed - enavi)\n" + Render(split, 1);
  out += "\n(flight time and path length: mean over successful episodes; cpu %: navigation "
         "tasks, % of one board core, mean over all episodes)\n";
  return out;
}

namespace {

// 95 % interval of the reduction 1 - E / B of two means of scenario means, from the spread over
// seeds within each scenario (the draw of routes; the scenarios are the same in every run):
// Var(B) = sum_s var_s / n_s / S^2 per method, the delta method for the ratio, Student's t with
// the smaller method's pooled degrees of freedom. "-" when a scenario has fewer than two values.
template <typename CellOf, typename Metric>
std::string ReductionInterval(const CellOf& cell_of, const std::string& board, Metric metric, std::size_t scenarios) {
  double mean[2] = {0, 0}, var[2] = {0, 0};
  int df[2] = {0, 0};
  const char* methods[2] = {"baseline", "enavi"};
  for (int k = 0; k < 2; ++k) {
    for (std::size_t s = 0; s < scenarios; ++s) {
      const auto* c = cell_of(board, methods[k], s);
      if (c == nullptr || ((*c).*metric).n < 2) return "-";
      const Mean& m = (*c).*metric;
      mean[k] += m.value() / static_cast<double>(scenarios);
      var[k] += m.variance() / m.n / static_cast<double>(scenarios * scenarios);
      df[k] += m.n - 1;
    }
  }
  const double b = mean[0], e = mean[1];
  if (b == 0) return "-";
  const double sd = std::sqrt(var[1] / (b * b) + e * e * var[0] / (b * b * b * b));
  const double r = 1.0 - e / b, half = StudentT975(std::min(df[0], df[1])) * sd;
  return Fixed(100.0 * (r - half), 1) + " to " + Fixed(100.0 * (r + half), 1) + "%";
}

}  // namespace

std::string PaperComparison(const nlohmann::json& results) {
  const std::vector<std::string>& scenarios = PaperScenarios();
  // Ours, by (board, method, scenario): the same means as PaperTable.
  struct Cell {
    Mean cpu, flight, path;
  };
  std::map<std::tuple<std::string, std::string, std::string>, Cell> ours;
  for (const auto& r : results) {
    Cell& c = ours[{r.value("board", ""), r.value("method", ""), r.value("scenario", "")}];
    c.cpu.Add(r.value("nav_cpu_util_pct", 0.0));
    if (r.value("success", false)) {
      c.flight.Add(r.value("flight_time_s", 0.0));
      c.path.Add(r.value("path_length_m", 0.0));
    }
  }
  auto our_cell = [&](const std::string& b, const std::string& m, std::size_t s) -> const Cell* {
    auto it = ours.find({b, m, scenarios[s]});
    return it == ours.end() ? nullptr : &it->second;
  };
  // Scenario-averaged mean of one metric, "-"-safe: NaN when a scenario has no value.
  auto average = [](const std::array<double, 5>& v) {
    double sum = 0;
    for (double x : v) sum += x;
    return sum / static_cast<double>(v.size());
  };
  using Metric = Mean Cell::*;
  auto ours_of = [&](const std::string& b, const std::string& m, Metric metric) {
    std::array<double, 5> v{};
    for (std::size_t s = 0; s < scenarios.size(); ++s) {
      const Cell* c = our_cell(b, m, s);
      v[s] = c == nullptr ? std::nan("") : (c->*metric).value();
    }
    return v;
  };

  std::string out;
  struct Block {
    const char* title;
    Metric metric;
    std::array<double, 5> PaperRow::*paper;
  };
  const Block blocks[] = {{"nav cpu % of one core", &Cell::cpu, &PaperRow::cpu_pct},
                          {"flight time s", &Cell::flight, &PaperRow::flight_time_s},
                          {"path m", &Cell::path, &PaperRow::path_m}};
  auto text = [](double v, int digits) { return std::isnan(v) ? std::string("-") : Fixed(v, digits); };
  for (const Block& block : blocks) {
    std::vector<std::string> head1 = {"", ""}, head2 = {"board", "method"};
    for (const auto& s : scenarios) {
      head1.insert(head1.end(), {s, "", ""});
      head2.insert(head2.end(), {"ours", "paper", "diff"});
    }
    std::vector<std::vector<std::string>> rows = {head1, head2};
    for (const std::string& b : PaperBoards()) {
      for (const char* m : {"baseline", "enavi"}) {
        const PaperRow* paper = FindPaperRow(b, m);
        const std::array<double, 5> mine = ours_of(b, m, block.metric);
        std::vector<std::string> line = {b, m};
        bool any = false;
        for (std::size_t s = 0; s < scenarios.size(); ++s) {
          const double p = (paper->*block.paper)[s];
          any = any || !std::isnan(mine[s]);
          line.insert(line.end(), {text(mine[s], 1), Fixed(p, 1), text(mine[s] - p, 1)});
        }
        if (any) rows.push_back(line);
      }
    }
    if (rows.size() > 2) out += std::string("\n") + block.title + ": ours beside the paper's HIL table\n" + Render(rows, 2);
  }

  std::vector<std::vector<std::string>> red = {{"board", "cpu reduction ours", "95 % interval", "paper",
                                                 "flight time reduction ours", "95 % interval", "paper"}};
  for (const std::string& b : PaperBoards()) {
    auto reduction = [&](Metric metric, std::array<double, 5> PaperRow::*paper, bool mine) {
      const double base = mine ? average(ours_of(b, "baseline", metric)) : average(FindPaperRow(b, "baseline")->*paper);
      const double enavi = mine ? average(ours_of(b, "enavi", metric)) : average(FindPaperRow(b, "enavi")->*paper);
      return std::isnan(base) || std::isnan(enavi) || base == 0 ? std::string("-")
                                                                 : Fixed(100.0 * (base - enavi) / base, 1) + "%";
    };
    const std::string cpu_ours = reduction(&Cell::cpu, &PaperRow::cpu_pct, true);
    const std::string time_ours = reduction(&Cell::flight, &PaperRow::flight_time_s, true);
    if (cpu_ours == "-" && time_ours == "-") continue;
    red.push_back({b, cpu_ours, ReductionInterval(our_cell, b, &Cell::cpu, scenarios.size()),
                   reduction(&Cell::cpu, &PaperRow::cpu_pct, false), time_ours,
                   ReductionInterval(our_cell, b, &Cell::flight, scenarios.size()),
                   reduction(&Cell::flight, &PaperRow::flight_time_s, false)});
  }
  if (red.size() > 1) {
    out += "\nE-Navi vs baseline, mean of the scenario means (a board's reduction needs all of S1-S5; the "
           "interval is the seeds' draw: their spread within each scenario)\n" +
           Render(red, 1);
  }
  return out.empty() ? "no results on the paper's boards and scenarios\n" : out;
}

std::string TrendTable(const nlohmann::json& trend, const std::string& method) {
  std::vector<std::string> boards, jobs;
  std::map<std::string, std::set<std::string>> methods_of;  // job -> methods
  std::map<std::tuple<std::string, std::string, std::string>, const nlohmann::json*> point;
  for (const auto& p : trend.at("points")) {
    const std::string job = p.at("job_id"), board = p.at("board"), m = p.at("method");
    if (!method.empty() && m != method) continue;
    if (std::find(jobs.begin(), jobs.end(), job) == jobs.end()) jobs.push_back(job);
    if (std::find(boards.begin(), boards.end(), board) == boards.end()) boards.push_back(board);
    methods_of[job].insert(m);
    point[{job, m, board}] = &p;
  }
  if (jobs.empty()) return "no results with this label and metric\n";
  std::sort(boards.begin(), boards.end());
  std::vector<std::vector<std::string>> rows = {{"#", "job", "name", "method"}};
  rows[0].insert(rows[0].end(), boards.begin(), boards.end());
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    for (const std::string& m : methods_of[jobs[i]]) {
      std::vector<std::string> line = {std::to_string(i + 1), jobs[i], "", m};
      for (const std::string& b : boards) {
        const auto it = point.find({jobs[i], m, b});
        if (it == point.end()) {
          line.push_back("-");
          continue;
        }
        const nlohmann::json& p = *it->second;
        line[2] = p.value("name", "");
        const double mean = p.at("mean").get<double>();
        const int digits = std::abs(mean) >= 100 ? 1 : std::abs(mean) >= 1 ? 2 : 3;
        line.push_back(Fixed(mean, digits) +
                       (p.value("ci95", nlohmann::json()).is_number() ? " ± " + Fixed(p["ci95"].get<double>(), digits) : ""));
      }
      rows.push_back(std::move(line));
    }
  }
  return Render(rows, 4) +
         "(mean over the job's flights of the board and method ± the 95 % interval of the seeds' draw: their spread "
         "within each scenario, pooled; a step smaller than it can be the draw, `enavi compare --mode paired` "
         "judges it)\n";
}

std::string EciRangeTable(const nlohmann::json& results) {
  struct Cell {
    Mean lo, hi;
    double lowest = 1.0, highest = 0.0;
    int without = 0;  // flights with no range: never took off, or stored before the field existed
  };
  ScenarioMethodCells<Cell> table;
  const auto& order = table.order;
  const auto& cells = table.cells;
  for (const auto& r : results) {
    Cell& c = table.Of(r);
    const nlohmann::json eci = r.value("eci", nlohmann::json::object());
    if (eci.value("flight_frames", 0) <= 0) {
      ++c.without;
      continue;
    }
    const double lo = eci.value("flight_min", 0.0), hi = eci.value("flight_max", 0.0);
    c.lo.Add(lo);
    c.hi.Add(hi);
    c.lowest = std::min(c.lowest, lo);
    c.highest = std::max(c.highest, hi);
  }
  if (cells.empty()) return "no results\n";
  const bool paper = std::any_of(order.begin(), order.end(),
                                 [](const auto& k) { return FindPaperEciRange(k.first) != nullptr; });
  std::vector<std::string> head = {"scenario", "method", "flights", "no range", "min", "max", "lowest min",
                                   "highest max"};
  if (paper) head.insert(head.end(), {"paper min", "paper max", "diff min", "diff max"});
  std::vector<std::vector<std::string>> rows = {head};
  for (const auto& key : order) {
    const Cell& c = cells.at(key);
    const bool any = c.lo.n > 0;
    std::vector<std::string> line = {key.first, key.second, std::to_string(c.lo.n), std::to_string(c.without),
                                     c.lo.Text(2), c.hi.Text(2), any ? Fixed(c.lowest, 2) : "-",
                                     any ? Fixed(c.highest, 2) : "-"};
    if (paper) {
      if (const PaperEciRange* p = FindPaperEciRange(key.first)) {
        line.insert(line.end(), {Fixed(p->min, 2), Fixed(p->max, 2), any ? Fixed(c.lo.value() - p->min, 2) : "-",
                                 any ? Fixed(c.hi.value() - p->max, 2) : "-"});
      } else {
        line.insert(line.end(), {"-", "-", "-", "-"});
      }
    }
    rows.push_back(line);
  }
  return "eci range per scenario (per flight: least and greatest eci of the frames in flight; min, max: their means "
         "over the flights)\n" +
         Render(rows, 2);
}

bool HasMovingWorlds(const nlohmann::json& results) {
  return std::any_of(results.begin(), results.end(), [](const nlohmann::json& r) {
    return r.value("notes", nlohmann::json::object()).contains("movers");
  });
}

std::string RobustnessTable(const nlohmann::json& results) {
  struct Cell {
    Mean success, flight, tracking, cpu, difference;
    double static_hits = 0, mover_hits = 0;
  };
  ScenarioMethodCells<Cell> table;
  const auto& order = table.order;
  const auto& cells = table.cells;
  for (const auto& r : results) {
    Cell& c = table.Of(r);
    const bool ok = r.value("success", false);
    c.success.Add(ok ? 1.0 : 0.0);
    if (ok) c.flight.Add(r.value("flight_time_s", 0.0));
    c.tracking.Add(r.value("setpoint_lag_p95_m", 0.0));
    c.cpu.Add(r.value("nav_cpu_util_pct", 0.0));
    c.difference.Add(r.value("replans_by_trigger", nlohmann::json::object()).value("difference", 0.0));
    if (r.value("collided", false)) {
      // Results stored before collided_with existed could only hit the static world.
      (r.value("collided_mover", false) ? c.mover_hits : c.static_hits) += 1.0;
    }
  }
  if (cells.empty()) return "no results\n";
  std::vector<std::vector<std::string>> rows = {{"scenario", "method", "flights", "success", "hit static", "hit mover",
                                                 "time s", "tracking p95 m", "cpu %", "diff replans"}};
  for (const auto& key : order) {
    const Cell& c = cells.at(key);
    rows.push_back({key.first, key.second, std::to_string(c.success.n), Fixed(100.0 * c.success.value(), 0) + "%",
                    Fixed(c.static_hits, 0), Fixed(c.mover_hits, 0), c.flight.Text(1), c.tracking.Text(3),
                    c.cpu.Text(1), c.difference.Text(1)});
  }
  return "flights in moving worlds (over boards and seeds; time: successful flights; diff replans: replans asked "
         "for by a change of eci, per flight)\n" +
         Render(rows, 2);
}

std::string ProgressLine(const api::JobProgress& p, bool bar) {
  std::ostringstream os;
  if (bar) {
    constexpr int kWidth = 30;
    const int filled = p.total > 0 ? kWidth * p.finished() / p.total : 0;
    os << "[" << std::string(filled, '#') << std::string(kWidth - filled, '-') << "] ";
  }
  os << p.id << " " << p.done << "/" << p.total << " done";
  if (p.failed) os << "  " << p.failed << " failed";
  if (p.cancelled) os << "  " << p.cancelled << " cancelled";
  if (p.leased) os << "  " << p.leased << " running";
  const double rate = p.rate_per_s();
  if (rate > 0) os << "  " << Fixed(rate, rate < 1 ? 3 : 1) << " ep/s";
  if (p.terminal()) {
    os << "  " << p.state;
  } else {
    const double eta = p.eta_s();
    os << "  ETA " << (eta < 0 ? std::string("?") : Fixed(eta, 0) + "s");
    if (!p.waiting.empty()) os << "  (waiting: " << p.waiting << ")";
  }
  return os.str();
}

}  // namespace enavi::server
