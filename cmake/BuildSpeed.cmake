# Build time. CI builds both trees from scratch (no compiler cache): the Release tree and its
# tests, then the sanitizer tree's fuzz harnesses and self-check, all within its 30 minutes;
# docs/reliability.md ("CI's time") has the measurements. Every setting here changes how long the
# build takes, not what the code under test computes.
#
# Unity builds (CMAKE_UNITY_BUILD; on unless set on the command line): a target's sources are
# compiled in batches of up to 8, each batch one translation unit, so the third-party headers
# they share (Eigen, OMPL, Bullet, nlohmann/json, spdlog, CLI11) are parsed, and their inline
# functions optimised (and instrumented), once per batch instead of once per file. A source that
# does not combine with the others of its target is named in enavi_unity_exclusions() with the
# reason.
if(NOT DEFINED CMAKE_UNITY_BUILD)
  set(CMAKE_UNITY_BUILD ON)
endif()

# Test sources (enavi_add_test) compile at less optimisation than the code under test, which keeps
# its build type's: they only drive it, and optimising each test file's gtest and Eigen
# instantiations at -O3 costs 1.3 times the compile time of -O1 and 1.8 times that of -O0
# (planner_test.cc: 12.9, 9.7 and 7.3 CPU s). Release: -O1, because the linker may keep a test
# file's copy of an inline function the library shares (Eigen, OctoMap templates), and at -O0
# the occupancy-map tests ran 3.5 to 19 times slower. The sanitizer tree: -O0 (its code is -O1).
if(ENAVI_SANITIZE)
  set(ENAVI_TEST_COMPILE_OPTIONS -O0)
else()
  set(ENAVI_TEST_COMPILE_OPTIONS -O1)
endif()

# lld links the binaries (about 100 test programs, each with the static libraries they use).
find_program(ENAVI_LLD NAMES ld.lld)
if(ENAVI_LLD)
  add_link_options(-fuse-ld=lld)
endif()

# Sources that do not combine in a unity batch (each defines a file-local helper or constant that
# another source of its target defines too, or must include Eigen before another source's
# httplib.h, whose <resolv.h> defines the macro `_res`): each is compiled on its own.
function(enavi_unity_exclusions)
  set(exclusions
      enavi_adapt navstack/adapt/resolution_adapter.cc          # RequireNonNegative
      enavi_perception navstack/perception/occupancy_map.cc     # Require
      enavi_perception navstack/perception/points.cc            # Require
      enavi_report server/report/top_down.cc                    # kPi
      enavi_http server/http/dashboard_routes.cc)               # Eigen before httplib.h
  while(exclusions)
    list(POP_FRONT exclusions target source)
    set_source_files_properties(${PROJECT_SOURCE_DIR}/${source} TARGET_DIRECTORY ${target}
                                PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
  endwhile()
endfunction()
