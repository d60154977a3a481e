#!/bin/bash
# The installed package, used as another project would (docs/install.md):
#  1. cmake --install into a prefix inside the build tree, and what must be there;
#  2./3. a CMake project with find_package(hil) built against it, run, its numbers checked;
#  4. a program built with `pkg-config --cflags --libs hil`, run;
#  5. the installed `hil` run from elsewhere: its data dir lookup ($HIL_DATA_DIR, then the prefix
#     beside the binary, also once the tree is moved) and `hil validate` on the installed examples;
#  6. the installed Python module imported by Debian's python3 from the prefix alone;
#  7. `--strip` (no debug sections left in the command, the module or the archives) and the
#     `runtime` component alone (no libraries or headers), with the sizes docs/install.md quotes.
# Environment (from tests/install/CMakeLists.txt): BUILD WORK HERE CMAKE GENERATOR CXX VERSION
# BINDIR LIBDIR INCLUDEDIR DATADIR DOCDIR PYTHONDIR (empty when the module is not built).
set -euo pipefail

fail() { echo "FAIL: $*" >&2; exit 1; }
# has NAME TEXT PATTERN: TEXT matches the extended regex PATTERN.
has() { grep -qE -- "$3" <<<"$2" || fail "$1: expected /$3/ in:"$'\n'"$2"; }
# near NAME GOT WANT TOL
near() { awk -v g="$2" -v w="$3" -v t="$4" 'BEGIN { d = g - w; exit !(d <= t && -d <= t) }' ||
  fail "$1: got $2, expected $3 +- $4"; }
# field LINE KEY N: the N-th word after the word KEY.
field() { awk -v key="$2" -v n="$3" '{ for (i = 1; i < NF; ++i) if ($i == key) { print $(i + n); exit } }' <<<"$1"; }

rm -rf "$WORK"
mkdir -p "$WORK"
WORK=$(realpath "$WORK")  # the binary sees its real path
prefix=$WORK/prefix
export HIL_DDS_DOMAIN=$((200 + $$ % 30))

echo "== 1. cmake --install $BUILD --prefix $prefix"
"$CMAKE" --install "$BUILD" --prefix "$prefix" >"$WORK/install.log" || { cat "$WORK/install.log"; fail "cmake --install"; }
for f in "$BINDIR/hil" "$LIBDIR/cmake/hil/hilConfig.cmake" "$LIBDIR/cmake/hil/hilConfigVersion.cmake" \
  "$LIBDIR/cmake/hil/hilTargets.cmake" "$LIBDIR/pkgconfig/hil.pc" "$LIBDIR/libhil_contact_id.a" \
  "$LIBDIR/libhil_idl_types.a" "$INCLUDEDIR/hil/format/rig.hpp" "$INCLUDEDIR/hil/dds/types.hpp" \
  "$INCLUDEDIR/hil/calibration/vjm.hpp" "$INCLUDEDIR/hil/messages/sample_msg.hpp" "$INCLUDEDIR/hil/error/error.hpp" \
  "$INCLUDEDIR/hil/drivers/force_plate.hpp" "$INCLUDEDIR/hil/idl/hil_msgsPubSubTypes.h" \
  "$INCLUDEDIR/hil/idl/std_msgs.h" "$DATADIR/hil/dds_localhost.xml" "$DATADIR/hil/examples/acu/acu.yaml" \
  "$DATADIR/hil/examples/rigs/press_bench.yaml" "$DOCDIR/LICENSE"; do
  [[ -f $prefix/$f ]] || fail "not installed: $prefix/$f"
done
# Nothing of the build or source tree leaks into the exported targets.
targets=$(cat "$prefix/$LIBDIR"/cmake/hil/hilTargets*.cmake)
for tree in "$BUILD" "$(cd "$HERE/../.." && pwd)"; do
  ! grep -qF "$tree" <<<"$targets" || fail "hilTargets*.cmake names $tree"
done

echo "== 2. find_package(hil 0.1) in a consumer project"
"$CMAKE" -S "$HERE/consumer" -B "$WORK/consumer" -G "$GENERATOR" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_COMPILER="$CXX" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
  >"$WORK/consumer-configure.log" || { cat "$WORK/consumer-configure.log"; fail "configuring the consumer"; }
has "consumer configure" "$(cat "$WORK/consumer-configure.log")" "hil $VERSION from $prefix/$LIBDIR/cmake/hil, data in $prefix/$DATADIR/hil"
"$CMAKE" --build "$WORK/consumer" -j 2 >"$WORK/consumer-build.log" || { cat "$WORK/consumer-build.log"; fail "building the consumer"; }
# A version the package does not promise is refused.
if "$CMAKE" -S "$HERE/consumer" -B "$WORK/consumer-v9" -G "$GENERATOR" -DCMAKE_PREFIX_PATH="$prefix" \
  -DHIL_WANT=9 -DCMAKE_CXX_COMPILER="$CXX" >"$WORK/consumer-v9.log" 2>&1; then
  fail "find_package(hil 9) succeeded"
fi
has "find_package(hil 9)" "$(cat "$WORK/consumer-v9.log")" "hilConfig.cmake, version: $VERSION"

echo "== 3. the consumer's numbers"
out=$(cd "$WORK" && "$WORK/consumer/consumer" "$WORK")
echo "$out"
has consumer "$out" "^rig acu_bench objects 2 features 8 polyhedra 15$"
# The ACU body (0.3 m square, bottom at the ee) 0.5 mm into the base (top at z = -0.012) over the
# corner [0.18, 0.2]^2: one contact, depth 0.5 mm, pushing the ACU up, at the overlap's centroid.
has consumer "$out" "^contacts 1$"
line=$(grep '^contact delta' <<<"$out")
near delta "$(field "$line" delta 1)" 0.0005 1e-9
near "point x" "$(field "$line" point 1)" 0.19 1e-9
near "point y" "$(field "$line" point 2)" 0.19 1e-9
near "point z" "$(field "$line" point 3)" -0.01225 1e-9
near "normal z" "$(field "$line" normal 3)" 1 1e-12
# The plate (origin at z = -0.06) carries K delta = 1.8e5 * 5e-4 = 90 N downward at the point:
# moments r x F about its origin with r = (0.19, 0.19, 0.04775).
line=$(grep '^plate wrench' <<<"$out")
for i in 1 2 3 4 5 6; do
  want=(0 0 0 -90 -17.1 17.1 0); near "wrench $i" "$(field "$line" wrench "$i")" "${want[$i]}" 1e-6
done
line=$(grep '^cdr type' <<<"$out")
has "cdr" "$line" "^cdr type hil_msgs::msg::dds_::PoseWrenchSample_ bytes [1-9][0-9]* index 7 t 1.25 z -0.0125 fz -90 my 17.1 joints 0.5 -0.25$"

# The installed example run through MCAP files (hil::mcap with zstd and lz4) and back.
for c in zstd lz4; do
  line=$(grep "^mcap $c " <<<"$out") || fail "consumer: no MCAP line for $c"
  [[ $(field "$line" samples 1) == 325 && $(field "$line" of 1) == 325 ]] || fail "consumer MCAP $c: $line (325 samples)"
  fz=$(field "$line" fz 1)
  [[ $fz == $(field "$line" fz 3) ]] || fail "consumer MCAP $c: the peak fz changed: $line"
  awk -v f="$fz" 'BEGIN { exit !(f > 1 || f < -1) }' || fail "consumer MCAP $c: no loaded sample: $line"
done

echo "== 4. pkg-config"
export PKG_CONFIG_PATH="$prefix/$LIBDIR/pkgconfig"
[[ $(pkg-config --modversion hil) == "$VERSION" ]] || fail "pkg-config --modversion hil: $(pkg-config --modversion hil)"
[[ $(realpath "$(pkg-config --variable=includedir hil)") == "$prefix/$INCLUDEDIR" ]] || fail "pkg-config includedir"
[[ $(realpath "$(pkg-config --variable=libdir hil)") == "$prefix/$LIBDIR" ]] || fail "pkg-config libdir"
datadir=$(realpath "$(pkg-config --variable=datadir hil)")
[[ $datadir == "$prefix/$DATADIR/hil" ]] || fail "pkg-config datadir: $datadir"
# shellcheck disable=SC2046  # the flags are words
"$CXX" -O1 -o "$WORK/pkgconfig_consumer" "$HERE/pkgconfig_consumer.cpp" $(pkg-config --cflags --libs hil) ||
  fail "building with pkg-config --cflags --libs hil: $(pkg-config --cflags --libs hil)"
out=$("$WORK/pkgconfig_consumer" "$datadir/examples/acu/acu.yaml")
echo "$out"
# The ACU body: 0.3 x 0.3 x 0.15 m, a box (6 faces).
has pkgconfig_consumer "$out" "^rig acu_bench polyhedra 15 first volume 0.0135 faces 6$"

echo "== 5. the installed hil, run from $WORK"
cd "$WORK"
hil=$prefix/$BINDIR/hil
out=$(env -u HIL_DATA_DIR "$hil" validate "$prefix/$DATADIR/hil/examples/rigs/press_bench.yaml")
has "hil validate press_bench.yaml" "$out" "OK"
has "hil validate press_bench.yaml" "$out" "features: 2"
out=$(env -u HIL_DATA_DIR "$hil" validate "$prefix/$DATADIR/hil/examples/acu/acu.yaml")
has "hil validate acu.yaml (the consumer's count)" "$out" "polyhedra: 15"
out=$(env -u HIL_DATA_DIR "$hil" validate "$prefix/$DATADIR/hil/examples/runs/press_slide")
has "hil validate press_slide (the consumer's MCAP count)" "$out" "samples: 325,"
# With $HIL_DATA_DIR unset the demo's defaults come from <prefix>/share/hil (before the source tree).
out=$(env -u HIL_DATA_DIR "$hil" demo --help)
has "hil demo --help" "$out" "$prefix/$DATADIR/hil/examples/acu/acu.yaml"
has "hil demo --help" "$out" "$prefix/$DATADIR/hil/examples/acu/traj_2a.csv"
# $HIL_DATA_DIR comes first...
mkdir -p "$WORK/data"
cp -r "$prefix/$DATADIR/hil/examples" "$WORK/data/"
out=$(HIL_DATA_DIR="$WORK/data" "$hil" demo --help)
has "HIL_DATA_DIR=$WORK/data hil demo --help" "$out" "$WORK/data/examples/acu/acu.yaml"
# ...and a wrong one is refused by name, not passed over.
set +e
err=$(HIL_DATA_DIR="$WORK/nowhere" "$hil" demo --out "$WORK/never" 2>&1 >/dev/null)
status=$?
set -e
((status != 0)) || fail "hil demo with HIL_DATA_DIR=$WORK/nowhere succeeded"
has "hil demo with a bad HIL_DATA_DIR" "$err" "HIL_DATA_DIR=$WORK/nowhere \\(no examples/ folder there\\)"
[[ ! -e $WORK/never ]] || fail "hil demo with a bad HIL_DATA_DIR recorded anyway"
# A moved tree finds its own data: the lookup is relative to the binary, not the configured prefix.
mkdir -p "$WORK/moved/$BINDIR" "$WORK/moved/$DATADIR"
ln "$hil" "$WORK/moved/$BINDIR/hil"
cp -r "$prefix/$DATADIR/hil" "$WORK/moved/$DATADIR/"
# ...and its own host-only DDS profile, not the configured prefix's nor the source tree's.
out=$(env -u HIL_DDS_PROFILE HIL_DDS_DOMAIN=229 "$WORK/moved/$BINDIR/hil" --log-level debug echo pose_wrench --timeout 0.2 2>&1 || true)
has "moved hil's DDS profile" "$out" "from $WORK/moved/$DATADIR/hil/dds_localhost.xml"
out=$(env -u HIL_DATA_DIR "$WORK/moved/$BINDIR/hil" demo --help)
has "moved hil demo --help" "$out" "$WORK/moved/$DATADIR/hil/examples/acu/acu.yaml"

echo "== 6. import hil from $prefix/$PYTHONDIR"
if [[ -z $PYTHONDIR ]]; then
  echo "(the Python module is not built: pybind11-dev or python3-dev missing)"
else
  # Away from the build tree, so only the installed extension can be found. In a sanitizer build
  # the interpreter is not instrumented: it preloads the runtime for the module (as tests/python).
  san_env=()
  [[ -z ${PYTHON_PRELOAD:-} ]] || san_env=(LD_PRELOAD="$PYTHON_PRELOAD" ASAN_OPTIONS=detect_leaks=0:halt_on_error=1:new_delete_type_mismatch=0)
  out=$(cd "$WORK" && env -i PATH=/usr/bin:/bin "${san_env[@]}" PYTHONPATH="$prefix/$PYTHONDIR" /usr/bin/python3 -c '
import hil, sys
print("file", hil.__file__)
print("version", hil.__version__)
rig = hil.read_rig(sys.argv[1])
print("rig", rig["name"], "frames", len(rig["frames"]), "robot", rig["robot"]["name"])
' "$prefix/$DATADIR/hil/examples/rigs/press_bench.yaml") || fail "import hil from $prefix/$PYTHONDIR"
  echo "$out"
  has "import hil" "$out" "^file $prefix/$PYTHONDIR/hil\\.cpython-[0-9]+-.*\\.so$"
  has "import hil" "$out" "^version $VERSION$"
  has "import hil" "$out" "^rig press_bench frames 3 robot ur5e$"
fi

echo "== 7. --strip, and --component runtime"
# debug_sections FILE: the names of FILE's .debug_* sections (an archive's members together).
debug_sections() { readelf -S -W "$1" 2>/dev/null | grep -oE '\.debug_[a-z_]+' | sort -u | tr '\n' ' '; }
[[ -n $(debug_sections "$prefix/$BINDIR/hil") ]] || fail "the default install's hil has no debug info: the check below proves nothing"
stripped=$WORK/stripped
"$CMAKE" --install "$BUILD" --prefix "$stripped" --strip >"$WORK/install-strip.log" || { cat "$WORK/install-strip.log"; fail "cmake --install --strip"; }
for f in "$stripped/$BINDIR/hil" "$stripped/$LIBDIR"/libhil_*.a ${PYTHONDIR:+"$stripped/$PYTHONDIR"/hil.*.so}; do
  [[ -z $(debug_sections "$f") ]] || fail "--strip left debug sections in $f: $(debug_sections "$f")"
done
"$stripped/$BINDIR/hil" validate "$stripped/$DATADIR/hil/examples/rigs/press_bench.yaml" >/dev/null || fail "the stripped hil does not run"
runtime=$WORK/runtime
"$CMAKE" --install "$BUILD" --prefix "$runtime" --component runtime --strip >"$WORK/install-runtime.log" ||
  { cat "$WORK/install-runtime.log"; fail "cmake --install --component runtime"; }
for f in "$BINDIR/hil" "$DATADIR/hil/dds_localhost.xml" "$DATADIR/hil/examples/acu/acu.yaml" "$DOCDIR/LICENSE"; do
  [[ -f $runtime/$f ]] || fail "runtime component: not installed: $f"
done
[[ -z $PYTHONDIR ]] || compgen -G "$runtime/$PYTHONDIR/hil.*.so" >/dev/null || fail "runtime component: no Python module"
[[ ! -e $runtime/$INCLUDEDIR && ! -e $runtime/$LIBDIR/cmake ]] || fail "runtime component: headers or CMake files installed"
! compgen -G "$runtime/$LIBDIR/*.a" >/dev/null || fail "runtime component: libraries installed"
echo "sizes (KiB): default $(du -sk "$prefix" | cut -f1), --strip $(du -sk "$stripped" | cut -f1)," \
  "runtime --strip $(du -sk "$runtime" | cut -f1), stripped hil $(($(stat -c %s "$stripped/$BINDIR/hil") / 1024))"
echo "install: all checks passed"
rm -rf "$WORK"  # ~2 GB (static libraries, the binary and the module with debug info); kept when a check fails
