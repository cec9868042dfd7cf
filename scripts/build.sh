#!/usr/bin/env bash
# Configures and builds E-Navi Farm (Release) into ${BUILD_DIR:-build}.
# --sanitize [TARGET...]: ASan + UBSan with clang at -O1, the libFuzzer harnesses of tests/fuzz
# included, into ${BUILD_DIR:-build-asan}; by default only what the unit, fault, fuzz and
# sanitizer tests need, or the TARGETs given (CI: fuzzers tests_sanitizer, what fits its time).
# The CMAKE_<LANG>_COMPILER_LAUNCHER environment variables (e.g. ccache) are honoured by CMake.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  "")
    build_dir=${BUILD_DIR:-build}
    cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >/dev/null
    targets=(all)
    ;;
  --sanitize)
    build_dir=${BUILD_DIR:-build-asan}
    CC=clang CXX=clang++ cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DENAVI_FUZZ=ON \
      -DENAVI_BUILD_BENCH=OFF -DCMAKE_DISABLE_FIND_PACKAGE_pybind11=ON >/dev/null
    shift
    if [ $# -gt 0 ]; then
      targets=("$@")
    else
      targets=(tests_unit tests_fault fuzzers tests_sanitizer)
    fi
    ;;
  *)
    echo "usage: $0 [--sanitize [TARGET...]]" >&2
    exit 2
    ;;
esac
cmake --build "$build_dir" -j"$(nproc)" --target "${targets[@]}"
