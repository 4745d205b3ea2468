#!/usr/bin/env bash
# Installs the Debian 12 packages doorbench builds with, only those that are missing.
# Run as root (or with sudo); needs network access to Debian's archive only.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  ninja-build            # the build tool scripts/test.sh configures (objects of a library's dependents
                         # compile while it links; docs/PERFORMANCE.md)
  catch2                 # Catch2 v2 (tests)
  libbenchmark-dev       # Google Benchmark (bench/)
  nlohmann-json3-dev     # parameter files
  libcli11-dev           # the doorbench command line
  libceres-dev libeigen3-dev  # Jets for derivatives now, fitting later
  python3 python3-mpmath      # the independent high-precision check of the models
  libhdf5-dev hdf5-tools      # session files; h5dump reads them in tests
  python3-h5py                # tests read sessions without doorbench
  libtomlplusplus-dev         # rig files
  libcomedi-dev               # comedi DAQ cards (sensors/comedi_backend.h)
  libimgui-dev libstb-dev     # the viewer: Dear ImGui (+ its backends' sources), PNG writing
  libglfw3-dev libgl-dev      # the viewer's window and OpenGL
  xvfb libgl1-mesa-dri libglx-mesa0 xauth  # headless screenshots: Xvfb + Mesa software GL
  libassimp-dev               # the station's meshes: glTF 2.0, OBJ, STL exported from CAD (station/)
  libopenal-dev               # the station's sound: OpenAL Soft (the study's OpenAL)
  libsndfile1-dev             # the station's sound samples from WAV files
  libmodbus-dev               # Modbus sensors (sensors/modbus_source.h)
  python3-pymodbus python3-serial python3-serial-asyncio  # the Modbus test server (tests/modbus)
  socat                       # RTU tests over a pseudo-terminal pair
  weasyprint                  # doorbench spec renders spec.html to spec.pdf
  poppler-utils               # pdftoppm: the spec report test renders spec.pdf to pixels to check the page width
  clang-format-14             # scripts/check_format.sh: every C++ source formatted as .clang-format says
  clang libclang-rt-14-dev    # libFuzzer and the sanitizers for the parsers' fuzz targets (fuzz/)
  libboost-math-dev           # Boost.Math: Student-t quantile (calibration), exact binomial test (A/B)
  libboost-dev                # Boost.Random: the Sobol sequence of the fit's global stage
  zlib1g-dev                  # zlib's crc32() for the recording journal's checksums
  r-base-core                 # tests only: R, the independent checks of the statistics
  r-cran-ordinal              # tests only: R's ordinal (clmm/clm), the ratings fit's independent check
  r-cran-bradleyterry2        # tests only: BTm, the preference scale's check (tests/study/preference_oracle.R);
                              # its namespaces all come through Depends: no recommends needed
  r-cran-qvcalc               # tests only: qvcalc, the quasi-variances' check (tests/study/preference_oracle.R)
  r-cran-mass                 # benchmark only: MASS's menarche data, the threshold table of docs/PERFORMANCE.md
)

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
as_root=()
if [[ $(id -u) -ne 0 ]]; then as_root=(sudo); fi
"${as_root[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
