#!/usr/bin/env bash
# Installs exactly the Debian bookworm packages Embody needs. Idempotent: when everything is
# present it only checks and returns (well under a second). Uses sudo when not root.
#   scripts/install-deps.sh          what `make build/test/demo` need
#   scripts/install-deps.sh --fuzz   that, plus clang and LLVM for `make fuzz` (libFuzzer): a few
#                                    hundred MB that CI's `make test` does not need (its fuzz smoke
#                                    is the gcc replay)
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools glslang-tools
  libglm-dev libeigen3-dev libtinygltf-dev libstb-dev nlohmann-json3-dev
  libopenxr-dev libopenxr-loader1 libopenxr-utils openxr-layer-corevalidation
  catch2 libglfw3-dev xvfb xauth libbenchmark-dev gnuplot-nox liborocos-kdl-dev
  clang-format
)
case "${1:-}" in
  --fuzz) PACKAGES+=(clang libclang-rt-14-dev llvm) ;;  # libFuzzer + sanitizer runtimes, llvm-symbolizer
  "") ;;
  *) echo "install-deps: unknown option '$1' (use --fuzz or nothing)" >&2; exit 2 ;;
esac

if [[ ! -r /etc/os-release ]] || ! grep -qE '^ID=debian' /etc/os-release; then
  echo "install-deps: this script supports Debian bookworm only." >&2
  echo "install-deps: install these packages (or their equivalents) yourself: ${PACKAGES[*]}" >&2
  exit 1
fi
if ! grep -qE '^VERSION_CODENAME=bookworm' /etc/os-release; then
  echo "install-deps: warning: tested on Debian bookworm; this is $(. /etc/os-release; echo "$PRETTY_NAME")" >&2
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "install-deps: not root and no sudo" >&2; exit 1; }
  SUDO="sudo"
fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Node.js + npm run the Khronos glTF validator; use the ones present, else Debian's.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  missing+=(nodejs npm)
fi

if ((${#missing[@]})); then
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The one npm package: the Khronos glTF validator, into an ignored local folder.
here=$(cd "$(dirname "$0")/.." && pwd)
if [[ ! -f "$here/.tools/node_modules/gltf-validator/package.json" ]]; then
  echo "install-deps: installing gltf-validator into .tools/"
  mkdir -p "$here/.tools"
  (cd "$here/.tools" && npm install --silent --no-audit --no-fund --prefix . gltf-validator@2.0.0-dev.3.10 >/dev/null 2>&1) ||
    echo "install-deps: warning: could not install gltf-validator; the glTF validation test will skip" >&2
fi
echo "install-deps: all dependencies present"
