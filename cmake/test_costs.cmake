# The order CTest starts the long tests in (included at test time: every test directory adds
# this file after its own tests; cmake/shelfcross_module.cmake, app/CMakeLists.txt).
#
# With tests run side by side (`ctest -j N`), CTest starts the tests in descending COST, and
# without a record of earlier runs (Testing/Temporary/CTestCostData.txt, absent in a fresh
# build, as on CI) every test's COST is 0 and the order is the order of definition: a long test
# defined late can start last and leave the other cores idle at the end. COST here is about the
# test's CTest time in seconds on a 2-core machine, rounded; only the order it gives matters.
# Once CTest has timed a test, its own record takes over.
#
# The end-to-end flights against the emulator (paced by the wall clock, one at a time: a
# resource lock, app/CMakeLists.txt) come first: one after another, beside the rest, they end
# long before the other tests do.
#
# A name that no test has (yet) is skipped: each directory includes this file, and the names
# defined so far are set.
set(_shelfcross_test_costs
  # the flights (app/CMakeLists.txt): 1000 and their seconds, above every other
  TelloEndToEnd.SameWithFivePercentLossOnEveryChannel 1035
  TelloEndToEnd.PilotFliesTheEmulatorTakesInventoryCrossesAndLands 1021
  TelloEndToEnd.CalibrationFlightFacingTheShelfStopsAndLands 1007
  # the rest, longest first
  Identify.NoiseFreeRecordsOfDronesAcrossTheRangesAreRecoveredWithoutTheRoundingsBias 39
  Warehouse.EveryStrategyInventoriesTheRowAndThroughTheCellsIsShortestOverTheSdkLink 36
  docs_runnable_blocks 30
  CmdSearch.ResumesToTheUninterruptedSearchAndRepeatsTheCampaignInRoundZero 29
  SdkLink.LostLandWithoutTheStopSticksRuleFliesIntoTheWall 25
  SdkLink.ABackOffUnderWayIsNeverTurnedIntoACrossing 25
  Senses.SensesOutsideAScenariosRangesAreNamedAndTheCalibratedScenarioHoldsThem 23
  CampaignWorkers.AStoppedCampaignDoesNotCountTheStopAgainstItsRun 20
  Campaign.SmallDefaultCampaignNeverTouchesTheShelfAndMostlyCrosses 19
  SdkLink.AThreeSecondOutageIsRiddenThroughAndOnePastTheBoundLands 18
  SdkLink.AStrongAutopilotIsMeasuredAndItsSticksScaled 18
  SdkLink.LostFirstLandIsSentAgainBeforeTheFlightSoftwaresTimeout 17
  MpiSearch.ThreeRanksEqualOneProcess 14
  SdkLink.ALineHoldNotMeasuredAtTheLastAttemptReReadsRatherThanDeclines 14
  Warehouse.ThroughTheCellsCrossesAndInventoriesAllFiveShelves 13
  CmdCampaign.ShardsMergedEqualOneProcess 12
  CmdCampaign.KilledMidwayAndRestartedEqualsUninterrupted 11
  Identify.RecoversAKnownDroneFromItsCalibrationLog 10
  MpiCampaign.ThreeRanksEqualOneProcess 10
  ResponseFit.CorrelatedNoiseWidensTheQuantisedRecordsIntervals 10
  SdkLink.FivePercentLossOnEveryChannelNeverTouchesAndListsNothingWrong 10
  ReplayOverlay.TagsAreDrawnOnThePictureTheyCameFrom 9
  Warehouse.EveryStrategyInventoriesTheRowAndThroughTheCellsIsShortestOverTheIdealLink 9
  MpiCampaign.KilledWorkerRankThenResumeCompletesEveryRunOnce 9
  CmdFrames.NominalSequenceRendersAndBothPipelinesDecideTheSame 8
  CompareCommand.WritesTableAndPlotsForThreeStrategiesWithTheSameDraws 8
  MpiCampaign.KilledWorkerRankUnderRecoveryCompletesInOneGo 8
  PictureDamage.RowsOutsideTheDamageAreTheLossFreePicture 8
)
list(LENGTH _shelfcross_test_costs _shelfcross_n)
math(EXPR _shelfcross_last "${_shelfcross_n} - 1")
foreach(_shelfcross_i RANGE 0 ${_shelfcross_last} 2)
  math(EXPR _shelfcross_j "${_shelfcross_i} + 1")
  list(GET _shelfcross_test_costs ${_shelfcross_i} _shelfcross_name)
  list(GET _shelfcross_test_costs ${_shelfcross_j} _shelfcross_cost)
  set_tests_properties(${_shelfcross_name} PROPERTIES COST ${_shelfcross_cost})
endforeach()
