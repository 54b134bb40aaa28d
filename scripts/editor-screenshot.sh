#!/usr/bin/env bash
# Opens the Javari editor in the standalone app under a virtual X server, plucks a string with
# the editor's own Pluck button, takes a screenshot and checks that it is not blank.
#
#   bash scripts/editor-screenshot.sh [output.png]     (default: docs/editor.png)
#
# Installs what it needs with apt-get when run as root (Xvfb, Mesa's software OpenGL, ALSA/JACK
# headers for the standalone build, ImageMagick, xdotool). The standalone runs with nice-plug's
# dummy audio backend (`--backend dummy`), which calls process() in real time without a
# sound card. Exit status is non-zero if the window does not appear or the image is blank.
set -euo pipefail

cd "$(dirname "$0")/.."
output="${1:-docs/editor.png}"
display_number="${JAVARI_DISPLAY:-:97}"
width=1180
height=780

packages=(xvfb xdotool imagemagick x11-utils libgl1-mesa-dri libegl1 libasound2-dev
    libjack-jackd2-dev pkg-config python3)
missing=()
for package in "${packages[@]}"; do
    dpkg -s "$package" >/dev/null 2>&1 || missing+=("$package")
done
if ((${#missing[@]})); then
    if [[ $(id -u) -ne 0 ]]; then
        echo "error: missing packages ${missing[*]} (run as root or install them)" >&2
        exit 1
    fi
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
fi

cargo build --release -p javari --features standalone --bin javari-standalone

work="$(mktemp -d)"
cleanup() {
    [[ -n "${app_pid:-}" ]] && kill "$app_pid" 2>/dev/null || true
    [[ -n "${xvfb_pid:-}" ]] && kill "$xvfb_pid" 2>/dev/null || true
    rm -rf "$work"
}
trap cleanup EXIT

Xvfb "$display_number" -screen 0 "${width}x${height}x24" -nolisten tcp >"$work/xvfb.log" 2>&1 &
xvfb_pid=$!
export DISPLAY="$display_number"
for _ in $(seq 50); do
    xdpyinfo >/dev/null 2>&1 && break
    sleep 0.1
done

# Mesa's software rasteriser stands in for a GPU.
LIBGL_ALWAYS_SOFTWARE=1 target/release/javari-standalone --backend dummy \
    >"$work/app.log" 2>&1 &
app_pid=$!

window=""
for _ in $(seq 100); do
    window="$(xdotool search --name '^Javari' 2>/dev/null | head -n1 || true)"
    [[ -n "$window" ]] && break
    if ! kill -0 "$app_pid" 2>/dev/null; then
        echo "error: the standalone exited before its window appeared:" >&2
        cat "$work/app.log" >&2
        exit 1
    fi
    sleep 0.2
done
if [[ -z "$window" ]]; then
    echo "error: no Javari window after 20 s" >&2
    cat "$work/app.log" >&2
    exit 1
fi
sleep 1.5

# Press the editor's Pluck button, found by its place in the top bar (see
# plugin/src/editor/controls.rs: title, preset browser, note, Pluck), then let the string ring
# so the force strip, spectrum and spectrogram fill.
geometry="$(xdotool getwindowgeometry --shell "$window")"
eval "$geometry"
pluck_x="${JAVARI_PLUCK_X:-408}"
pluck_y="${JAVARI_PLUCK_Y:-12}"
xdotool mousemove --window "$window" "$pluck_x" "$pluck_y" click 1
sleep 0.12
xdotool mousemove --window "$window" 700 400
sleep "${JAVARI_RING_SECONDS:-3}"

mkdir -p "$(dirname "$output")"
import -window root "$work/full.png"
convert "$work/full.png" -crop "${WIDTH}x${HEIGHT}+${X}+${Y}" +repage -strip \
    -colors 128 "PNG8:$output"

# Non-blank check: the screenshot must have real structure, not one flat colour.
python3 - "$output" <<'EOF'
import subprocess, sys
path = sys.argv[1]
pixels = subprocess.run(["convert", path, "-colorspace", "Gray", "-depth", "8", "gray:-"],
                        check=True, capture_output=True).stdout
n = len(pixels)
mean = sum(pixels) / n
variance = sum((p - mean) ** 2 for p in pixels) / n
distinct = len(set(pixels))
print(f"{path}: {n} pixels, mean grey {mean:.1f}, variance {variance:.1f}, {distinct} grey levels")
if variance < 100 or distinct < 16:
    sys.exit("error: the screenshot looks blank")
EOF
echo "wrote $output"
