# The project's sources each fuzz target compiles again with clang (tests/fuzz/CMakeLists.txt),
# relative to services/: PBNBV_FUZZED_<target>. The top-level CMakeLists.txt reads this file
# whether or not the tests are built and keeps these files out of their libraries' unity builds:
# a fuzz target links the library too, and a unity object pulled in for another symbol would
# define theirs a second time; and turning the tests on must not regroup (and rebuild) a library.
set(PBNBV_FUZZ_TARGETS fuzz_messages fuzz_mesh_file fuzz_cloud_file fuzz_config fuzz_rig_file fuzz_scan_folder)
set(PBNBV_FUZZED_fuzz_messages bus/message_guard.cpp bus/depth_codec.cpp)
set(PBNBV_FUZZED_fuzz_mesh_file core/io/mesh_file.cpp core/io/file_checks.cpp)
set(PBNBV_FUZZED_fuzz_cloud_file core/io/cloud_file.cpp core/io/pcd_file.cpp core/io/file_checks.cpp)
set(PBNBV_FUZZED_fuzz_config cli/options.cpp launcher/command_line.cpp)
set(PBNBV_FUZZED_fuzz_rig_file core/rig/rig_model.cpp core/rig/mujoco_model.cpp core/rig/kinematics.cpp)
set(PBNBV_FUZZED_fuzz_scan_folder launcher/scan_processes.cpp core/scan/scan_settings.cpp core/scan/scan_record.cpp
    core/scan/scan_sequencer.cpp)
