#!/usr/bin/env bash
# The dependency direction between layers, beyond what the include directories already enforce
# at compile time (see pbnbv_library in CMakeLists.txt): only the rig library and the twin see
# MuJoCo, only the report library draws with OpenCV, only the surface library meshes with PCL's
# surface module, and the processes that need neither do not load them (ldd: the coordinator,
# which writes scan.json and nothing else, loads none of MuJoCo, PCL and OpenCV); no program loads
# OpenCV's imgcodecs (about 130 libraries at every start: PNG and JPEG are libpng's and libjpeg's,
# core/io/image_codec); scan.json is parsed in one place; no core file is over 800 lines.
set -uo pipefail
src=${PBNBV_SOURCE_DIR:?}
bin=${PBNBV_BIN_DIR:?}
fail=0

# verdict <hits> <what failed> <what holds>: FAIL with the hits (one per line) or ok.
verdict() {
  if [ -n "$1" ]; then
    echo "FAIL: $2:"; echo "$1" | sed 's/^/  /'
    fail=1
  else
    echo "ok: $3"
  fi
}

# Library and service sources (not tests, not benchmarks) that include a header they must not.
check_includes() {  # <pattern> <what> <allowed path regex>
  local hits
  hits=$(cd "$src" && grep -rlE "#include <$1" services twin --include=*.cpp --include=*.hpp |
         grep -vE '/(test|bench)/' | grep -vE "$3" || true)
  verdict "$hits" "$2 is included outside its layer by" "$2 only in $3"
}
check_includes 'mujoco/' "MuJoCo" '^(services/core/rig/|twin/)'
check_includes 'opencv2/' "OpenCV" '^services/report/'
check_includes '(png|jpeglib)\.h' "libpng and libjpeg" '^services/core/io/image_codec\.cpp'
check_includes 'pcl/surface/' "PCL's surface module (marching-cubes tables, Poisson)" '^services/core/surface/'

# The scan's layer names a rig kind but uses none of the rig's model or kinematics (those are for
# the motion and camera sequencing, core/acquisition): pbnbv_scan does not link pbnbv_rig.
verdict "$(cd "$src" && grep -rln '#include "core/rig/' services/core/scan || true)" \
        "core/scan includes the rig's model (core/rig/), which it does not link:" "core/scan does not include core/rig"
verdict "$(grep -E 'target_link_libraries\(pbnbv_scan .*pbnbv_(rig|acquisition)' "$src/services/core/scan/CMakeLists.txt" || true)" \
        "pbnbv_scan links the rig:" "pbnbv_scan does not link pbnbv_rig"

# scan.json is parsed by core/scan alone (scan_file.cpp: read_scan_json, which checks its format);
# every other source reads it into its types (scan_record.hpp: read_scan_record), never by key.
verdict "$(cd "$src" && grep -rnE 'read_json\([^;]*(scan\.json|scan_json|scan_path|replay_of)' services twin \
             --include=*.cpp --include=*.hpp | grep -vE '/(test|bench)/' | grep -v '^services/core/scan/scan_file.cpp:' || true)" \
        "scan.json read outside core/scan/scan_file.cpp (use read_scan_json)" "scan.json read by core/scan/scan_file.cpp only"
verdict "$(cd "$src" && grep -rn 'read_scan_json(' services twin --include=*.cpp --include=*.hpp | grep -vE '/(test|bench)/' |
             grep -vE '^services/core/scan/(scan_file|scan_record|scan_record_read)\.(cpp|hpp):' || true)" \
        "scan.json read by key outside core/scan's record (use read_scan_record)" \
        "scan.json read into its types (read_scan_record) outside core/scan"

# No library file of core/ over 800 lines: a file that long holds several things.
verdict "$(cd "$src" && find services/core -name '*.cpp' -o -name '*.hpp' | grep -vE '/(test|bench)/' | xargs wc -l |
             awk '$2 != "total" && $1 > 800 {print $2 ": " $1 " lines"}')" \
        "core files over 800 lines" "no core file over 800 lines"

# Processes that must not load a library.
check_ldd() {  # <binary> <library pattern>...
  local b=$1; shift
  [ -x "$bin/$b" ] || { echo "FAIL: $bin/$b is missing"; fail=1; return; }
  for lib in "$@"; do
    verdict "$(ldd "$bin/$b" | grep "$lib" || true)" "$b loads $lib" "$b does not load $lib"
  done
}
check_ldd pbnbv-ellipsoids libmujoco libopencv libpcl
check_ldd pbnbv-mapping libmujoco libopencv libpcl
check_ldd pbnbv-registration libmujoco
# The coordinator owns scan.json only: it decodes no frame, meshes nothing, loads no rig model.
check_ldd pbnbv-coordinator libmujoco libpcl libopencv
# PNG and JPEG through libpng and libjpeg: no program starts with OpenCV's codecs (GDAL, Poppler, ...).
for b in pbnbv pbnbv-twin pbnbv-motion pbnbv-camera pbnbv-registration pbnbv-scorer pbnbv-view pbnbv-replay-rig; do
  check_ldd "$b" libopencv_imgcodecs libgdal
done
exit $fail
