#!/usr/bin/env bash
# Build the unit tests with AddressSanitizer + UndefinedBehaviorSanitizer (build-asan) and run them.
# Left out, because the Release run of tools/test.sh covers them and they would take minutes under
# the sanitizers: the app group (it runs the talus program), the verification benchmarks (whole
# physics runs), and the reliability tests that spawn the program or run whole scenes (Crash.*,
# HardCases.*), and the long whole-run tests (the column collapses, Drucker-Prager and mu(I), the
# bit-identical restarts at six steps, the terrain slides' stopping distance and transition crossing,
# the terrain slide's thread-count check, the PIC share's energy budget, mu(I)'s rate-independent
# limit, and three of the thread-count checks (block order, smaller blocks, MLS): 27-120 s each
# under the sanitizers, which kept CI near its 30 minutes; shorter tests of the same code run here:
# TerrainSlide.ThirtyDegreePlaneFine, PicDamping.BitIdenticalForOneAndTwoThreads,
# MuICollapse.SeparatedParticlesAreStressFree, Solver.BitIdenticalForOneAndTwoThreads(ForEveryShapeAndScheme),
# MlsSolver.DisabledSmoothingIsTheUnsmoothedSolverBitForBit), and the checks of the tree that are not C++ (Layers.*, SceneSchema.*, Install.*, RunsTable.*,
# Tools.PlotsShowWhatTheRunsDid: scripts that the
# Release run covers; this build has no talus program to install), and the distributed runs (Mpi.*: Open MPI's own allocations at start-up trip the
# leak checker); -O1 keeps the build short, and so does leaving the AVX-512 kernels out
# (-DTALUS_NO_AVX512=ON: the baseline and AVX2 paths run under the sanitizers; the Release run
# checks the AVX-512 path's bits where the CPU has it). The scene fuzzer (100 000 inputs) does run here.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="${TALUS_JOBS:-$(nproc)}"
bash tools/configure.sh build-asan build-asan.log \
  -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-O1 -DTALUS_SANITIZE=ON -DTALUS_NO_AVX512=ON
targets=()
for group in core material dem scene particles grid shape transfer smoothing boundary solver diagnostics io reliability; do
  if compgen -G "tests/$group/*.cpp" > /dev/null; then targets+=("talus_${group}_tests"); fi  # no sources, no target
done
cmake --build build-asan -j "$jobs" --target "${targets[@]}" >> build-asan.log 2>&1 || { tail -50 build-asan.log; exit 1; }
echo "sanitize build: ok (log in build-asan.log)"
# Any sanitizer report fails the test; leak checking stays on.
export ASAN_OPTIONS="halt_on_error=1:abort_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
OMP_WAIT_POLICY=PASSIVE ctest --test-dir build-asan --output-on-failure -j "$jobs" \
  -E '^(Cli|DemSpringsCli|ElementTestCli|ElasticBenchmarks|Crash|HardCases|Layers|SceneSchema|Install|RunsTable|Mpi)\.|^Tools\.(PlotsShowWhatTheRunsDid|ScalingToolsRefuseEarlyAndRecordProvenance)|^GranularCollapse\.Column|^MuICollapse\.(Column|RateIndependentLimit)|^TerrainSlide\.(HorizontalPlaneStoppingDistance|BlockCrossesTheTransition|BitIdenticalForOneAndTwoThreadsOnATerrainGrid)|^PicDamping\.TheBudgetCounts|^Solver\.BitIdenticalFor(EitherBlockOrder|OneAndThreeThreadsWithSmallerBlocks)|^MlsSolver\.BitIdenticalForOneAndTwoThreads|^Checkpoint\.Restart|_NOT_BUILT'
