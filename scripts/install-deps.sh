#!/usr/bin/env bash
# Installs the Debian 12 packages viewpose needs to build, test and fuzz. Idempotent: packages that
# are already installed are skipped, and apt-get runs only when something is missing.
# Usage: scripts/install-deps.sh [build|fuzz|pcl|opencv|results]...   (default: build)
set -euo pipefail

build_pkgs=(build-essential cmake pkg-config
            libeigen3-dev libnanoflann-dev libassimp-dev libpng-dev liblzf-dev nlohmann-json3-dev
            libcli11-dev libspdlog-dev libfmt-dev libgtest-dev libgmock-dev libbenchmark-dev
            libmeshoptimizer-dev
            python3-dev pybind11-dev python3-numpy python3-pytest  # the Python module and its tests
            libfreenect-dev libopenni2-dev)  # camera back-ends of viewpose live (libfreenect ships fakenect)
fuzz_pkgs=(clang libclang-rt-dev libomp-dev)  # libFuzzer, sanitizer runtimes and OpenMP for clang
pcl_pkgs=(libpcl-dev)               # only for the optional side-by-side benchmark
opencv_pkgs=(libopencv-contrib-dev libopencv-dev)  # the optional point pair benchmark: surface_matching, and
                                                    # OpenCVConfig.cmake (only libopencv-dev ships it)
results_pkgs=(python3 python3-matplotlib python3-numpy)  # make results and fit-confidence: the report, its plots, the fit

wanted=()
for group in "${@:-build}"; do
  case "$group" in
    build) wanted+=("${build_pkgs[@]}") ;;
    fuzz)  wanted+=("${build_pkgs[@]}" "${fuzz_pkgs[@]}") ;;
    pcl)   wanted+=("${pcl_pkgs[@]}") ;;
    opencv) wanted+=("${opencv_pkgs[@]}") ;;
    results) wanted+=("${results_pkgs[@]}") ;;
    *) echo "install-deps: unknown group '$group' (build, fuzz, pcl, opencv or results)" >&2; exit 2 ;;
  esac
done

# Each package once, even when two groups name it.
mapfile -t wanted < <(printf "%s\n" "${wanted[@]}" | sort -u)
missing=()
for p in "${wanted[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
