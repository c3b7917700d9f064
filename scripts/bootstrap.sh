#!/usr/bin/env bash
# Set up everything flexnet_fe needs on Debian 12, idempotently (fast when already done):
#   1. Debian packages: dolfinx 0.5.2 (python3-dolfinx-real), gmsh, EGL for offscreen rendering;
#   2. .venv from Debian's /usr/bin/python3 with --system-site-packages (dolfinx imports only there);
#   3. the Python dependencies from pyproject.toml (numpy held at >=1.25,<2; see DESIGN.md §2).
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(python3-dolfinx-real python3-gmsh python3-venv python3-dev libegl1 libegl-mesa0
              libgl1-mesa-dri openmpi-bin python3-h5py)
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "bootstrap: installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

if [ ! -x .venv/bin/python ]; then
  echo "bootstrap: creating .venv (Debian python3 + system site packages)"
  /usr/bin/python3 -m venv --system-site-packages .venv
fi

stamp=.venv/.flexnet-deps
want=$(sha256sum pyproject.toml | cut -d' ' -f1)
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "bootstrap: installing Python dependencies into .venv"
  # numba>=0.60 and scipy>=1.11 in pyproject make pip install them into .venv over Debian's older ones.
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -e ".[test]"
  echo "$want" > "$stamp"
fi
.venv/bin/python -c "import dolfinx, numba, numpy; assert numpy.__version__ < '2'" \
  || { echo "bootstrap: the environment does not import (dolfinx/numba/numpy)"; exit 1; }
