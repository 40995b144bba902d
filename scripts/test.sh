#!/usr/bin/env bash
# The one test command: on a fresh Debian 12 machine it installs the system packages (apt, as
# root or via sudo), creates .venv with mgn installed, runs the static checks (ruff, ruff format,
# mypy, clang-format, clang-tidy), builds the C++ tests with warnings as errors, and runs them
# all: ctest (GoogleTest, mgn-cli, the find_package(mgn) consumer), then pytest (which also
# checks the import layers and the error classes: tests/python/test_architecture.py), then every
# GoogleTest binary built again with AddressSanitizer (leaks included) and
# UndefinedBehaviorSanitizer.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-system-deps.sh
# The wheel (pip, build/<wheel tag>) and the C++ tests (build/cpp) compile the same core sources:
# ccache lets the second build reuse the first one's objects (third_party_notes/ccache.md).
if command -v ccache >/dev/null; then
  export CMAKE_CXX_COMPILER_LAUNCHER=ccache CXX=g++ CCACHE_BASEDIR="$PWD"
fi
# Warnings are errors in mgn's own code (MGN_WARNINGS_AS_ERRORS) in both builds; the same flags
# also keep the two builds' objects shareable. scikit-build-core reads CMAKE_ARGS.
export CMAKE_ARGS="-DMGN_WARNINGS_AS_ERRORS=ON"
bash scripts/setup-python.sh
. .venv/bin/activate
# Static checks. Tools: the dev extra (pinned ruff, mypy; scripts/setup-python.sh) and Debian's
# clang-format (scripts/install-system-deps.sh). Settings: pyproject.toml and .clang-format.
ruff check python tests benchmarks
ruff format --check python tests benchmarks
mypy
find cpp bindings tests/cpp -name '*.cpp' -o -name '*.hpp' -o -name '*.h' | sort |
  xargs clang-format --dry-run -Werror
# clang-tidy (Debian's, with its run-clang-tidy; settings: .clang-tidy) on mgn's own sources:
# cpp/ and bindings/, and the headers of cpp/include and cpp/src through its HeaderFilterRegex.
# Function size and cognitive complexity ceilings, bugprone-* and performance-* checks; any
# warning is an error. The compile commands come from build/tidy, configured (never built) with
# the same flags as build/cpp plus the Python extension (pybind11 from the dev extra); only the
# generated headers are needed, so it runs before the build.
cmake -S . -B build/tidy -G Ninja -DCMAKE_BUILD_TYPE=Release -DMGN_BUILD_PYTHON=ON \
  -DMGN_INSTALL_CPP=OFF -DMGN_WARNINGS_AS_ERRORS=ON -DCMAKE_EXPORT_COMPILE_COMMANDS=ON \
  -Dpybind11_DIR="$(python -m pybind11 --cmakedir)" >/dev/null
if ! run-clang-tidy -p build/tidy -j 2 -quiet "^$PWD/(cpp|bindings)/" >build/clang-tidy.log 2>&1
then
  grep -E -A4 'warning:|error:' build/clang-tidy.log || cat build/clang-tidy.log
  echo "test.sh: clang-tidy failed (build/clang-tidy.log)" >&2
  exit 1
fi
cmake -S . -B build/cpp -G Ninja -DCMAKE_BUILD_TYPE=Release -DMGN_BUILD_TESTS=ON \
  -DMGN_WARNINGS_AS_ERRORS=ON >/dev/null
cmake --build build/cpp
ctest --test-dir build/cpp --output-on-failure
# The core under ASan + UBSan (MGN_SANITIZE: mgn's own code only; -O1, line tables for the
# reports), exercised by every GoogleTest binary: every test_* target of build/asan, so a new
# one joins without an edit here. Any report fails the command; tests/sanitizers/ holds the
# suppressions of third-party code. The sanitized build compiles at a lower priority while
# pytest runs (pytest leaves part of the two cores idle); its binaries run after pytest.
cmake -S . -B build/asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DMGN_BUILD_TESTS=ON -DMGN_BUILD_PYTHON=OFF \
  -DMGN_BUILD_CLI=OFF -DMGN_INSTALL_CPP=OFF -DMGN_WARNINGS_AS_ERRORS=ON \
  -DMGN_SANITIZE=address,undefined >/dev/null
mapfile -t asan_tests < <(ninja -C build/asan -t targets | sed -nE 's/^(test_[a-z0-9_]+): phony$/\1/p')
if ((${#asan_tests[@]} == 0)); then
  echo "test.sh: no GoogleTest target found in build/asan" >&2
  exit 1
fi
# Four binaries run all their tests but the slowest under the sanitizers (--gtest_filter, the
# tests left out named below): those repeat code the remaining tests of the binary already run
# under the sanitizers, on larger inputs or many more samples (whole drops and shake grids run
# twice to compare two settings, Monte Carlo and brute-force sweeps). Together they take about
# 95 s of CPU time under the sanitizers, twice the rest of the four binaries. Every other binary
# runs all its tests.
declare -A asan_filter=(
  [test_drop]="-Drop.FullAndReducedHullsBothSettleTheSamePile:Drop.SameSeedSamePosesOtherSeedOtherPoses"
  [test_shake]="-Shake.SkippingSeparatedPairsChangesNoTrial:Staircase.ResultsDoNotDependOnThreadCountWithUnevenGrasps:Staircase.ShakeTestScoresEqualTheFullGridOnABox"
  [test_path_bsdf]="-PathBsdf.SamplingPdfIntegratesToTheFractionOfValidSamples"
  [test_hole_walker]="-HoleWalker.PlateWithHolesSeamAndSecondLayerEqualsBruteForce"
)
nice -n 10 cmake --build build/asan --target "${asan_tests[@]}" >build/asan-build.log 2>&1 &
asan_build=$!
python -m pytest
if ! wait "$asan_build"; then
  cat build/asan-build.log
  echo "test.sh: the sanitized build failed (build/asan-build.log)" >&2
  exit 1
fi
export ASAN_OPTIONS=detect_leaks=1:strict_init_order=1:detect_stack_use_after_return=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitizers/lsan.supp"
for t in "${asan_tests[@]}"; do
  (cd build/asan/tests/cpp && "./$t" --gtest_brief=1 --gtest_filter="${asan_filter[$t]:-*}")
done
echo "test.sh: every check passed"
