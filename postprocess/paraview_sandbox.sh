#!/bin/sh
# Put Debian bookworm's ParaView 5.11 (pvpython) in a private folder, WITHOUT installing the
# `paraview` package: that package hard-depends on python3-matplotlib 3.6, which lands in
# /usr/lib/python3/dist-packages and breaks the pip matplotlib of the project's
# system-site-packages venv (DESIGN.md §2). Here the two .deb files are only unpacked; the C
# libraries pvpython links to (GLEW, FFmpeg, GDAL, NetCDF, Theora: no Python package among
# them) are installed with apt, and Xvfb gives it a display (Debian's build renders through X).
#
#   sh postprocess/paraview_sandbox.sh [DIR]      (default ~/.cache/flexnet/paraview; needs root)
#   DIR/pvpython report_files/paraview/open_missile.py picture.png
#   FLEXNET_PVPYTHON=DIR/pvpython pytest tests/report/test_paraview.py   (ParaView's own reader)
set -eu
DIR="${1:-$HOME/.cache/flexnet/paraview}"
mkdir -p "$DIR/debs" "$DIR/root"
apt-get install -y -qq --no-install-recommends libglew2.2 libavcodec59 libavformat59 libavutil57 \
    libgdal32 libnetcdf19 libswscale6 libtheora0 xvfb xauth >/dev/null
(cd "$DIR/debs" && apt-get download paraview python3-paraview 2>/dev/null)
for deb in "$DIR"/debs/*.deb; do dpkg -x "$deb" "$DIR/root"; done
cat > "$DIR/pvpython" <<'WRAP'
#!/bin/sh
HERE="$(dirname "$(readlink -f "$0")")"
export LD_LIBRARY_PATH="$HERE/root/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export PYTHONPATH="$HERE/root/usr/lib/python3/dist-packages"
exec xvfb-run -a -s "-screen 0 1920x1080x24" "$HERE/root/usr/bin/pvpython" "$@"
WRAP
chmod +x "$DIR/pvpython"
echo "$DIR/pvpython"
