#!/usr/bin/env bash
# The sanitizer run (docs/install.md "Style and sanitizers"): tests of the AddressSanitizer +
# UndefinedBehaviorSanitizer build that .ci/sanitizers.sh makes in build-asan (.ci/setup.sh
# builds it when CI is set). Any sanitizer finding fails the test that hit it, and so this one.
# Exit 77 (ctest: skipped) when there is no such build.
# Usage: sanitized_suite.sh SANITIZER_BUILD_DIR SOURCE_DIR [default|heavy|all|unit]
#   default (the default suite's ci.SanitizedTests): the unit tests and every system test but
#            the heavy ones below, a few minutes on 2 cores;
#   heavy    (ci.SanitizedHeavyTests, label validate): the heavy tests alone;
#   all      (.ci/sanitizers.sh): everything; unit: the unit tests alone.
# The heavy tests repeat, thousands of times at -O1 under instrumentation, code that
# the default scope already runs once (seconds each unsanitized, minutes sanitized; measured on
# 2 cores beside another build, 2026-11-22): the elasto-plastic and global-start calibrations
# (600 s and 540 s: the driver integrated over every probe of every start), the tiny run of
# every stage and the figure overlay (258 s, 255 s), a pressure branch (56 s), a slowly jammed
# packing (46 s), the damaged-file walk (1739 runs of the binary: over 600 s) and the sweep
# (109 s); and the model selection over every law and the exact-derivative checks of the two
# integrated laws (600 s, 120 s, 90 s beside the rest of the suite in CI, 2026-11-23: the
# selection alone ran past its time limit); and the resumed runs (11 tiny runs between them,
# stopped and resumed: the same stages as the tiny run of every stage, not measured sanitized);
# and the frictional linear response against the engine's dynamic probes (495 s sanitized,
# 68-98 s unsanitized: four probes relaxed to E_kin/E_el < 1e-12; CI 2026-11-23, where it made
# the sanitized suite 601 s of the 10-minute budget), its twin with rolling resistance
# (7-8 s unsanitized: the same probes) and the same at t_c / 10 (22 s unsanitized); and, since
# the default suite took 13.4 min on a slower host (a Zen 5 VM, 2026-11-30: the sanitized
# scope 698 s of it), the system tests of 12 s and more sanitized there (384 s alone on 2
# idle cores, 766 s of test time): the frictional states through a results file (85 s, 55 s),
# sheared frictional packings run for thousands of steps (20, 19, 16, 16, 13 s: the frictional
# engine's code runs sanitized in the shorter friction tests, ContactsFirst... and
# BitIdenticalOnOneAndTwoThreads among them), both forms of the pair loop (15 s: the
# determinism across teams stays), the log of every DEM stage (15 s) and the figure tests that
# draw in Python (39, 15, 12 s: the interpreter is not instrumented). Then, the fresh-clone CI
# of that trim took 639 s (ci.SanitizedTests 531 s), so also the tests of 8.4 s and more
# sanitized whose code shorter sanitized tests run too: the last figure test drawing in Python
# (11.3 s; Plot.RefusesAFileThatIsNotOurs and FaultsSystem.AnInterruptedPlot... start the
# binary's plot), a hot deforming packing's neighbour list (9.4 s; its two siblings stay), the
# rolling resistance against LAMMPS (9.2 s, mostly LAMMPS; the sliding history against LAMMPS
# stays), a drained path through the CLI (8.9 s; dem.Paths stays), a state's probes from a
# results file (8.9 s; five other app.Probe tests stay) and the fit's linear scaling (8.4 s).
# The figures drawn by /usr/bin/python3 after PATH's interpreter lacks the modules (6 s
# unsanitized, the seed-like file's figures again) joined them: its sibling with a user's
# script, 1.5 s, runs the same fallback of the binary sanitized. So did bench/stage_threads.py's
# rounds (eight tiny runs of two DEM stages, 5 s unsanitized: stages that dem.RunStages runs
# sanitized; the script itself is Python). Then, on a host where the default suite took 570.9 s
# and 656.9 s in two fresh-clone CIs (an Intel Xeon VM, 2026-12-06; ci.SanitizedTests 458 s and
# 552 s), the two longest sanitized tests whose code others run sanitized: calibrate()'s
# warning that trial points of a global search failed on the substep cap (80 s sanitized, 2.2 s
# unsanitized: a global search integrating every probe; the tally it reports stays, in
# DriverLoad.TallyCounts..., and the cap's other warning) and bench --phases (52 s sanitized,
# 4 s unsanitized: two packings of 1000 prepared for a team of two; the phase clocks stay, in
# dem.PhaseTiming, and the bench's own code in the other Bench tests). A run with its standard
# streams closed (the whole tiny run again, 12 s sanitized, for a check of three system calls
# at start that every sanitized test runs) joined them on 2026-12-06. On 2026-12-07 two
# checks against a second method joined them (CI, 2 cores): the cell's work against the
# energy and sliding dissipation (70.8 s sanitized, 2.5 s unsanitized: 60,000 steps, most of
# them frictional; the frictional loop stays sanitized in the Friction tests) and a doubled
# packing's negative modes by a dense eigensolver (32.2 s sanitized, 1.6 s unsanitized: three
# 1500 x 1500 eigenproblems; the pivot count stays, in UnstableSimpleCubicIsDetected). Later that
# day its sibling, the same saddle left (two such eigenproblems, 1.3 s unsanitized): leave_saddle
# itself stays sanitized in app's Probe.ASaddleHasNoLinearResponseUntilItIsLeft.
set -uo pipefail
dir=${1:?sanitizer build folder}
src=${2:?source folder}
scope=${3:-default}
heavy='Selection\.PicksTheGeneratingLaw|Derivatives\.ElastoplasticExactMatchesCentralDifferences|Derivatives\.HypoplasticExactMatchesCentralDifferences|ElastoplasticCalibration\.RecoversEvolutionParametersFromPathAndEnvelopes|GlobalStart\.RescuesAPoorStartWhereLocalFails|RunStages\.TinyScenarioWritesTheInterfacesSchema|Overlay\.FiguresAndReportShowEveryCalibratedLaw|RunStages\.PressureBranchRepeatsThePathAndStatesAtALowerVolumeFraction|Jamming\.SlowlyCompressedW3PackingJams|FaultsSystem\.EverySubcommandRefusesDamagedResultsFilesInOneLine|Sweep\.QuickRunWritesFilesAndItsNumbersHold|Resume\.AfterSigtermGivesTheUninterruptedRunsFile|ResumeRefusal\.|LinearResponseFriction\.MatchesTheEnginesDynamicProbesAtTheStatesStepAndATenthOfIt|LinearResponseFriction\.WithRollingResistanceMatchesTheEnginesDynamicProbes|FrictionState\.RestsWithTorquesAndContinuesBitIdentically|FrictionState\.TheDynamicMethodsRunAndTheSeriesCarryTheSliding|FrictionSystem\.StressIsSymmetricAtRest|FrictionSystem\.SlidingFlagIsTheLastStepsSlip|FrictionSystem\.SpringsSurviveListRebuilds|FrictionSystem\.CoordinationOfNonRattlersUsesTheFrictionalRule|DensePreparation\.LessFrictionInTheLoadingJamsDenser|Determinism\.BothFormsOfThePairLoopGiveTheSameBits|Progress\.ALogGetsPlainLinesForEveryDemStage|Plot\.TwoProcessesDrawTheSameFiguresAsOne|Plot\.EveryFigureOfATinyRunHasEqualAxesLegendsAndErrorBars|Plot\.RunsTheScriptOfTheOptionTheEnvironmentOrTheInstallPrefix|Plot\.DrawsEveryFigureOfASeedLikeFile|Plot\.DrawsWithDebiansPythonWhenPathsOneLacksTheModules|NeighborList\.NeverMissesAContactInAHotDeformingPacking|FrictionLammps\.RollingResistanceMatchesLammps|Cli\.ADrainedPathFromAPressureIsRunStoredAndReported|Probe\.AResultsFileStateGivesTheStoredEnvelopesAndFits|FitScaling\.WorkGrowsLinearlyWithThePoints|StageThreads\.TimesEveryStageForBothSettingsIdleAndLoadedInAlternatedRounds|DriverLoad\.CalibrateSaysWhenTrialPointsFailedOnTheCap|Bench\.PhasesSayWhereAStepGoesPerThreadOfTheTeam|Cli\.ARunWithItsStandardStreamsClosedKeepsItsResultsFileWhole|Energy\.TheCellsWorkIsTheEnergyGainedPlusTheSlipsWork|LinearResponse\.ADoubledPackingsNegativeModesAreCountedExactly|LinearResponse\.ASaddleIsLeftAlongItsNegativeModesToAMinimum'
if [ ! -f "$dir/CTestTestfile.cmake" ]; then
  echo "no sanitizer build in $dir: not run (bash .ci/sanitizers.sh builds and runs it)"
  exit 77
fi
# detect_leaks: a leak is a finding. The suppressions name leaks of the libraries we link
# (not ours), each with its reason. UBSan stops at its first finding and prints its stack.
export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:check_initialization_order=1"
export LSAN_OPTIONS="suppressions=$src/.ci/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# The style and sanitizer entries of the sanitizer build itself are never run again, nor the
# install test (it builds a consumer project: nothing of ours runs under the sanitizers).
skip='^ci\.|^install\.'
case "$scope" in
  default) ctest --test-dir "$dir" -LE 'validate' -E "$skip|$heavy" --output-on-failure \
             -j "${JOBS:-2}" ;;
  heavy) ctest --test-dir "$dir" -R "$heavy" --output-on-failure -j "${JOBS:-2}" ;;
  all) ctest --test-dir "$dir" -LE 'validate' -E "$skip" --output-on-failure -j "${JOBS:-2}" ;;
  unit) ctest --test-dir "$dir" -L unit --output-on-failure -j "${JOBS:-2}" ;;
  *) echo "sanitized_suite.sh: scope '$scope' is not default, heavy, all or unit"; exit 2 ;;
esac
