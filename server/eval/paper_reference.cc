#include "server/eval/paper_reference.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tuple>

#include "worlds/generators.h"

namespace enavi::server {

const std::vector<PaperRow>& PaperHilTable() {
  static const std::vector<PaperRow> rows = {
      {"pi4b", "enavi", {50.1, 40.7, 51.2, 64.0, 49.1}, {49.6, 51.3, 22.6, 44.6, 33.1}, {44.1, 49.5, 17.6, 43.4, 31.6}},
      {"pi4b", "baseline", {47.9, 85.0, 68.2, 78.6, 73.5}, {75.1, 119.3, 26.0, 65.8, 66.2}, {50.4, 65.5, 18.4, 44.0, 36.7}},
      {"tx2", "enavi", {50.8, 59.2, 51.7, 49.1, 45.9}, {46.7, 52.3, 18.3, 50.2, 33.2}, {44.3, 53.5, 16.2, 44.6, 31.9}},
      {"tx2", "baseline", {60.2, 95.9, 81.5, 91.5, 78.7}, {70.9, 144.5, 27.9, 67.7, 54.0}, {46.8, 75.3, 20.4, 43.3, 33.8}},
      {"nx", "enavi", {25.0, 29.9, 29.5, 47.6, 28.9}, {46.1, 53.2, 17.4, 44.4, 32.6}, {43.9, 50.7, 17.5, 42.5, 31.7}},
      {"nx", "baseline", {36.7, 64.9, 45.8, 59.1, 44.1}, {89.9, 128.5, 27.1, 122.6, 52.0}, {56.2, 69.0, 20.6, 76.0, 34.0}},
      {"opi5", "enavi", {27.7, 36.5, 39.0, 36.9, 39.7}, {46.0, 53.3, 23.3, 44.1, 33.9}, {44.8, 50.0, 17.6, 42.1, 31.8}},
      {"opi5", "baseline", {40.3, 59.2, 53.6, 56.9, 51.3}, {69.6, 102.3, 27.0, 65.3, 48.6}, {46.6, 56.6, 18.1, 42.4, 32.7}},
      {"x86", "enavi", {38.2, 46.9, 38.2, 46.3, 41.2}, {45.8, 53.0, 27.2, 44.5, 32.0}, {44.3, 52.9, 21.6, 42.9, 32.0}},
      {"x86", "baseline", {42.5, 57.8, 50.7, 47.4, 48.6}, {74.8, 122.0, 33.6, 67.6, 47.8}, {49.8, 67.1, 24.3, 46.5, 32.7}},
  };
  return rows;
}

const PaperRow* FindPaperRow(const std::string& board, const std::string& method) {
  for (const PaperRow& r : PaperHilTable()) {
    if (r.board == board && r.method == method) return &r;
  }
  return nullptr;
}

const std::array<PaperEciRange, 5>& PaperEciRanges() {
  // S1 city with varying-height buildings, S2 park with trees and a pavilion, S3 indoor hall with
  // varying furniture, S4 city with similar-height buildings, S5 village with house, bridge, river.
  static const std::array<PaperEciRange, 5> ranges = {
      {{0.06, 0.87}, {0.08, 0.97}, {0.19, 0.83}, {0.26, 0.86}, {0.25, 0.79}}};
  return ranges;
}

const PaperEciRange* FindPaperEciRange(const std::string& scenario) {
  const std::vector<std::string>& ids = PaperScenarios();
  const auto it = std::find(ids.begin(), ids.end(), scenario);
  return it == ids.end() ? nullptr : &PaperEciRanges()[static_cast<std::size_t>(it - ids.begin())];
}

const std::vector<std::string>& PaperBoards() {
  static const std::vector<std::string> boards = [] {
    std::vector<std::string> b;
    for (const PaperRow& r : PaperHilTable())
      if (std::find(b.begin(), b.end(), r.board) == b.end()) b.push_back(r.board);
    return b;
  }();
  return boards;
}

const std::vector<std::string>& PaperScenarios() {
  static const std::vector<std::string> scenarios = [] {
    std::vector<std::string> s;
    for (const worlds::GeneratorInfo& g : worlds::Generators())
      if (g.paper_path_length > 0) s.push_back(g.id);
    if (s.size() != std::tuple_size_v<decltype(PaperRow::cpu_pct)>)
      throw std::logic_error("the paper has " + std::to_string(std::tuple_size_v<decltype(PaperRow::cpu_pct)>) +
                             " scenarios, the generators " + std::to_string(s.size()));
    return s;
  }();
  return scenarios;
}

}  // namespace enavi::server
