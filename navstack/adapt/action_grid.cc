#include "navstack/adapt/action_grid.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace enavi::navstack {
namespace {

void CheckLevels(const std::vector<double>& levels, const char* name, bool positive) {
  if (levels.empty()) throw std::invalid_argument(std::string("action grid: ") + name + " is empty");
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const double f = levels[i];
    if (!std::isfinite(f) || f < 0.0 || (positive && f <= 0.0)) {
      throw std::invalid_argument(std::string("action grid: ") + name + "[" + std::to_string(i) +
                                  "] = " + std::to_string(f) +
                                  (positive ? " must be finite and > 0" : " must be finite and >= 0"));
    }
    if (i > 0 && !(levels[i] > levels[i - 1])) {
      throw std::invalid_argument(std::string("action grid: ") + name +
                                  " must be strictly ascending (index " + std::to_string(i) + ")");
    }
  }
}

}  // namespace

ActionGrid::ActionGrid()
    : ActionGrid(FromLevels(DefaultPerceptionLevels(), DefaultCollisionLevels(),
                            DefaultDifferenceLevels(), true)) {}

ActionGrid ActionGrid::FromLevels(const std::vector<double>& f_per, const std::vector<double>& f_col,
                                  const std::vector<double>& f_dif, bool drop_cascade_violations) {
  CheckLevels(f_per, "f_per", true);
  CheckLevels(f_col, "f_col", false);
  CheckLevels(f_dif, "f_dif", false);
  std::vector<TaskFrequencies> actions;
  for (double p : f_per) {
    for (double c : f_col) {
      if (drop_cascade_violations && c > p) continue;
      for (double d : f_dif) actions.push_back({p, c, d});
    }
  }
  return ActionGrid(std::move(actions));
}

ActionGrid ActionGrid::FromTriples(std::vector<TaskFrequencies> triples, const std::string& what) {
  if (triples.empty()) throw std::invalid_argument(what + ": no actions");
  for (std::size_t i = 0; i < triples.size(); ++i) {
    const TaskFrequencies& t = triples[i];
    const bool ok = std::isfinite(t.f_per) && std::isfinite(t.f_col) && std::isfinite(t.f_dif) &&
                    t.f_per > 0.0 && t.f_col >= 0.0 && t.f_dif >= 0.0;
    if (!ok) {
      throw std::invalid_argument(what + ": action " + std::to_string(i) +
                                  " needs finite f_per > 0, f_col >= 0, f_dif >= 0");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (triples[j] == t) {
        throw std::invalid_argument(what + ": action " + std::to_string(i) + " repeats action " +
                                    std::to_string(j));
      }
    }
  }
  return ActionGrid(std::move(triples));
}

const TaskFrequencies& ActionGrid::At(int index) const {
  if (index < 0 || index >= size()) {
    throw std::out_of_range("ActionGrid::At: index " + std::to_string(index) + " outside [0, " +
                            std::to_string(size()) + ")");
  }
  return actions_[static_cast<std::size_t>(index)];
}

std::optional<int> ActionGrid::Find(const TaskFrequencies& f) const {
  for (int i = 0; i < size(); ++i) {
    if (actions_[static_cast<std::size_t>(i)] == f) return i;
  }
  return std::nullopt;
}

int ActionGrid::Nearest(const TaskFrequencies& f) const {
  int best = 0;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < size(); ++i) {
    const TaskFrequencies& a = actions_[static_cast<std::size_t>(i)];
    const double d2 = (a.f_per - f.f_per) * (a.f_per - f.f_per) +
                      (a.f_col - f.f_col) * (a.f_col - f.f_col) +
                      (a.f_dif - f.f_dif) * (a.f_dif - f.f_dif);
    if (d2 < best_d2) {
      best_d2 = d2;
      best = i;
    }
  }
  return best;
}

}  // namespace enavi::navstack
