# Read by ctest after faults_test's discovered tests (TEST_INCLUDE_FILES, tests/CMakeLists.txt).
# The packet-loss case runs alone: it asserts that a scan at 1 % loss takes at most twice the wall
# time of a clean one, and another test's load beside one of the two scans would skew that ratio.
# Its cost is the lowest: ctest starts a RUN_SERIAL test only when nothing else is running, so it
# waits for the end of the run either way.
set_tests_properties(Faults.PacketLossOfOneAndFivePercentCostsNoViewAndNoCoverage PROPERTIES RUN_SERIAL TRUE COST 0)
