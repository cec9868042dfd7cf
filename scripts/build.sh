#!/usr/bin/env bash
# Configures and builds E-Navi Farm (Release) into ${BUILD_DIR:-build}.
# --sanitize: ASan + UBSan with clang, the libFuzzer harnesses of tests/fuzz included, into
# ${BUILD_DIR:-build-asan}; only what the unit and fault tests and the fuzzers need (what CI
# runs there).
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
    targets=(tests_unit fuzzers)
    if cmake --build "$build_dir" --target help | grep -qw tests_fault; then targets+=(tests_fault); fi
    ;;
  *)
    echo "usage: $0 [--sanitize]" >&2
    exit 2
    ;;
esac
cmake --build "$build_dir" -j"$(nproc)" --target "${targets[@]}"
