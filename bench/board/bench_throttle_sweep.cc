// Fidelity of the board emulation: expected vs measured slowdown over boards, CFS periods and
// the two per-core mechanisms (per-thread cgroup quota, SCHED_DEADLINE speed server).
//   bench_throttle_sweep [--quick] [--board id:cores:speed]... [--periods 5000,10000,...]
//                        [--dilations 1,2,...] [--deadline] [--json]
// Needs root (creates cgroups under enavi/); prints one line per run, JSON lines with --json.
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "server/bench/throttle_bench.h"

int main(int argc, char** argv) {
  using namespace enavi::bench;
  bool json = false, quick = false, deadline = false;
  std::vector<long> periods{20'000};
  std::vector<double> dilations{0.0};
  std::vector<std::string> board_args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--json") json = true;
    else if (a == "--quick") quick = true;
    else if (a == "--deadline") deadline = true;
    else if (a == "--board" && i + 1 < argc) board_args.push_back(argv[++i]);
    else if ((a == "--periods" || a == "--dilations") && i + 1 < argc) {
      std::stringstream ss(argv[++i]);
      std::string item;
      if (a == "--periods") periods.clear(); else dilations.clear();
      while (std::getline(ss, item, ',')) {
        if (a == "--periods") periods.push_back(std::stol(item)); else dilations.push_back(std::stod(item));
      }
    } else {
      std::fprintf(stderr, "usage: %s [--quick] [--board id:cores:speed]... [--periods us,...] [--dilations k,...] [--deadline] [--json]\n", argv[0]);
      return 2;
    }
  }
  struct Board { const char* id; int cores; double speed; };
  // Per-core speeds spanning ~0.2-0.6 of this host and 2-6 cores (the acceptance range).
  std::vector<Board> boards{{"slow4", 4, 0.2}, {"mid4", 4, 0.35}, {"mid6", 6, 0.3},
                            {"fast2", 2, 0.6}, {"fast4", 4, 0.5}, {"fast6", 6, 0.6}};
  if (quick) boards = {{"mid4", 4, 0.35}};
  static std::vector<std::string> ids;  // keeps the ids of --board id:cores:speed alive
  if (!board_args.empty()) boards.clear();
  for (const std::string& arg : board_args) {
    std::stringstream ss(arg);
    std::string id, cores, speed;
    std::getline(ss, id, ':');
    std::getline(ss, cores, ':');
    std::getline(ss, speed, ':');
    ids.push_back(id);
    boards.push_back({nullptr, std::stoi(cores), std::stod(speed)});
  }
  for (std::size_t i = 0; i < board_args.size(); ++i) boards[i].id = ids[i].c_str();
  if (!json) {
    std::printf("%-6s %5s %5s %6s %7s %-26s %7s %8s %8s %8s %8s\n", "board", "cores", "speed",
                "k", "period", "phase", "threads", "expected", "measured", "rel_err", "worst_t");
  }
  int failures = 0;
  for (const Board& b : boards) {
    for (long period : periods) {
      for (double k : dilations) {
        ThrottleBenchOptions o;
        o.period_us = period;
        o.dilation = k;
        o.deadline_servers = deadline;
        ThrottleBenchResult r;
        try {
          r = RunThrottleBench(b.id, {b.cores, b.speed}, o);
        } catch (const std::invalid_argument& e) {
          std::fprintf(stderr, "%s period %ld: %s\n", b.id, period, e.what());
          continue;
        }
        if (json) {
          std::printf("%s\n", ToJson(r).dump().c_str());
          std::fflush(stdout);
          continue;
        }
        if (!r.ok) {
          std::printf("%-6s: %s\n", b.id, r.message.c_str());
          ++failures;
          continue;
        }
        for (const ThrottlePhase& p : r.phases) {
          std::printf("%-6s %5d %5.2f %6.2f %7ld %-26s %7d %8.3f %8.3f %+8.3f %+8.3f %s\n", b.id,
                      b.cores, b.speed, r.quota.dilation, period, p.name.c_str(), p.threads,
                      p.expected_slowdown, p.measured_slowdown, p.relative_error,
                      p.max_thread_error, p.note.c_str());
        }
        std::fflush(stdout);
      }
    }
  }
  return failures == 0 ? 0 : 1;
}
