# CTest labels of the gtest tests (docs/testing-labels.md). CTest includes this file after
# gtest_discover_tests has added them (TEST_INCLUDE_FILES, through the build tree's
# test_labels_include.cmake, which sets SKYCAL_TESTS_BINARY_DIR). The tests named below are
# `slow` or `browser`; every other discovered test is `fast` (read from the discovery's
# *_tests.cmake files). CTest appends labels, so each test is labelled once, here. A name
# that no longer exists is ignored by CTest.
#
# How they were sorted (2026-11-28, this project's 2-core machine, shared): the binaries of
# the first group were run whole, one at a time under `nice`, and gtest's per-test
# milliseconds read (load average 2.6-19, so the times are high); a test at 5 s or more, or
# one still running when its binary was stopped after 150 s, is `slow`. The second group
# could not be timed (load average 17-19 while six builds ran): they are sorted by what they
# do -- a Ceres fit at more than 128x64 or of several references, a cloud march, a bench or
# batch run, a real photographed frame -- and should be timed and moved when the machine is
# quiet.

# Measured (ms, under load): cloud_noise, fit_cloud_stats, hdr_merge, render_parity,
# response_recovery, lens_unwrap, clouds_parity; cli_test.
set(SKYCAL_SLOW_TESTS_MEASURED
  OutputSafety.InterruptedRunsLeaveNothingBehind                                # 12530 (quiet, whole suite)
  Reliability.APresetInterruptedBetweenItsFilesIsOneWholePreset                 # 11330 (quiet, whole suite)
  CloudNoiseCache.AFlippedByteAnywhereIsRegeneratedWithAWarning                 # 13752
  CloudNoiseCache.AConsistentCacheWithAValueOutOfRangeIsRegeneratedWithAWarning # 6090
  CloudNoiseCache.ATruncatedCacheIsRegeneratedWithAWarning                      # 5326
  FitCloudStats.WiringAtASmallSize                                              # 7391
  HdrMerge.ExposureScaleAcrossSettings                                          # 6727
  HdrMerge.ThreadsGiveIdenticalResults                                          # 6120
  RenderParity.VulkanMatchesCpuReferenceOverSweep                               # 10004
  ResponseRecovery.WithinOneAndAHalfOfTheKnownResponseOnUnseenCurves            # 74461
  ResponseRecovery.HarderCurvesStayBounded                                      # 42018
  ResponseRecovery.AutoMeetsTheTargetOnSharedAndPerChannelCurves                # > 30000 (stopped)
  Unwrap.CoarseOutputIsAreaAveragedNotAliased                                   # 33973
  Unwrap.FisheyeRigRoundTripRecoversTheLatLong                                  # > 80000 (stopped)
  Unwrap.RotatedLatLongCameraRoundTrip                                          # not reached (after the above)
  CloudsParity.FloatCpuVsVulkanPerPixelAndDoubleVsVulkanStatistics              # > 150000 (stopped)
  # cli_test through CTest at load average 16 (a bare `skycal --version` took ~2 s there,
  # so only the tests at 20 s or more, dozens of binary runs each, are moved):
  Cli.HelpListsEveryRegisteredOption                                            # 89019
  Cli.OptionSyntaxAndStrictness                                                 # 51576
  Cli.BadInputIsRefusedClearlyAndLeavesNothing                                  # 40789
  Cli.FitBadInputLeavesNothing                                                  # 38695
  Cli.FitWritesItsOutputsAndExportMakesGameTables                               # 20394
  SkySun.SyntheticCieSkiesRecoverTheSun                                         # 12100 (ctest -j2, load 10)
  RawCapture.FiveDngBracketsOfASkyThroughTheBinary                              # 8490 (ctest -j2, load ~12)
  RawCapture.BadBracketsAreRefusedByTheBinaryWithNothingWritten                 # 11000 (ctest -j2, load ~12)
  VulkanRenderers.DeviceTimeWithinWallTime                                      # 4171 (load 9)
  VulkanRenderers.StagedAndDirectAreBitIdentical                                # 6100 (load 9)
  VulkanRenderers.UnchangedContentIsNotUploadedAgain                            # 5762 (load 9)
  VulkanRenderers.ManyCloudRendersKeepMemoryFlat                                # 17373 (load 9; 1,000 renders since 2026-11-29)
  VulkanRenderers.ManyCloudRendersOnSampledImagesKeepMemoryFlat                 # 1,000 renders, as the one above
  VulkanRenderers.RenderersMadeAndDroppedReturnTheirMemory                      # 17347 (load 9)
)

# Measured fast (2026-11-28, load average 9, ms): ResponseRecovery.SharedShoulderCurveOneCurveForTheThreeChannels
# 1409, ResponseRecovery.BracketsThatCannotDetermineTheCurveSaySo 2340: labelled fast by the loop below.

# Not timed: sorted by what they do (see above).
set(SKYCAL_SLOW_TESTS_BY_CONTENT
  CloudStats.KnownShapesControlRecoversTheTruth
  CloudStats.UnknownShapesPointTowardTheTruth
  CloudStats.Regime2UnknownShapesRecoverTheAmbient
  CloudLighting.RecoversSeparableParametersNoiseless
  CloudLighting.RecoversSeparableParametersWithTwoPercentNoise
  CloudLightingDay.RecoversASmoothDayAndThePriorHelps
  CloudLightingCli.CloudyReferenceFitsAndExportsCloudKeyframes
  CloudLightingCli.ADayOfCloudyReferencesExportsOneKeyPerTimeOfDay
  FitRoundTrip.NoiselessRecoversImageAndHaziness
  FitRoundTrip.VulkanAndCpuBackendsReachTheSameFit
  FitRoundTrip.NoiseAndOutliersAreHandledByTheRobustLoss
  FitRoundTrip.DayStartSearchesGOnSixReferencesAndHoldsItOnTheRest
  FitRoundTrip.SyntheticDayRecoversTheObservedLut
  FitCeiling.OwnFamilyCeilingIsZero
  FitCeiling.CieGeneralSkiesAtTenThirtySixtyDegrees
  FitCeiling.OtherAtmospheresFromLowToHighSuns
  FitCeiling.CloudBlobsAndABuildingDoNotPull
  FitCeiling.RandomStartsReachTheCeiling
  RealSky.FitsSunrise
  RealSky.FitsSunset
  RealSky.BackendsAgreeOnTheUnmaskedSunrise
  ProbeFit.RecoversTheSunWithinOnePercent
  ProbeFit.DayWithCloudsOverTheSunDecidesVisibilityEveryFrame
  FitTerms.CeresPathThroughTermsGivesTheLutOfBefore
  FitTerms.OvercastHeldInFfxvIsoAndFittedInFfxv
  FitTerms.CoarseLevelsSavedIsEstimatedFromThisRunWhenThePolishRan
  CloudsCli.RenderWritesCompositeAndTransmittance
  Batch.LocalDayWarmStartsReduceAndResume
  Batch.KilledMidwayLosesNothingAndResumeCompletes
  RowMapping.AResampledFrameFitsAsTheOriginalDoes
  Flow.CloudsMovedByAKnownShiftAreRecovered
  FlowWind.CloudsMovedByTheWindAreRecoveredOnCloudPixels
  SkySegmentation.PrecisionAndRecallAgainstTheHandMasks
  SkyKind.EachBundledRealFrame
  Calibrate.TheSunWithItsDiscCoveredIsFoundFromTheSky
  Calibrate.AClearSkyThroughTheBinary
  Calibrate.APartlyCloudySkyGetsItsCloudsWhereThePhotoHasThem
  StarRemoval.RealNightSkyThroughTheBinary
  ColorChart.CastInARealSkyFrameIsRecoveredByDetection
  ColorChart.ChartVerbAndCaptureThroughTheBinary
  Capture.BracketsOfAFisheyeBecomeTheLatLong
)

set_tests_properties(${SKYCAL_SLOW_TESTS_MEASURED} ${SKYCAL_SLOW_TESTS_BY_CONTENT} PROPERTIES LABELS slow)

# Headless Chromium over the DevTools protocol (tests/report_browser_test.cc).
set_tests_properties(ReportBrowser.DayExportAndBenchRenderInChromium ReportBrowser.ControlPageFailsEveryCheck
                     PROPERTIES LABELS browser)

# Every other discovered test: fast.
set(_skycal_not_fast ${SKYCAL_SLOW_TESTS_MEASURED} ${SKYCAL_SLOW_TESTS_BY_CONTENT}
    ReportBrowser.DayExportAndBenchRenderInChromium ReportBrowser.ControlPageFailsEveryCheck)
file(GLOB _skycal_discovered "${SKYCAL_TESTS_BINARY_DIR}/*_tests.cmake")
foreach(_file IN LISTS _skycal_discovered)
  file(STRINGS "${_file}" _lines REGEX "^add_test\\(\\[=\\[")
  foreach(_line IN LISTS _lines)
    string(REGEX REPLACE "^add_test\\(\\[=\\[([^]]+)\\]=\\].*" "\\1" _name "${_line}")
    list(FIND _skycal_not_fast "${_name}" _index)
    if(_index EQUAL -1)
      set_tests_properties("${_name}" PROPERTIES LABELS fast)
    endif()
  endforeach()
endforeach()
