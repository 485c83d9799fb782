#!/usr/bin/env bash
# tools/check_arm64.sh: the CPU kernels and their tests cross-built for aarch64 (Debian 12's
# g++-aarch64-linux-gnu against arm64 multiarch libraries) and run under qemu-user, so the neon and scalar
# code of every Highway kernel is compiled and tested from an x86-64 machine. tools/ARM64.md says what it
# covers, what it costs and where it runs.
#   1. installs what is missing (dpkg -s first; the arm64 architecture, then apt-get as root or through
#      sudo, like tools/bootstrap.sh); exits 77 (skipped) when it cannot: no dpkg, no root and no sudo, or
#      apt-get fails. With SFFD_REQUIRE_ARM64=1 that is a failure (exit 1) instead;
#   2. configures build/arm64 with cmake/aarch64-linux-gnu.cmake and SFFD_CPU_KERNELS_ONLY=ON: the kernels'
#      libraries and tests only (no GL, EGL, GLFW, Embree, OpenEXR, ImGui);
#   3. builds what builds (a test program that does not build is one failed test, ctest's *_NOT_BUILT),
#      and runs every test there through ctest, qemu-aarch64 being the cross-compiling emulator.
# Ends with one line "check_arm64: N passed, N failed"; exits non-zero if anything failed.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build=build/arm64

# Host tools, arm64 libraries (multiarch, beside the amd64 ones: apt keeps both at one version, and may
# upgrade an installed amd64 package to match), and the header-only libraries (Architecture: all).
HOST_PACKAGES=(g++-aarch64-linux-gnu qemu-user cmake make)
ARM64_PACKAGES=(libhwy-dev:arm64 libtbb-dev:arm64 libgtest-dev:arm64)
ALL_PACKAGES=(libglm-dev nlohmann-json3-dev)

finish() {  # finish PASSED FAILED
  echo "check_arm64: $1 passed, $2 failed"
  ((${2} == 0)) || exit 1
  exit 0
}
skip() {
  echo "check_arm64: $1" >&2
  [[ ${SFFD_REQUIRE_ARM64:-0} == 1 ]] && finish 0 1
  echo "check_arm64: skipped"
  exit 77
}
now() { date +%s; }
t0=$(now)

command -v dpkg >/dev/null 2>&1 ||
  skip "dpkg not found: this check installs Debian 12 packages (${HOST_PACKAGES[*]} ${ARM64_PACKAGES[*]})"
missing=()
for p in "${HOST_PACKAGES[@]}" "${ARM64_PACKAGES[@]}" "${ALL_PACKAGES[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
has_arm64=0
dpkg --print-foreign-architectures | grep -qx arm64 && has_arm64=1
if ((${#missing[@]} > 0 || has_arm64 == 0)); then
  if [[ $(id -u) == 0 ]]; then
    sudo=()
  elif command -v sudo >/dev/null 2>&1 && { sudo -n true 2>/dev/null || [[ -t 0 ]]; }; then
    sudo=(sudo)
  else
    skip "need root to install ${missing[*]}; as root: dpkg --add-architecture arm64 && apt-get update && apt-get install -y ${missing[*]}"
  fi
  export DEBIAN_FRONTEND=noninteractive
  echo "check_arm64: installing ${missing[*]:-the arm64 architecture}"
  if ((has_arm64 == 0)); then
    "${sudo[@]}" dpkg --add-architecture arm64 || skip "dpkg --add-architecture arm64 failed"
  fi
  "${sudo[@]}" apt-get update -qq || skip "apt-get update failed"
  if ((${#missing[@]} > 0)); then
    "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null ||
      skip "apt-get install ${missing[*]} failed"
  fi
fi
t_install=$(now)

jobs=$(nproc 2>/dev/null || echo 2)
launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
mkdir -p "$build"
if ! cmake -S . -B "$build" -G "Unix Makefiles" --toolchain "$PWD/cmake/aarch64-linux-gnu.cmake" \
  -DCMAKE_BUILD_TYPE=Release -DSFFD_CPU_KERNELS_ONLY=ON -DSFFD_NATIVE=OFF "${launcher[@]}" \
  >"$build/configure.log" 2>&1; then
  cat "$build/configure.log" >&2
  echo "check_arm64: configure failed" >&2
  finish 0 1
fi
# Every package must be the arm64 one: a host (x86_64) config found by mistake would link host libraries.
if grep -E '^[A-Za-z0-9_]+_DIR:PATH=.*x86_64-linux-gnu' "$build/CMakeCache.txt" >&2; then
  echo "check_arm64: the configure found host (x86_64) packages, above" >&2
  finish 0 1
fi
t_configure=$(now)
# -k: a kernel that does not build for aarch64 fails its own tests (ctest lists NAME_NOT_BUILT), the rest run.
build_ok=1
cmake --build "$build" -j"$jobs" -- -k || build_ok=0
t_build=$(now)

log=$(mktemp)
trap 'rm -f "$log"' EXIT
# The longest test (the FFD paper case, per target) took 3 to 8 minutes under qemu on a 2-core machine
# shared with other builds; 30 minutes is a hang.
# ctest's summary line is reworded as it is shown, so that a run which sums ctest summaries around this one
# (tools/test.sh, when ctest prints this test's output) does not count these tests as its own.
ctest --test-dir "$build" -j"$jobs" --timeout 1800 --output-on-failure 2>&1 | tee "$log" |
  sed -E 's/tests passed, ([0-9]+ tests? failed out of)/tests passed (aarch64), \1/' || true
t_test=$(now)

total=0 failed=0
if read -r failed total < <(sed -nE 's/.*tests passed, ([0-9]+) tests? failed out of ([0-9]+).*/\1 \2/p' "$log"); then :; fi
echo "check_arm64: $(qemu-aarch64 --version | head -n 1); times: install $((t_install - t0)) s," \
  "configure $((t_configure - t_install)) s, build $((t_build - t_configure)) s, tests $((t_test - t_build)) s"
if ((total == 0)); then
  echo "check_arm64: no test ran" >&2
  finish 0 1
fi
if ((build_ok == 0)); then
  echo "check_arm64: the build failed (the compiler's errors are above; its programs' tests are NAME_NOT_BUILT)" >&2
  ((failed > 0)) || failed=1 total=$((total + 1))
fi
finish $((total - failed)) "$failed"
