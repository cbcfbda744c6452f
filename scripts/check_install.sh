#!/usr/bin/env bash
# Check that hssbem works as an installed library.
#
#   scripts/check_install.sh BUILD_DIR
#
# Installs BUILD_DIR (a configured and built hssbem tree) into a temporary prefix, builds a copy of
# examples/ against it with find_package(hssbem) (CMAKE_PREFIX_PATH = the prefix), and runs the
# example on 1 and 2 MPI ranks on a small shipped mesh. Fails (non-zero) when a step fails, when
# the example does not print its summary line or does not converge, when the build of the example
# refers to the source tree, or when the two runs disagree or leave the physical range.
# Environment: MPIEXEC (default mpirun), KEEP=1 keeps the temporary directory.
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
mesh="$repo/meshes/cube_l0.msh" # unit cube, 98 vertices: a few seconds per run
E=3000 nu=0.45 pressure=100    # the example's defaults, spelled out for the range check below

step() { printf '\n==> check_install: %s\n' "$*"; }
fail() {
  printf 'check_install: FAILED: %s\n' "$*" >&2
  exit 1
}

[ $# -eq 1 ] || fail "usage: scripts/check_install.sh BUILD_DIR"
build=$(cd "$1" && pwd) || fail "no build directory '$1'"
[ -f "$build/cmake_install.cmake" ] || fail "'$build' is not a configured hssbem build (no cmake_install.cmake)"

work=$(mktemp -d "${TMPDIR:-/tmp}/hssbem-check-install.XXXXXX")
prefix="$work/prefix"
cleanup() {
  if [ "${KEEP:-0}" = 1 ] || [ "${ok:-0}" != 1 ]; then
    echo "check_install: kept $work"
  else
    rm -rf "$work"
  fi
}
trap cleanup EXIT

step "installing $build into $prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log" || {
  cat "$work/install.log"
  fail "cmake --install"
}
for f in lib/libhssbem.a bin/hssbem include/hssbem/petsc/system.h lib/cmake/hssbem/hssbemConfig.cmake \
  lib/cmake/hssbem/hssbemConfigVersion.cmake lib/cmake/hssbem/hssbemTargets.cmake; do
  [ -e "$prefix/$f" ] || fail "missing from the prefix: $f"
done
if grep -rl "$repo" "$prefix/lib/cmake/hssbem"; then fail "the installed package files refer to the source tree $repo"; fi
echo "installed: $(find "$prefix" -type f | wc -l) files (library, app, headers, package files)"

# A copy of examples/, so nothing but the prefix can supply headers or libraries.
step "configuring a copy of examples/ with -DCMAKE_PREFIX_PATH=$prefix"
cp -r "$repo/examples" "$work/examples"
cmake -S "$work/examples" -B "$work/build" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >"$work/configure.log" 2>&1 || {
  cat "$work/configure.log"
  fail "configuring examples/ against the installed hssbem"
}
grep -h "hssbem_DIR:PATH=" "$work/build/CMakeCache.txt"

step "building the example"
cmake --build "$work/build" -j2 >"$work/build.log" 2>&1 || {
  cat "$work/build.log"
  fail "building examples/"
}
if grep -q "$repo" "$work/build/compile_commands.json"; then fail "the example's compile commands refer to the source tree $repo"; fi
exe="$work/build/clamped_block"
[ -x "$exe" ] || fail "no executable $exe"
echo "built $exe"

# One thread per rank, as the MPI tests do: CI machines have 2 cores.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
mpiexec=${MPIEXEC:-mpirun}
mpiflags=(--oversubscribe)
if [ "$(id -u)" -eq 0 ]; then mpiflags+=(--allow-run-as-root); fi
summary_re='^example: [0-9]+ unknowns, [a-z]+/[a-z]+: [0-9]+ iterations \(CONVERGED_[A-Z_]+\), max \|u_z\| = [0-9.e+-]+$'

# run NP: run the example on NP ranks, check its exit code and summary line, print the line and
# set $uz to its max |u_z|.
run() {
  local np=$1 out="$work/run-np$1.log" line rc=0
  local cmd=("$mpiexec" -n "$np" "${mpiflags[@]}" "$exe" -mesh "$mesh" -E "$E" -nu "$nu" -pressure "$pressure" -options_left)
  echo "${cmd[*]}"
  "${cmd[@]}" >"$out" 2>&1 || rc=$?
  if [ "$rc" -ne 0 ]; then
    cat "$out"
    fail "the example exited with status $rc on $np rank(s)"
  fi
  line=$(grep -E "$summary_re" "$out") || {
    cat "$out"
    fail "no summary line 'example: N unknowns, ksp/pc: K iterations (CONVERGED_...), max |u_z| = X' on $np rank(s)"
  }
  if grep -q "Option left:" "$out"; then
    cat "$out"
    fail "unused options on $np rank(s)"
  fi
  echo "$line"
  uz=${line##*= }
}

step "running the example on 1 rank ($mesh)"
run 1
uz1=$uz
step "running the example on 2 ranks"
run 2
uz2=$uz

# The operator and its compression are the same on any number of ranks, so the runs agree to
# about the KSP tolerance (1e-8); 1e-6 leaves room for the order of parallel sums. The top of a
# block clamped at its base and free at its sides settles between the confined (oedometric,
# modulus M) and the unconfined (uniaxial, modulus E) compression: p h / M < max |u_z| < p h / E.
step "checking the results (1 vs 2 ranks, physical range)"
awk -v a="$uz1" -v b="$uz2" -v E="$E" -v nu="$nu" -v p="$pressure" 'BEGIN {
  h = 1.0 # cube_l0 spans z in [0, 1]
  M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
  lo = p * h / M; hi = p * h / E
  d = a - b; if (d < 0) d = -d
  printf "max |u_z|: %.6e (1 rank), %.6e (2 ranks), relative difference %.1e; expected in [%.4e, %.4e]\n", a, b, d / a, lo, hi
  if (!(a > lo && a < hi)) { print "check_install: max |u_z| out of range" > "/dev/stderr"; exit 1 }
  if (!(d <= 1e-6 * a)) { print "check_install: 1 and 2 ranks disagree" > "/dev/stderr"; exit 1 }
}' || fail "results"

# The scene API: a contact sliding around the cardioid, re-solved every frame (examples/moving_contact).
step "running examples/moving_contact (the scene API) on the cardioid"
scene_exe="$work/build/moving_contact"
[ -x "$scene_exe" ] || fail "no executable $scene_exe"
scene_out="$work/moving_contact.log"
"$scene_exe" -mesh "$repo/meshes/cardioid_832.msh" -frames 20 >"$scene_out" 2>&1 || { cat "$scene_out"; fail "moving_contact exited with an error"; }
scene_re='^moving_contact: [0-9]+ unknowns, set-up [0-9.]+ s; moving contact [0-9]+ Hz, values only [0-9]+ Hz, contact forces [0-9]+ Hz; max \|u\| = [0-9.]+e[-+][0-9]+, max \|F\| = [0-9.]+e[-+][0-9]+$'
grep -E "$scene_re" "$scene_out" || { cat "$scene_out"; fail "no summary line from moving_contact"; }
# the indentation (0.03 of the size 1.3, deepened 4 x 10 % per frame) must show: max |u| in (0.01, 0.2)
awk '/^moving_contact:/ { split($0, a, "max \\|u\\| = "); split(a[2], b, ","); u = b[1] + 0; if (!(u > 0.01 && u < 0.2)) { print "check_install: max |u| " u " out of range" > "/dev/stderr"; exit 1 } }' "$scene_out" || fail "moving_contact results"

# The Python module, when the build has it: imported from the prefix alone (not the build tree),
# examples/python/solve.py on 1 and 2 ranks against its closed form.
module=$(find "$prefix" -name '_hssbem*.so' | head -n 1)
if [ -n "$module" ]; then
  site=$(dirname "$(dirname "$module")")
  python=$(grep -h "^Python3_EXECUTABLE:" "$build/CMakeCache.txt" | cut -d= -f2)
  for np in 1 2; do
    step "running examples/python/solve.py from $site on $np rank(s)"
    py_out="$work/solve-py-np$np.log"
    (cd "$work" && PYTHONPATH="$site" "$mpiexec" -n "$np" "${mpiflags[@]}" "$python" "$repo/examples/python/solve.py") >"$py_out" 2>&1 || {
      cat "$py_out"
      fail "examples/python/solve.py on $np rank(s)"
    }
    cat "$py_out"
    grep -q "^hssbem imported from $site" "$py_out" || fail "examples/python/solve.py did not import hssbem from the prefix"
    # sphere_l1 under pressure: the P1 discretisation's error is about 1 % of the displacement
    awk '/largest error against the closed form/ { e = $(NF-2) + 0; if (!(e < 2e-3)) { print "check_install: error " e " too large" > "/dev/stderr"; exit 1 }; found = 1 } END { exit !found }' "$py_out" ||
      fail "examples/python/solve.py results"
  done
fi

ok=1
step "passed: installed hssbem builds and runs examples/clamped_block on 1 and 2 ranks and examples/moving_contact${module:+, and examples/python/solve.py on 1 and 2 ranks}"
