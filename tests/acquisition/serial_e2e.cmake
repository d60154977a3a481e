# Included by ctest after gtest's discovered tests: the end-to-end tests run alone (RUN_SERIAL).
set_tests_properties(EndToEnd.ThirtySecondsAt1kHzNoneLost EndToEnd.InjectedFaultsAreReportedAndRecoveredFrom
                     EndToEnd.FaultSwitchesAreReportedWithinThreePeriods PROPERTIES RUN_SERIAL TRUE)
