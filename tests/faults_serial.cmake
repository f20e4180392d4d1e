# Read by ctest after faults_test's discovered tests (TEST_INCLUDE_FILES, tests/CMakeLists.txt).
# Two cases run alone (the packet-loss case, which compares a lossy scan's wall time with a clean
# one's, runs both at once instead, so that any load beside them is shared):
# - the killed-logger case kills lcm-logger at view 3 and asserts that the two log files still
#   hold every message of the scan: beside another test (CI, 2026-12-04, -j2) the killed logger had
#   not yet written view 3's REGISTERED_CLOUD and VOXEL_MAP, and the case failed;
# - the main job's log case asserts that lcm-logger on the default bus kept every message: beside
#   the hostile-traffic case (2026-12-04, -j2) the logger lost one CLOUD (9 of 10) under the load.
# Their cost is the lowest: ctest starts a RUN_SERIAL test only when nothing else is running, so
# they wait for the end of the run either way.
set_tests_properties(Faults.AKilledLoggerGoesOnInASecondFileAndTheAuditSaysWhatItLacks
                     Faults.TheMainJobsLogHoldsEveryMessageOfItsScan
                     PROPERTIES RUN_SERIAL TRUE COST 0)
# The longest case that shares the machine (about 1.5 minutes: four 10-view scans) starts first.
set_tests_properties(Faults.EachKilledServiceIsRestartedAndTheScanCompletes PROPERTIES COST 90)
# The packet-loss case (three 10-view scans at once, about 40 s) next to it.
set_tests_properties(Faults.PacketLossOfOneAndFivePercentCostsNoViewAndNoCoverage PROPERTIES COST 60)
