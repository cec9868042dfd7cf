#pragma once
// Shared by the harnesses. What every harness asserts about rejected input: it is the usual error, an exception whose
// message names the source (the file name the harness passed in), never a crash or a foreign
// exception type escaping with a message nobody can act on.

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include "api/episode.h"

namespace enavi::fuzz {

/// A catalog shaped like the registries' (method names, real and integer ranges, boards,
/// scenarios, clocks); the registries live above api, which the harnesses need not link.
inline api::Catalog Catalog() {
  api::Catalog c;
  c.methods = {{"baseline", "", {{"planner.v_max", 0.1, 10.0, false}}},
               {"fixed", "", {{"planner.v_max", 0.1, 10.0, false}, {"map.resolution", 0.05, 0.5, false}}},
               {"enavi", "", {{"strategy.f_adapt", 1, 30, true}}}};
  c.boards = {"pi4b", "tx2", "x86", "host"};
  c.scenarios = {"s1", "s2", "canyon", "empty"};
  c.clocks = {"virtual", "emulated"};
  return c;
}

/// Aborts (a libFuzzer crash, the input is saved) when `e` does not name `source`.
inline void CheckNamesSource(const std::exception& e, std::string_view source) {
  if (std::string_view(e.what()).find(source) != std::string_view::npos) return;
  std::fprintf(stderr, "rejected input without the source '%.*s' in the message: %s\n",
               static_cast<int>(source.size()), source.data(), e.what());
  std::abort();
}

/// Aborts with `what` when `ok` is false: an invariant the harness checks on accepted input.
inline void Check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "invariant violated: %s\n", what);
  std::abort();
}

}  // namespace enavi::fuzz
