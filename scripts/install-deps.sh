#!/usr/bin/env bash
# Installs the Debian 12 packages Repose builds and tests against. Safe to run again.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config
  libvtk9-dev python3-vtk9 vtk9 libvtk9-qt-dev
  libinsighttoolkit5-dev libgdcm-dev  # ITK's image IO; GDCM: DICOM series in and out
  libdcmtk-dev  # DICOM Segmentation objects (dcmseg)
  libeigen3-dev libjsoncpp-dev
  zlib1g-dev  # gzip CRC and length checked: damaged inputs on read, written .nii.gz outputs read back
  libtet1.5-dev
  libopenvdb-dev libboost-iostreams-dev libtbb-dev
  qtbase5-dev
  libsuitesparse-dev libopenblas0-pthread
  libgtest-dev googletest
  python3-numpy python3-scipy
  python3-distributed python3-yaml  # repose batch: Dask's local and remote clusters, YAML manifests
  python3-psutil  # the batch test finds and kills a Dask worker (also a dependency of python3-distributed)
  xvfb xauth
  clang  # libFuzzer with AddressSanitizer and UndefinedBehaviorSanitizer: the readers' fuzz targets (scripts/fuzz.sh)
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all packages present"
  exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
